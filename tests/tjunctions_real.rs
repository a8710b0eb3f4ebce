//! T-junction elimination (Kim 2013) on the real meshes of the test data
//! folder, as loaded by raykit-io: the naive and fast forms give the same
//! answer and the same mesh on every mesh the naive form accepts, the result
//! passes the independent brute-force checker, and the plane-cut real meshes
//! are repaired the same way.

#[path = "../crates/core/tests/tjunction_support/mod.rs"]
mod tjunction_support;

use raykit_core::tjunction::{
    eliminate, find_fast, find_naive, Method, TJunctionError, TJunctionOptions,
};
use raykit_core::TriangleMesh;
use std::path::PathBuf;
use tjunction_support::*;

fn shared_mesh(file: &str) -> TriangleMesh {
    let dir = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data"));
    let path = dir.join("meshes").join(file);
    assert!(
        path.is_file(),
        "shared mesh not found at {} (set RAYKIT_SHARED_DATA): these tests need the real meshes",
        path.display()
    );
    raykit_io::load_mesh(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Naive and fast agree (finders and elimination), the output is clean by
/// the checker, no triangle is flat, and area changes only by the dropped
/// degenerate triangles (which have at most tolerance-thin area).
fn check(name: &str, m: &TriangleMesh) {
    let o = TJunctionOptions::default();
    let naive = find_naive(m, &o).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(naive, find_fast(m, &o).unwrap(), "{name}");
    let (a, ra) = eliminate(m, Method::Naive, &o).unwrap();
    let (b, rb) = eliminate(m, Method::Fast, &o).unwrap();
    assert_eq!(a, b, "{name}");
    assert_eq!(
        (ra.t_junctions, ra.degenerate_dropped, ra.rounds),
        (rb.t_junctions, rb.degenerate_dropped, rb.rounds),
        "{name}"
    );
    assert_eq!(
        (ra.remaining_t_junctions, ra.remaining_degenerate),
        (0, 0),
        "{name}: {ra:?}"
    );
    let left = brute_t_junctions(&a);
    assert!(left.is_empty(), "{name}: {} T-junctions left", left.len());
    for t in 0..a.num_triangles() {
        assert!(tri_area(&a, t) > 0.0, "{name}: triangle {t} is flat");
    }
    let (before, after) = (m.area(), a.area());
    assert!(
        (before - after).abs() <= 1e-5 * before,
        "{name}: area {before} → {after}"
    );
    eprintln!(
        "{name}: {} triangles, {} T-junctions, {} degenerate dropped → {} triangles",
        ra.triangles_in, ra.t_junctions, ra.degenerate_dropped, ra.triangles_out
    );
}

#[test]
fn shared_meshes_the_naive_form_accepts_agree_and_come_out_clean() {
    for file in [
        "teapot_992.obj",
        "bunny_3674.obj",
        "dragon_vrip_res4.ply.gz",
        "bearing.stl",
    ] {
        check(file, &shared_mesh(file));
    }
}

#[test]
fn plane_cut_shared_meshes_are_repaired_identically_by_both_forms() {
    for (file, depth) in [("teapot_992.obj", 6), ("bunny_3674.obj", 7)] {
        let base = shared_mesh(file);
        let m = cut(&base, &random_planes(&base, depth, 5));
        let found = find_naive(&m, &TJunctionOptions::default()).unwrap();
        assert!(found.len() > 20, "{file}: only {} T-junctions", found.len());
        check(&format!("{file} cut"), &m);
    }
}

#[test]
fn the_naive_form_refuses_the_large_meshes_and_the_fast_one_cleans_them() {
    let o = TJunctionOptions::default();
    for file in ["2CylinderEngine.glb", "dragon_vrip_res2.ply.gz"] {
        let m = shared_mesh(file);
        match find_naive(&m, &o) {
            Err(e @ TJunctionError::TooLarge { .. }) => {
                assert!(e.to_string().contains("fast"), "{e}")
            }
            other => panic!(
                "{file}: expected TooLarge, got {:?}",
                other.map(|v| v.len())
            ),
        }
        // Too large for the brute-force checker as well: the output is
        // checked by a fresh fast pass, which must agree with the report.
        let (out, report) = eliminate(&m, Method::Fast, &o).unwrap();
        let left = find_fast(&out, &o).unwrap();
        assert_eq!(left.len(), report.remaining_t_junctions, "{file}");
        for t in 0..out.num_triangles() {
            assert!(tri_area(&out, t) > 0.0, "{file}: triangle {t} is flat");
        }
        eprintln!("{file}: {report:?}");
        if file.starts_with("dragon") {
            assert_eq!(
                report.remaining_t_junctions + report.remaining_degenerate,
                0
            );
        } else {
            // The engine is a CAD model with distinct vertices about 1.2 ×
            // the rounding allowance apart: a few flat triangles and
            // T-junctions trade places each round (see the module docs of
            // raykit_core::tjunction); all but a handful are fixed.
            assert!(report.t_junctions > 1000, "{report:?}");
            let left = report.remaining_t_junctions + report.remaining_degenerate;
            assert!(left * 1000 < report.triangles_in, "{report:?}");
        }
    }
}
