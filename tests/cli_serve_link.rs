//! `raykit experiment serve --connect`: the link client against a server
//! started in this test process (loopback), its report checked against what
//! the server counted and against the frame size it asked for.

use std::process::Command;
use std::sync::Arc;

#[test]
fn connect_measures_a_running_server_and_counts_its_frames() {
    let rt = tokio::runtime::Runtime::new().unwrap();
    let loader: raykit_serve::SceneLoader = Arc::new(|spec: &str| {
        let name = spec.strip_prefix("builtin:").unwrap_or(spec);
        Ok(raykit_scene::builtin(name)?)
    });
    let config = raykit_serve::ServeConfig {
        addr: "127.0.0.1:0".parse().unwrap(),
        full: (160, 90),
        ..raykit_serve::ServeConfig::default()
    };
    let server = rt
        .block_on(raykit_serve::start(config, loader, "builtin:cornell"))
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    for format in ["raw", "jpeg"] {
        let out = dir.path().join(format);
        let before = server.state().totals.lock().unwrap().frames;
        let status = Command::new(env!("CARGO_BIN_EXE_raykit"))
            .args(["experiment", "serve", "--connect"])
            .arg(format!("ws://{}/ws", server.addr()))
            .args(["--width", "64", "--height", "48", "--format", format])
            .args(["--seconds", "1.5", "--warmup", "0.3", "--out"])
            .arg(&out)
            .status()
            .unwrap();
        assert!(status.success(), "{format}: {status}");
        let served = server.state().totals.lock().unwrap().frames - before;
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("link.json")).unwrap()).unwrap();
        let link = &report["link"];
        let frames = link["frames"].as_u64().unwrap();
        assert!(frames >= 3 && frames <= served, "{frames} of {served}");
        assert_eq!(link["format"], format);
        assert_eq!(
            (link["width"].as_u64(), link["height"].as_u64()),
            (Some(64), Some(48))
        );
        let payload = link["payload_bytes_per_frame"].as_f64().unwrap();
        if format == "raw" {
            assert_eq!(payload, (64 * 48 * 3) as f64);
        } else {
            assert!(payload > 0.0 && payload < (64 * 48 * 3) as f64);
        }
        assert!(report["provenance"].as_str().unwrap().contains("cores"));
        assert!(std::fs::read_to_string(out.join("link.md"))
            .unwrap()
            .contains("fps"));
    }
    // Nothing listening: the run fails with an error, not a panic.
    let out = Command::new(env!("CARGO_BIN_EXE_raykit"))
        .args(["experiment", "serve", "--connect", "ws://127.0.0.1:9/ws"])
        .args(["--seconds", "1", "--warmup", "0.2", "--out"])
        .arg(dir.path().join("none"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
    rt.block_on(server.shutdown()).unwrap();
}
