//! Occupancy on a real open CAD assembly: the shared 2CylinderEngine has
//! 13,292 boundary edges (open rims and seams), so its winding number is
//! counted through a cap and decided coarsely first. Checked against the
//! `f64` sum of all 121,496 triangles' solid angles at points uniform in
//! its box and points next to its vertices.

mod common;

use common::shared;
use raykit_core::query::winding::{winding_number_brute, COARSE_MARGIN};
use raykit_core::query::SurfaceBvh;
use raykit_core::rng::Pcg32;
use raykit_core::Vec3;
use raykit_io::load_mesh;
use rayon::prelude::*;

#[test]
fn engine_occupancy_and_counted_winding_numbers_match_f64() {
    let mesh = load_mesh(&shared("meshes/2CylinderEngine.glb")).unwrap();
    let b = mesh.bounds();
    let (lo, hi) = (b.min, b.max);
    let (pad, diag) = ((hi - lo) * 0.1, (hi - lo).length());
    let mut rng = Pcg32::new(21);
    let mut pts: Vec<Vec3> = (0..160).map(|_| rng.in_box(lo - pad, hi + pad)).collect();
    for _ in 0..80 {
        let v = mesh.positions[rng.below(mesh.positions.len() as u32) as usize];
        pts.push(v + rng.unit_vector() * diag * 2e-3 * rng.next_f32());
    }
    let want: Vec<f64> = pts
        .par_iter()
        .map(|p| winding_number_brute(&mesh, p.as_dvec3()))
        .collect();
    let bvh = SurfaceBvh::build(&mesh);
    let mut batch = vec![false; pts.len()];
    bvh.inside_batch(&pts, &mut batch);
    let (mut counted, mut decided, mut inside) = (0, 0, 0);
    for ((p, &w), &in_batch) in pts.iter().zip(&want).zip(&batch) {
        if let Some(c) = bvh.winding_number_counted(*p) {
            counted += 1;
            assert!((c as f64 - w).abs() < 2e-3, "counted {c} vs f64 {w} at {p}");
        }
        let single = bvh.is_inside(*p);
        assert_eq!(single, in_batch, "batch and single differ at {p}");
        // Within the margin the answer rests on the finer sum; beyond it,
        // it must be the f64 one.
        if (w - 0.5).abs() > COARSE_MARGIN as f64 {
            decided += 1;
            inside += single as usize;
            assert_eq!(
                single,
                w >= 0.5,
                "inside {single}, f64 winding number {w} at {p}"
            );
        }
    }
    assert!(counted * 10 >= pts.len() * 9, "only {counted} counted");
    // Both answers occur, and nearly every point is clear of ½.
    assert!(
        inside > 0 && inside < decided,
        "{inside} inside of {decided}"
    );
    assert!(decided * 10 >= pts.len() * 9, "only {decided} clear of 1/2");
}
