//! Instanced scenes from real files: the 2CylinderEngine glTF loaded with
//! its instancing kept (one geometry per mesh, one instance per node)
//! traced ray for ray against the same file loaded flattened (the loader's
//! own node walk and transforms) under the single-mesh `Bvh8`; and random
//! instances of the dragon, the bearing and the bunny against their
//! flattening, with an `f64` brute force deciding disagreements.

mod common;
#[path = "../../core/tests/instancing_support/mod.rs"]
mod instancing_support;

use common::shared;
use instancing_support::{
    agree_with_flattened, close_on_plane, crossings, near_edge, rays, Placed,
};
use raykit_core::accel::{Accel, BuildOptions, Bvh8};
use raykit_core::instancing::{SceneBuilder, MASK_ALL};
use raykit_core::tri::Moller;
use raykit_io::{load_gltf_instances, load_mesh};

#[test]
fn engine_instanced_traces_as_engine_flattened() {
    let path = shared("meshes/2CylinderEngine.glb");
    let inst = load_gltf_instances(&path).unwrap();
    let flat = load_mesh(&path).unwrap();
    // The same nodes in the same order: instance i is the flattened part i.
    assert_eq!(inst.instances.len(), flat.parts.len());
    for (i, p) in inst.instances.iter().zip(&flat.parts) {
        assert_eq!(Some(i.node), p.node);
    }
    assert_eq!(inst.instanced_triangles(), flat.num_triangles());
    assert!(
        inst.stored_triangles() < flat.num_triangles(),
        "no instancing kept"
    );
    eprintln!(
        "2CylinderEngine: {} geometries, {} instances, {} triangles stored, {} flattened",
        inst.geometries.len(),
        inst.instances.len(),
        inst.stored_triangles(),
        flat.num_triangles()
    );
    let mut part_first = vec![usize::MAX; flat.parts.len()];
    for t in (0..flat.num_triangles()).rev() {
        part_first[flat.part_of(t) as usize] = t;
    }
    let mut builder = SceneBuilder::new();
    let (_, warnings) = inst.add_to(&mut builder).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let scene = builder.build(&BuildOptions::default());
    let bvh = Bvh8::<Moller>::build(&flat, &BuildOptions::default());
    let placed = Placed {
        meshes: inst.geometries.clone(),
        instances: inst
            .instances
            .iter()
            .map(|i| (i.geometry, i.to_world, MASK_ALL))
            .collect(),
    };
    let world = placed.world_f64(MASK_ALL);
    let bounds = flat.bounds();
    let scale = bounds.extent().max_element() as f64;
    let rays = rays(&bounds, 6000, 21);
    let (mut same, mut excused, mut hits) = (0, 0, 0);
    for (k, ray) in rays.iter().enumerate() {
        let a = scene.intersect(ray, MASK_ALL);
        let b = bvh.intersect(ray);
        assert_eq!(scene.occluded(ray, MASK_ALL), bvh.occluded(ray), "ray {k}");
        let flat_ids = b.map(|b| {
            let part = flat.part_of(b.prim as usize);
            (part, b.prim - part_first[part as usize] as u32)
        });
        match (a, b) {
            (None, None) => same += 1,
            (Some(a), Some(b)) if Some((a.instance, a.prim)) == flat_ids => {
                hits += 1;
                same += 1;
                let n = flat.face_normal(b.prim as usize).as_dvec3();
                assert!(
                    close_on_plane(a.t as f64, b.t as f64, n, ray.dir().as_dvec3(), scale),
                    "ray {k}: {a:?} vs {b:?}"
                );
                assert!(a.normal.as_dvec3().dot(n.normalize()) > 0.999, "ray {k}");
                assert_eq!(a.geometry, inst.instances[a.instance as usize].geometry);
            }
            (a, b) => {
                let reference = crossings(&world, ray);
                let tie = matches!((a, b), (Some(a), Some(b))
                    if instancing_support::close(a.t as f64, b.t as f64, 1e-5));
                assert!(
                    tie || near_edge(&reference, ray.dir().as_dvec3(), scale),
                    "ray {k}: {a:?} vs {b:?} (reference {:?})",
                    reference.first()
                );
                excused += 1;
            }
        }
    }
    eprintln!("{same} rays agree ({hits} hits), {excused} ties or grazes");
    assert!(hits > 1000, "too few hits: {hits}");
    assert!(excused * 100 <= rays.len());
}

#[test]
fn random_instances_of_real_meshes_trace_as_their_flattening() {
    let meshes = vec![
        load_mesh(&shared("meshes/dragon_vrip_res4.ply.gz")).unwrap(),
        load_mesh(&shared("meshes/bearing.stl")).unwrap(),
        load_mesh(&shared("meshes/bunny_3674.obj")).unwrap(),
    ];
    let placed = Placed::random(meshes, 9, 2.0, 31);
    let scene = placed.scene();
    let rays = rays(&placed.bounds(), 3000, 32);
    let (same, excused) = agree_with_flattened(&placed, &scene, MASK_ALL, &rays);
    eprintln!("{same} rays agree, {excused} ties or grazes");
}
