//! Embree 4 (loaded at run time: `$RAYKIT_EMBREE4`, else the `embreex`
//! wheel of `$RAYKIT_PYTHON` or `python3`; scripts/test installs it)
//! against raykit-core on the shared data's real meshes, through each of
//! its query APIs (single rays, packets of 4, 8 and 16) with both
//! coherence hints: the nearest hits and occlusion of brute force on the
//! bunny and of our BVH8 on the dragon, up to rays grazing a triangle edge
//! (see `support`). Where Embree 4 cannot be found the tests fail, naming
//! every place tried.
#![cfg(feature = "embree4")]

mod support;

use raykit_core::accel::AccelKind;
use raykit_core::{Accel, TriangleMesh};
use raykit_embree::{Embree4, Embree4Device, Embree4Scene, Quality, QueryApi};
use std::sync::Arc;
use support::{check_hits, check_occlusion, check_regions, data_mesh, Reference};

/// The library, or a failure naming what was tried.
fn library() -> Arc<Embree4> {
    Embree4::load().unwrap_or_else(|e| panic!("{e:#}"))
}

/// Every Embree 4 API and hint against `reference` on `mesh`.
fn agrees(mesh: &TriangleMesh, reference: AccelKind, quality: Quality, n: usize) {
    let lib = library();
    let device = Embree4Device::new(&lib, 1).unwrap();
    let em = Embree4Scene::build(&device, mesh, quality).unwrap();
    check_regions(&em, mesh);
    let Reference {
        rays,
        hits: want,
        occluded: want_occ,
    } = support::reference(reference, mesh, n, 11);
    for api in QueryApi::ALL {
        for coherent in [false, true] {
            let engine = format!(
                "Embree {} {quality:?} vs {reference:?}, {api:?}, coherent {coherent}",
                lib.version
            );
            let mut got = vec![None; rays.len()];
            em.intersect_with(api, &rays, &mut got, coherent);
            check_hits(&engine, mesh, &rays, &want, &got);
            let mut occ = vec![false; rays.len()];
            em.occluded_with(api, &rays, &mut occ, coherent);
            let (w, g) = ((&want_occ[..], &want[..]), (&occ[..], &got[..]));
            check_occlusion(&engine, mesh, &rays, w, g);
        }
    }
    // The `Accel` trait's single rays answer as `rtcIntersect1` does.
    let mut single = vec![None; rays.len()];
    em.intersect_with(QueryApi::Single, &rays, &mut single, false);
    for (ray, h) in rays.iter().zip(&single) {
        assert_eq!(em.intersect(ray), *h, "{ray:?}");
    }
}

#[test]
fn embree4_agrees_with_brute_force_on_the_bunny_through_every_api() {
    let mesh = data_mesh("bunny_3674.obj");
    for quality in [Quality::High, Quality::Medium] {
        agrees(&mesh, AccelKind::Brute, quality, 3001);
    }
}

#[test]
fn embree4_agrees_with_our_bvh8_on_the_dragon_through_every_api() {
    let mesh = data_mesh("dragon_vrip_res4.ply.gz");
    agrees(&mesh, AccelKind::Bvh8, Quality::High, 20_000);
}

#[test]
fn the_loaded_library_reports_a_4_x_version() {
    let lib = library();
    assert!(lib.path.is_file(), "{}", lib.path.display());
    let parts: Vec<u32> = lib.version.split('.').map(|p| p.parse().unwrap()).collect();
    assert_eq!((parts.len(), parts[0]), (3, 4), "{}", lib.version);
}

/// A triangle naming a vertex past the end is refused with its number,
/// before Embree reads anything.
#[test]
fn an_index_past_the_vertices_is_an_error_naming_the_triangle() {
    let device = Embree4Device::new(&library(), 1).unwrap();
    support::check_index_error(|positions, indices| {
        Embree4Scene::build_triangles(&device, positions, indices, Quality::High)
    });
}
