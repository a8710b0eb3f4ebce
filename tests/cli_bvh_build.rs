//! `--bvh-build fast` (the linear BVH after Karras 2012) and
//! `--bvh-build high` (wide nodes filled as Embree's builders do) on a command that
//! builds: `raykit trace` over bvh2, bvh4 and bvh8 gives the hits of brute
//! force computed in this process, and an unknown builder is refused
//! cleanly.

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use std::path::PathBuf;

#[path = "support/cli.rs"]
mod cli;
use cli::{data, raykit, s, text};

fn teapot() -> PathBuf {
    data("meshes/teapot_992.obj")
}

#[test]
fn trace_with_the_fast_and_high_builds_matches_brute_force() {
    let dir = tempfile::tempdir().unwrap();
    let mesh_path = teapot();
    let rays = dir.path().join("r.bin");
    let o = raykit(&[
        "rays",
        "--mesh",
        s(&mesh_path),
        "--kind",
        "incoherent",
        "--size",
        "64",
        "--out",
        s(&rays),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let mesh = raykit_io::load_mesh(&mesh_path).unwrap();
    let ray_list = raykit_io::read_rays(&rays).unwrap();
    let brute = build_accel(
        AccelKind::Brute,
        TestKind::Moller,
        &mesh,
        &BuildOptions::default(),
    );
    for (build, accel) in [
        ("fast", "bvh4"),
        ("fast", "bvh2"),
        ("high", "bvh8"),
        ("high", "bvh4"),
    ] {
        let hits = dir.path().join(format!("h-{build}-{accel}.bin"));
        let o = raykit(&[
            "trace",
            "--mesh",
            s(&mesh_path),
            "--rays",
            s(&rays),
            "--out",
            s(&hits),
            "--accel",
            accel,
            "--test",
            "moller",
            "--bvh-build",
            build,
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let got = raykit_io::read_hits(&hits).unwrap();
        assert_eq!(got.len(), ray_list.len());
        let mut n_hits = 0;
        for (r, g) in ray_list.iter().zip(&got) {
            let want = brute.intersect(r);
            assert_eq!(want.is_some(), g.is_some(), "{build} {accel}: {r:?}");
            if let (Some(w), Some(g)) = (want, g) {
                assert!(
                    (w.t - g.t).abs() <= 1e-5 * w.t,
                    "{build} {accel}: {w:?} vs {g:?}"
                );
                n_hits += 1;
            }
        }
        assert!(
            n_hits > 100,
            "the incoherent set should hit the teapot often"
        );
    }
}

#[test]
fn unknown_builder_is_refused() {
    let o = raykit(&["bench", "--mesh", "builtin:cornell", "--bvh-build", "nope"]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(err.contains("nope") && err.contains("sah"), "{err}");
}
