//! Every structure × triangle test agrees with brute force on the real meshes
//! of the test data folder and on the built-in scenes, for the three
//! standard ray sets (sampled: brute force is O(rays × triangles)).

use raykit_core::accel::kdtree::build_tree;
use raykit_core::accel::{build_accel, kd_accel_from_tree, AccelKind, BuildOptions};
use raykit_core::raysets;
use raykit_core::tri::TestKind;
use raykit_core::{Hit, Ray, TriangleMesh};
use std::path::PathBuf;

fn shared_data() -> PathBuf {
    let dir = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data"));
    assert!(
        dir.join("meshes").is_dir(),
        "test data folder not found at {} (set RAYKIT_SHARED_DATA): these tests need the real meshes",
        dir.display()
    );
    dir
}

fn agree(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(x), Some(y)) => (x.t - y.t).abs() <= 1e-5 * x.t.abs().max(y.t.abs()),
        _ => false,
    }
}

/// Sample `k` rays of each standard set (size² rays) and compare.
fn check(name: &str, mesh: &TriangleMesh, k: usize) {
    let opts = BuildOptions::default();
    let helper = build_accel(AccelKind::Bvh2, TestKind::Moller, mesh, &opts);
    let sets = raysets::standard_sets(mesh, helper.as_ref(), 128, 3);
    // One SAH kd-tree build serves the four kd traversals.
    let (kd_root, kd_cell) = build_tree(mesh, &opts.kd);
    for test in TestKind::ALL {
        let brute = build_accel(AccelKind::Brute, test, mesh, &opts);
        let accels: Vec<_> = AccelKind::ALL[1..]
            .iter()
            .map(|&a| {
                let accel = kd_accel_from_tree(a, test, mesh, &kd_root, &kd_cell, &opts, 0.0)
                    .unwrap_or_else(|| build_accel(a, test, mesh, &opts));
                (a, accel)
            })
            .collect();
        for (si, set) in sets.iter().enumerate() {
            let step = (set.len() / k).max(1);
            let rays: Vec<Ray> = set.iter().step_by(step).copied().collect();
            let mut want = vec![None; rays.len()];
            brute.intersect_batch(&rays, &mut want);
            let mut want_occ = vec![false; rays.len()];
            brute.occluded_batch(&rays, &mut want_occ);
            assert!(
                want.iter().any(|h| h.is_some()),
                "{name}: set {si} has no hits at all"
            );
            for (kind, accel) in &accels {
                let mut got = vec![None; rays.len()];
                accel.intersect_batch(&rays, &mut got);
                let mut got_occ = vec![false; rays.len()];
                accel.occluded_batch(&rays, &mut got_occ);
                let bad = want.iter().zip(&got).filter(|(a, b)| !agree(a, b)).count();
                let bad_occ = want_occ
                    .iter()
                    .zip(&got_occ)
                    .filter(|(a, b)| a != b)
                    .count();
                assert_eq!(
                    (bad, bad_occ),
                    (0, 0),
                    "{name}: {} × {} on set {si}: {bad} hit and {bad_occ} occlusion disagreements of {}",
                    kind.name(),
                    test.name(),
                    rays.len()
                );
            }
        }
    }
}

#[test]
fn shared_meshes_agree_with_brute_force() {
    let dir = shared_data().join("meshes");
    for (file, k) in [
        ("teapot_992.obj", 3000),
        ("bunny_3674.obj", 2000),
        ("dragon_vrip_res4.ply.gz", 1000),
        ("bearing.stl", 600),
        ("2CylinderEngine.glb", 300),
        ("dragon_vrip_res2.ply.gz", 200),
    ] {
        let mesh = raykit_io::load_mesh(&dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
        check(file, &mesh, k);
    }
}

#[test]
fn builtin_scenes_agree_with_brute_force() {
    for spec in [
        "cornell",
        "shirley6",
        "terrain:triangles=20000",
        "scatter:triangles=20000",
    ] {
        let scene = raykit_scene::builtin(spec).unwrap_or_else(|e| panic!("{e}"));
        check(spec, &scene.mesh, 800);
    }
}
