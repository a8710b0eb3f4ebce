//! `raykit tjunctions` as a user runs it: the output file is read back and
//! checked with the independent brute-force checker; bad arguments give a
//! clear error and a non-zero exit.

#[path = "../crates/core/tests/tjunction_support/mod.rs"]
mod tjunction_support;

use tjunction_support::*;

#[path = "support/cli.rs"]
mod cli;
use cli::{raykit, s, text};

/// Two unit quads; the right one split at y = 0.5 with its own vertices:
/// (1, 0.5) lies inside the left quad's edge x = 1.
const TWO_QUADS: &str = "\
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
v 1 0 0\nv 2 0 0\nv 2 0.5 0\nv 1 0.5 0\n\
v 1 0.5 0\nv 2 0.5 0\nv 2 1 0\nv 1 1 0\n\
f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\nf 9 10 11\nf 9 11 12\n";

#[test]
fn two_quads_are_fixed_and_the_json_report_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("quads.obj");
    std::fs::write(&input, TWO_QUADS).unwrap();
    let output = dir.path().join("fixed.ply");
    for method in ["fast", "naive"] {
        let o = raykit(&[
            "tjunctions",
            s(&input),
            s(&output),
            "--method",
            method,
            "--json",
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(report["t_junctions"], 1, "{report}");
        assert_eq!(report["triangles_in"], 6);
        assert_eq!(report["triangles_out"], 7);
        assert_eq!(report["method"], method);
        for key in ["find_s", "retriangulate_s", "load_s", "save_s", "threads"] {
            assert!(report[key].is_number(), "{key} missing: {report}");
        }
        let input_mesh = raykit_io::load_mesh(&input).unwrap();
        assert_eq!(brute_t_junctions(&input_mesh).len(), 1);
        let fixed = raykit_io::load_mesh(&output).unwrap();
        assert_eq!(fixed.num_triangles(), 7);
        assert!(brute_t_junctions(&fixed).is_empty());
        assert!((fixed.area() - 2.0).abs() < 1e-6);
    }
}

#[test]
fn a_cut_sphere_comes_back_watertight_with_the_summary_printed() {
    let dir = tempfile::tempdir().unwrap();
    let base = sphere(3);
    let cut_mesh = cut(&base, &random_planes(&base, 4, 11));
    let input = dir.path().join("cut.stl");
    raykit_io::save_mesh(&input, &cut_mesh).unwrap();
    let before = raykit_io::load_mesh(&input).unwrap();
    let found = brute_t_junctions(&before).len();
    assert!(found > 0);
    let output = dir.path().join("fixed.obj");
    let o = raykit(&["tjunctions", s(&input), s(&output), "--threads", "2"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains(&format!("T-junctions found: {found}")),
        "{out}"
    );
    assert!(out.contains("triangles:") && out.contains("find"), "{out}");
    let fixed = raykit_io::load_mesh(&output).unwrap();
    assert!(brute_t_junctions(&fixed).is_empty());
    assert!(edge_uses(&fixed).values().all(|&n| n == 2));
    assert!((fixed.area() - before.area()).abs() < 1e-5 * before.area());
}

#[test]
fn bad_arguments_fail_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("quads.obj");
    std::fs::write(&input, TWO_QUADS).unwrap();
    let same = dir.path().join(".").join("quads.obj");
    for (args, want) in [
        (vec![s(&input), s(&same)], "also an input"),
        (vec![s(&input), "out.xyz"], "unknown mesh file extension"),
        (vec!["missing.obj", "out.obj"], "missing.obj"),
        (vec![s(&input), "out.obj", "--tolerance=-1"], "tolerance"),
    ] {
        let o = raykit(&[&["tjunctions"], &args[..]].concat());
        assert!(!o.status.success(), "{args:?}");
        let err = text(&o.stderr);
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    assert_eq!(std::fs::read_to_string(&input).unwrap(), TWO_QUADS);
    let o = raykit(&["tjunctions", "--help"]);
    assert!(text(&o.stdout).contains("--method"));
    assert!(text(&o.stdout).contains("T-junction"));
}

/// Cut points are computed in f64 and rounded to f32, and split planes are
/// f32: where two planes and a mesh edge nearly meet, the cut mesh has
/// distinct points a few f32 steps apart (measured: up to 6.6e-7 on this
/// unit sphere) with slivers between them, which the default tolerance
/// (1e-6 of the edge length) does not join.
const TOLERANCE: &str = "1e-5";

#[test]
fn kd_cut_then_eliminate_gives_a_closed_surface() {
    let dir = tempfile::tempdir().unwrap();
    let base = sphere(3);
    let input = dir.path().join("sphere.obj");
    raykit_io::save_mesh(&input, &base).unwrap();
    let (cut, output) = (dir.path().join("cut.obj"), dir.path().join("fixed.obj"));
    let o = raykit(&[
        "tjunctions",
        s(&input),
        s(&output),
        "--kd-cut",
        "6",
        "--kd-leaf",
        "3",
        "--cut-out",
        s(&cut),
        "--tolerance",
        TOLERANCE,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("kd-tree game:6"),
        "{}",
        text(&o.stderr)
    );
    let cut = raykit_io::load_mesh(&cut).unwrap();
    let fixed = raykit_io::load_mesh(&output).unwrap();
    assert!(
        cut.num_triangles() > base.num_triangles(),
        "the kd-tree cut triangles"
    );
    assert!(
        !brute_t_junctions(&cut).is_empty(),
        "cutting left T-junctions"
    );
    assert!(
        brute_t_junctions(&fixed).is_empty(),
        "T-junctions left after elimination"
    );
    assert!((fixed.area() - base.area()).abs() < 1e-5 * base.area());
    assert!(
        edge_uses(&fixed).values().all(|&n| n == 2),
        "surface not closed"
    );
    // The cut mesh and the output are two files: one path for both is
    // refused before any work, as is --cut-out without a cut.
    let before = std::fs::read(&output).unwrap();
    for (extra, want) in [
        (
            vec!["--kd-cut", "6", "--cut-out", s(&output)],
            "name the same file",
        ),
        (vec!["--cut-out", s(&output)], "--cut-out needs --kd-cut"),
    ] {
        let o = raykit(&[&["tjunctions", s(&input), s(&output)], &extra[..]].concat());
        assert!(!o.status.success(), "{extra:?}");
        assert!(
            text(&o.stderr).contains(want),
            "{extra:?}: {}",
            text(&o.stderr)
        );
    }
    assert_eq!(
        std::fs::read(&output).unwrap(),
        before,
        "the output is untouched"
    );
}
