//! `raykit serve` refuses unusable settings before it listens: an empty
//! token (which would otherwise serve without one while printing a link
//! with `?token=`), and a scene folder that cannot be read (named, with the
//! system's reason).

use std::process::Command;

#[path = "support/cli.rs"]
mod cli;
use cli::{s, text};

/// `raykit serve ARGS` on a free port for at most a moment, with
/// `RAYKIT_TOKEN` set to `token` or unset.
fn serve(args: &[&str], token: Option<&str>) -> std::process::Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_raykit"));
    c.args(["serve", "--addr", "127.0.0.1:0", "--seconds", "0"])
        .args(args);
    match token {
        Some(t) => c.env("RAYKIT_TOKEN", t),
        None => c.env_remove("RAYKIT_TOKEN"),
    };
    c.output().expect("the raykit binary runs")
}

#[test]
fn an_empty_token_is_refused_from_the_flag_and_the_environment() {
    for (args, env) in [(&["--token", ""][..], None), (&[][..], Some(""))] {
        let o = serve(args, env);
        let err = text(&o.stderr);
        assert!(!o.status.success(), "{args:?} {env:?}: {err}");
        assert!(err.contains("--token") && err.contains("empty"), "{err}");
        assert!(!err.contains("http://"), "it started: {err}");
    }
    // A token that is there starts the server and says so.
    let o = serve(&["--token", "s3cr3t"], None);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("?token="), "{}", text(&o.stderr));
}

#[test]
fn an_unreadable_scene_folder_is_refused_naming_it_and_why() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nonexistent");
    let o = serve(&["--scene-dir", s(&missing)], None);
    let err = text(&o.stderr);
    assert!(!o.status.success(), "{err}");
    let why = std::fs::read_dir(&missing).unwrap_err().to_string();
    assert!(
        err.contains("--scene-dir") && err.contains(s(&missing)) && err.contains(&why),
        "{err}"
    );
    // A folder that exists is taken.
    let o = serve(&["--scene-dir", s(dir.path())], None);
    assert!(o.status.success(), "{}", text(&o.stderr));
}

#[test]
fn a_host_name_address_is_resolved_and_a_bad_one_says_what_to_give() {
    let serve = |addr: &str| {
        Command::new(env!("CARGO_BIN_EXE_raykit"))
            .args(["serve", "--seconds", "0", "--addr", addr])
            .env_remove("RAYKIT_TOKEN")
            .output()
            .expect("the raykit binary runs")
    };
    // `localhost` resolves (to 127.0.0.1 where it has an IPv4 address).
    let o = serve("localhost:0");
    let err = text(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("http://"), "{err}");
    // Without a port, or a host that does not resolve: the flag is named,
    // with an example of what it takes.
    for addr in ["localhost", "no-such-host.invalid:8080"] {
        let o = serve(addr);
        let err = text(&o.stderr);
        assert!(!o.status.success(), "{addr}: {err}");
        assert!(
            err.contains("--addr") && err.contains("127.0.0.1:8080"),
            "{addr}: {err}"
        );
    }
}

#[test]
fn unusable_settings_are_refused_naming_the_flag() {
    for (args, flag) in [
        (&["--settle-ms", "90000"][..], "--settle-ms"),
        (&["--max-clients", "0"][..], "--max-clients"),
        (&["--max-message-bytes", "100"][..], "--max-message-bytes"),
        (
            &["--max-inputs-per-second", "0"][..],
            "--max-inputs-per-second",
        ),
        (&["--spp", "17"][..], "--spp"),
        (&["--max-spp", "5000"][..], "--max-spp"),
        (&["--quality", "0"][..], "--quality"),
        (&["--width", "8"][..], "--width"),
        (&["--max-width", "20000"][..], "--max-width"),
    ] {
        let o = serve(args, None);
        let err = text(&o.stderr);
        assert!(!o.status.success(), "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?}: {err}");
        assert!(!err.contains("http://"), "it started: {err}");
    }
}
