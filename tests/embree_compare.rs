//! `raykit bench --compare embree`: with the `embree`
//! feature, Embree 3 and our BVH trace the same rays in one process and
//! every answer must agree (up to shared-edge ties); without the feature the
//! command must say how to get it.

#[path = "support/cli.rs"]
mod cli;
use cli::{raykit, text};

#[cfg(feature = "embree")]
#[test]
fn embree_and_ours_agree_on_every_ray_and_the_table_has_every_cell() {
    // Two meshes and two structures in one run, as the comparison is meant to be run
    // asks: every mesh gets its tables, then one summary.
    let meshes = ["builtin:cornell", "builtin:scatter:triangles=20000"];
    let o = raykit(&[
        "bench",
        "--compare",
        "embree",
        "--mesh",
        meshes[0],
        "--mesh",
        meshes[1],
        "--accel",
        "bvh8,bvh2",
        "--size",
        "96",
        "--reps",
        "1",
    ]);
    let out = text(&o.stdout);
    assert!(
        o.status.success(),
        "answers disagree or the run failed:\n{out}\n{}",
        text(&o.stderr)
    );
    assert!(!out.contains("DISAGREE"), "{out}");
    let (tables, summary) = out
        .split_once("summary:")
        .expect("a summary after the tables");
    for cell in [
        "primary",
        "shadow",
        "incoherent",
        "primary, Embree stream (rtcIntersect1M)",
        "build vs Embree High",
        "build vs Embree Medium",
    ] {
        for accel in ["bvh8", "bvh2"] {
            let row = format!("{cell} [{accel}] ");
            assert_eq!(
                tables.lines().filter(|l| l.starts_with(&row)).count(),
                2 * meshes.len(),
                "'{cell}' [{accel}]: one row per thread count and mesh:\n{tables}"
            );
        }
    }
    for mesh in meshes {
        assert!(
            tables.contains(&format!("{mesh}: ")),
            "no tables for {mesh}:\n{out}"
        );
        assert!(
            summary.lines().nth(1).unwrap_or("").contains(mesh),
            "{summary}"
        );
        // SAH cost shown beside the build times.
        assert!(tables.contains("SAH cost"), "{tables}");
    }
    // Every set was compared on all of its rays, for each structure.
    assert_eq!(
        tables
            .matches(&format!("primary            {} rays", 96 * 96))
            .count(),
        2 * meshes.len(),
        "{tables}"
    );
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
