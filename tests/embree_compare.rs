//! `raykit bench --compare embree` (issue 8, part 1): with the `embree`
//! feature, Embree 3 and our BVH trace the same rays in one process and
//! every answer must agree (up to shared-edge ties); without the feature the
//! command must say how to get it.

#[path = "support/cli.rs"]
mod cli;
use cli::{raykit, text};

#[cfg(feature = "embree")]
#[test]
fn embree_and_ours_agree_on_every_ray_and_the_table_has_every_cell() {
    for mesh in ["builtin:cornell", "builtin:scatter:triangles=20000"] {
        let o = raykit(&[
            "bench",
            "--compare",
            "embree",
            "--mesh",
            mesh,
            "--size",
            "96",
            "--reps",
            "1",
        ]);
        let out = text(&o.stdout);
        assert!(
            o.status.success(),
            "{mesh}: answers disagree or the run failed:\n{out}\n{}",
            text(&o.stderr)
        );
        for cell in [
            "primary",
            "shadow",
            "incoherent",
            "rtcIntersect1M",
            "build vs Embree High",
            "build vs Embree Medium",
        ] {
            assert!(out.contains(cell), "{mesh}: no '{cell}' row:\n{out}");
        }
        assert!(!out.contains("DISAGREE"), "{out}");
        // Every set was compared on all of its rays.
        assert!(
            out.contains(&format!("primary            {} rays", 96 * 96)),
            "{out}"
        );
    }
}

#[cfg(not(feature = "embree"))]
#[test]
fn without_the_embree_feature_the_comparison_says_how_to_enable_it() {
    eprintln!("embree comparison skipped: this test binary was built without `--features embree`");
    let o = raykit(&["bench", "--compare", "embree", "--size", "8"]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(
        err.contains("libembree-dev") && err.contains("--features embree"),
        "{err}"
    );
}
