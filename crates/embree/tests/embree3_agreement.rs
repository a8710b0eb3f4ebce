//! Embree 3 (linked) against raykit-core on the shared data's real meshes:
//! its single-ray calls (through the `Accel` trait) and its stream calls
//! (`rtcIntersect1M` / `rtcOccluded1M`) give the nearest hits and the
//! occlusion of brute force on the bunny and of our BVH8 on the dragon,
//! up to rays grazing a triangle edge (see `support`).
#![cfg(feature = "embree3")]

mod support;

use raykit_core::accel::AccelKind;
use raykit_core::{Accel, TriangleMesh};
use raykit_embree::{Embree3Device, Embree3Scene, Quality};
use support::{check_hits, check_occlusion, check_regions, data_mesh, Reference};

/// Every Embree 3 query path against `reference` on `mesh`.
fn agrees(mesh: &TriangleMesh, reference: AccelKind, quality: Quality, n: usize) {
    let device = Embree3Device::new(1).unwrap();
    let em = Embree3Scene::build(&device, mesh, quality).unwrap();
    check_regions(&em, mesh);
    let Reference {
        rays,
        hits: want,
        occluded: want_occ,
    } = support::reference(reference, mesh, n, 7);

    let engine = format!("Embree 3 {quality:?} vs {reference:?}");
    let mut single = vec![None; rays.len()];
    em.intersect_batch(&rays, &mut single);
    check_hits(
        &format!("{engine}, rtcIntersect1"),
        mesh,
        &rays,
        &want,
        &single,
    );
    let mut stream = vec![None; rays.len()];
    em.intersect_stream(&rays, &mut stream, 64);
    check_hits(
        &format!("{engine}, rtcIntersect1M"),
        mesh,
        &rays,
        &want,
        &stream,
    );

    let mut occ = vec![false; rays.len()];
    em.occluded_batch(&rays, &mut occ);
    let (w, g) = ((&want_occ[..], &want[..]), (&occ[..], &single[..]));
    check_occlusion(&format!("{engine}, rtcOccluded1"), mesh, &rays, w, g);
    let mut occ_stream = vec![false; rays.len()];
    em.occluded_stream(&rays, &mut occ_stream, 64);
    let g = (&occ_stream[..], &stream[..]);
    check_occlusion(&format!("{engine}, rtcOccluded1M"), mesh, &rays, w, g);
}

#[test]
fn embree3_agrees_with_brute_force_on_the_bunny() {
    let mesh = data_mesh("bunny_3674.obj");
    for quality in [Quality::High, Quality::Medium] {
        agrees(&mesh, AccelKind::Brute, quality, 3000);
    }
}

#[test]
fn embree3_agrees_with_our_bvh8_on_the_dragon() {
    let mesh = data_mesh("dragon_vrip_res4.ply.gz");
    agrees(&mesh, AccelKind::Bvh8, Quality::High, 20_000);
}

/// A triangle naming a vertex past the end is refused with its number,
/// before Embree reads anything.
#[test]
fn an_index_past_the_vertices_is_an_error_naming_the_triangle() {
    let device = Embree3Device::new(1).unwrap();
    support::check_index_error(|positions, indices| {
        Embree3Scene::build_triangles(&device, positions, indices, Quality::Medium)
    });
}
