//! Meshes written once and placed by nodes (`write_gltf_placed`), read back
//! by both glTF loaders: the instanced load finds the same meshes, materials
//! and `f64` transforms; the flattened load finds every node's triangles
//! where the transform, applied here in `f64`, puts them. Bad nodes and
//! meshes are refused.

use raykit_core::glam::{DAffine3, DQuat, DVec3};
use raykit_core::{Material, Part, TriangleMesh, Vec3};
use raykit_io::{
    load_gltf_instances, load_mesh, stage_gltf_placed, write_gltf_placed, OutputSet, PlacedMesh,
};

/// A square of two triangles with two materials, named "tile".
fn tile() -> TriangleMesh {
    let mut m = TriangleMesh::new(
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    m.materials = vec![
        Material {
            name: "red".into(),
            diffuse: [0.8, 0.1, 0.1],
            ..Material::default()
        },
        Material {
            name: "blue".into(),
            diffuse: [0.1, 0.1, 0.8],
            ..Material::default()
        },
    ];
    m.tri_material = vec![0, 1];
    m.parts = vec![Part {
        name: "tile".into(),
        node: None,
    }];
    m
}

/// A tetrahedron with one material.
fn tetra() -> TriangleMesh {
    let mut m = TriangleMesh::new(
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::new(0.0, 0.0, 0.5),
        ],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    );
    m.materials = vec![Material {
        name: "green".into(),
        diffuse: [0.1, 0.7, 0.2],
        ..Material::default()
    }];
    m.tri_material = vec![0; 4];
    m
}

fn nodes() -> Vec<PlacedMesh> {
    let turn = DAffine3::from_rotation_translation(
        DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7),
        DVec3::new(2.5, -1.25, 0.125),
    );
    // Far from the origin, as a survey's coordinates place a model.
    let far = DAffine3::from_scale_rotation_translation(
        DVec3::splat(1.5),
        DQuat::from_rotation_z(0.3),
        DVec3::new(429_252.123, 5_150_885.456, 312.789),
    );
    vec![
        PlacedMesh {
            mesh: 0,
            to_world: DAffine3::IDENTITY,
            name: "tile at home".into(),
        },
        PlacedMesh {
            mesh: 1,
            to_world: turn,
            name: "tetra turned".into(),
        },
        PlacedMesh {
            mesh: 0,
            to_world: turn,
            name: String::new(),
        },
        PlacedMesh {
            mesh: 1,
            to_world: far,
            name: "tetra far".into(),
        },
    ]
}

#[test]
fn placed_meshes_read_back_by_both_loaders() {
    let dir = tempfile::tempdir().unwrap();
    let meshes = [tile(), tetra()];
    let placed = nodes();
    for name in ["scene.glb", "scene.gltf"] {
        let path = dir.path().join(name);
        let mut set = OutputSet::new();
        stage_gltf_placed(&mut set, &path, &meshes, &placed).unwrap();
        set.commit().unwrap();

        let inst = load_gltf_instances(&path).unwrap();
        assert_eq!(inst.geometries.len(), 2, "{name}");
        assert_eq!(inst.instances.len(), placed.len(), "{name}");
        for (k, m) in meshes.iter().enumerate() {
            let g = &inst.geometries[k];
            assert_eq!(g.positions, m.positions, "{name}: mesh {k}");
            assert_eq!(g.indices, m.indices, "{name}: mesh {k}");
            let mats: Vec<&str> = (0..g.num_triangles())
                .map(|t| g.materials[g.material_of(t) as usize].name.as_str())
                .collect();
            let want: Vec<&str> = (0..m.num_triangles())
                .map(|t| m.materials[m.material_of(t) as usize].name.as_str())
                .collect();
            assert_eq!(mats, want, "{name}: mesh {k}'s materials");
        }
        for (i, p) in inst.instances.iter().zip(&placed) {
            assert_eq!(i.geometry as usize, p.mesh, "{name}");
            // Written with every digit of the f64 values.
            assert!(
                i.to_world_f64.abs_diff_eq(p.to_world, 1e-9),
                "{name}: {:?} against {:?}",
                i.to_world_f64,
                p.to_world
            );
        }
        let names: Vec<&str> = inst.instances.iter().map(|i| i.name.as_str()).collect();
        // A node without a name takes its mesh's.
        assert_eq!(
            names,
            ["tile at home", "tetra turned", "tile", "tetra far"],
            "{name}"
        );

        // The flattened load, node by node, against the transforms applied
        // here in f64 and rounded once.
        let flat = load_mesh(&path).unwrap();
        assert_eq!(flat.parts.len(), placed.len(), "{name}");
        let mut t = 0;
        for (part, p) in placed.iter().enumerate() {
            let m = &meshes[p.mesh];
            for local in 0..m.num_triangles() {
                assert_eq!(flat.part_of(t) as usize, part, "{name}");
                let got = flat.triangle(t);
                for (c, want) in got.iter().zip(m.triangle(local)) {
                    let w = p.to_world.transform_point3(want.as_dvec3());
                    let err = (c.as_dvec3() - w).abs().max_element();
                    // One f32 rounding of the world position (0.03 at 5e6).
                    let ulp = w.abs().max_element() * f32::EPSILON as f64;
                    assert!(err <= ulp.max(1e-6), "{name}: node {part}: {c} against {w}");
                }
                t += 1;
            }
        }
        assert_eq!(t, flat.num_triangles(), "{name}");
    }
}

#[test]
fn bad_nodes_and_meshes_are_refused_by_name() {
    let meshes = [tile(), tetra()];
    let mut out = Vec::new();
    let missing = [PlacedMesh {
        mesh: 2,
        to_world: DAffine3::IDENTITY,
        name: String::new(),
    }];
    let e = write_gltf_placed(&mut out, &meshes, &missing, None, &[], true).unwrap_err();
    assert!(
        e.to_string()
            .contains("node 0 places mesh 2, but there are 2 meshes"),
        "{e}"
    );
    let mut nan = nodes();
    nan[3].to_world.translation.x = f64::NAN;
    let e = write_gltf_placed(&mut out, &meshes, &nan, None, &[], true).unwrap_err();
    assert!(
        e.to_string()
            .contains("node 3: the transform is not finite"),
        "{e}"
    );
    let empty = [tile(), TriangleMesh::default()];
    let e = write_gltf_placed(&mut out, &empty, &nodes()[..1], None, &[], false).unwrap_err();
    assert!(
        e.to_string()
            .contains("mesh 1: cannot write an invalid mesh: the mesh has no triangles"),
        "{e}"
    );
    let mut broken = tetra();
    broken.indices[2] = [0, 1, 9];
    let e = write_gltf_placed(&mut out, &[tile(), broken], &nodes(), None, &[], false).unwrap_err();
    assert!(e.to_string().contains("mesh 1"), "{e}");

    let dir = tempfile::tempdir().unwrap();
    let mut set = OutputSet::new();
    let e =
        stage_gltf_placed(&mut set, &dir.path().join("scene.obj"), &meshes, &nodes()).unwrap_err();
    assert!(e.to_string().contains("written as .gltf or .glb"), "{e}");
}
