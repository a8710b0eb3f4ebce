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
