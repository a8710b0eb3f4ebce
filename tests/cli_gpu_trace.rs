//! `raykit trace --backend gpu` and `raykit bench --backend gpu` from the
//! command line: the GPU's hit file equals the CPU's for the same structure
//! and test (ties on shared edges aside), and bad requests fail with a
//! message, never a panic. Needs a wgpu adapter (lavapipe in CI) and fails
//! loudly without one.

#[path = "support/cli.rs"]
mod cli;

use cli::{raykit, s, text};

fn read_hits(path: &std::path::Path) -> Vec<(f32, u32)> {
    std::fs::read(path)
        .unwrap()
        .chunks_exact(8)
        .map(|c| {
            (
                f32::from_le_bytes(c[0..4].try_into().unwrap()),
                u32::from_le_bytes(c[4..8].try_into().unwrap()),
            )
        })
        .collect()
}

/// 8² primary rays of the Cornell box in a temporary folder.
fn cornell_rays() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let rays = dir.path().join("r.bin");
    let out = raykit(&[
        "rays",
        "--mesh",
        "builtin:cornell",
        "--size",
        "8",
        "--out",
        s(&rays),
    ]);
    assert_ok(&out, "raykit rays");
    (dir, rays)
}

fn assert_ok(out: &std::process::Output, what: &str) {
    assert!(
        out.status.success(),
        "{what} failed: {}\n{}",
        text(&out.stderr),
        text(&out.stdout)
    );
}

#[test]
fn gpu_trace_writes_the_cpu_hit_file() {
    let dir = tempfile::tempdir().unwrap();
    let rays = dir.path().join("r.bin");
    let mesh = "builtin:shirley6";
    for kind in ["primary", "incoherent"] {
        assert_ok(
            &raykit(&[
                "rays",
                "--mesh",
                mesh,
                "--kind",
                kind,
                "--size",
                "64",
                "--out",
                s(&rays),
            ]),
            "raykit rays",
        );
        for (accel, test) in [("kd-stack", "plucker"), ("bvh-threaded", "moller")] {
            let gpu = dir.path().join("gpu.bin");
            let cpu = dir.path().join("cpu.bin");
            let out = raykit(&[
                "trace",
                "--backend",
                "gpu",
                "--mesh",
                mesh,
                "--rays",
                s(&rays),
                "--out",
                s(&gpu),
                "--accel",
                accel,
                "--test",
                test,
                "--verify",
                "500",
            ]);
            assert_ok(&out, "raykit trace --backend gpu");
            let log = text(&out.stderr);
            assert!(
                log.contains("\"backend\":\"gpu\"") && log.contains("\"ok\":true"),
                "{log}"
            );
            let out = raykit(&[
                "trace",
                "--mesh",
                mesh,
                "--rays",
                s(&rays),
                "--out",
                s(&cpu),
                "--accel",
                accel,
                "--test",
                test,
            ]);
            assert_ok(&out, "raykit trace");
            let (g, c) = (read_hits(&gpu), read_hits(&cpu));
            assert_eq!(g.len(), 64 * 64);
            assert!(
                c.iter().any(|h| h.1 != u32::MAX),
                "the {kind} rays hit something"
            );
            for (i, (g, c)) in g.iter().zip(&c).enumerate() {
                let same_t = (g.0 == c.0) || (g.0 - c.0).abs() <= 1e-4 * c.0.abs();
                assert!(
                    same_t && (g.1 == u32::MAX) == (c.1 == u32::MAX),
                    "{accel} × {test} {kind} ray {i}: gpu {g:?} cpu {c:?}"
                );
            }
        }
    }
}

#[test]
fn gpu_bench_checks_every_answer() {
    let out = raykit(&[
        "bench",
        "--backend",
        "gpu",
        "--mesh",
        "builtin:cornell",
        "--size",
        "48",
        "--reps",
        "1",
        "--json",
    ]);
    assert_ok(&out, "raykit bench --backend gpu");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(
        rows.len(),
        8,
        "kd-stack, kd-ropes, bvh-threaded and cwbvh × plucker and moller"
    );
    for r in rows {
        for c in r["cells"].as_array().unwrap() {
            assert!(c["verify"]["checked"].as_u64().unwrap() > 0);
            assert_eq!(c["verify"]["hit_miss"], 0, "{r}");
            assert_eq!(c["verify"]["distance"], 0, "{r}");
            assert!(c["mrays"].as_f64().unwrap() > 0.0);
        }
    }
}

#[test]
fn gpu_requests_without_a_kernel_fail_with_a_message() {
    let (dir, rays) = cornell_rays();
    let hits = dir.path().join("h.bin");
    for (flag, value, expect) in [
        ("--accel", "bvh4", "has no GPU kernel"),
        ("--test", "projection", "has no GPU kernel"),
    ] {
        let out = raykit(&[
            "trace",
            "--backend",
            "gpu",
            "--mesh",
            "builtin:cornell",
            "--rays",
            s(&rays),
            "--out",
            s(&hits),
            flag,
            value,
        ]);
        let err = text(&out.stderr);
        assert!(
            !out.status.success() && err.contains(expect) && !err.contains("panicked"),
            "{err}"
        );
    }
}

#[test]
fn no_adapter_is_a_clear_error() {
    // Only Vulkan, Metal and DX12 are built in; asking for OpenGL alone
    // leaves wgpu without an adapter on every platform.
    let (dir, rays) = cornell_rays();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_raykit"))
        .args([
            "trace",
            "--backend",
            "gpu",
            "--mesh",
            "builtin:cornell",
            "--rays",
            s(&rays),
            "--out",
        ])
        .arg(dir.path().join("h.bin"))
        .env("WGPU_BACKEND", "gl")
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("no GPU adapter found") && err.contains("mesa-vulkan-drivers"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    assert!(!dir.path().join("h.bin").exists(), "no output on failure");
}
