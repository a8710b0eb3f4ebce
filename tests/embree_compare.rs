//! The command `raykit bench --compare embree`: with the `embree` feature,
//! Embree 4 (loaded at run time: scripts/test installs the `embreex` wheel
//! and sets RAYKIT_PYTHON), Embree 3 and our BVH trace the same rays in one
//! process, the run succeeds only where every answer agrees (up to
//! shared-edge ties), and its tables and summary have every cell; without
//! the feature the command must say how to get it. Each Embree version's
//! own answers are checked against ours in `crates/embree/tests`.

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
    let err = text(&o.stderr);
    assert!(
        o.status.success(),
        "answers disagree or the run failed:\n{out}\n{err}"
    );
    // Both versions compared: Embree 4 must have been found (the note
    // names every place looked in).
    assert!(
        !err.contains("comparing with Embree 3 only"),
        "Embree 4 is missing: install it with `pip install embreex` or set RAYKIT_EMBREE4 (scripts/test does):\n{err}"
    );
    assert!(
        out.contains("against Embree 4.") && out.contains("and Embree 3"),
        "{out}"
    );
    assert!(!out.contains("DISAGREE"), "{out}");
    let (tables, summary) = out
        .split_once("summary:")
        .expect("a summary after the tables");
    // One thread and all of them, or one row where all is one.
    let both = if std::thread::available_parallelism().map_or(1, |n| n.get()) > 1 {
        2
    } else {
        1
    };
    for (cell, threads) in [
        ("primary", both),
        ("shadow", both),
        ("incoherent", both),
        ("primary, Embree 3 stream (rtcIntersect1M)", both),
        ("build vs Embree High", both),
        ("build vs Embree Medium", both),
        ("primary, one ray", 1),
        ("shadow, one ray", 1),
        ("incoherent, one ray", 1),
    ] {
        for accel in ["bvh8", "bvh2"] {
            let row = format!("{cell} [{accel}] ");
            let rows: Vec<&str> = tables.lines().filter(|l| l.starts_with(&row)).collect();
            assert_eq!(
                rows.len(),
                threads * meshes.len(),
                "'{cell}' [{accel}]: one row per thread count and mesh:\n{tables}"
            );
            // Trace cells name the Embree 4 API that gave its figure; the
            // one-ray cells name the single-ray calls.
            for r in rows
                .iter()
                .filter(|_| !cell.starts_with("build") && !cell.contains("stream"))
            {
                let api = if cell.contains("one ray") { "1 " } else { "" };
                let call = if cell.starts_with("shadow") {
                    "rtcOccluded"
                } else {
                    "rtcIntersect"
                };
                assert!(r.contains(&format!("{call}{api}")), "{r}");
            }
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
    // Every set was compared on all of its rays, for each structure: the
    // batch answers against Embree 3's single rays and stream and each of
    // Embree 4's four APIs, the one-ray answers against each single-ray
    // API.
    assert_eq!(
        tables
            .matches(&format!("primary            {} rays", 96 * 96))
            .count(),
        8 * 2 * meshes.len(),
        "{tables}"
    );
    for engine in [
        "Embree 4 rtcIntersect16]",
        "Embree 4 rtcOccluded8]",
        "one ray vs Embree 4 rtcOccluded1]",
    ] {
        assert!(tables.contains(engine), "{engine}: {tables}");
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
