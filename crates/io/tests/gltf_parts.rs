//! The glTF/GLB writer keeps a mesh's parts: one node and mesh per part with
//! triangles, named after it; parts without triangles are dropped.

use raykit_core::{Part, TriangleMesh, Vec3};
use raykit_io::{load_mesh, save_mesh};
use std::collections::{BTreeMap, BTreeSet};

type Corners = [[u32; 3]; 3];

/// A triangle's corners as exact f32 bit patterns (-0 folded into +0).
fn corners(m: &TriangleMesh, t: usize) -> Corners {
    m.triangle(t)
        .map(|p| p.to_array().map(|x| (x + 0.0).to_bits()))
}

/// Per part name: the set of its triangles' corners.
fn triangles_by_part(m: &TriangleMesh) -> BTreeMap<String, BTreeSet<Corners>> {
    let mut out: BTreeMap<String, BTreeSet<Corners>> = BTreeMap::new();
    for t in 0..m.num_triangles() {
        let name = m.parts[m.part_of(t) as usize].name.clone();
        out.entry(name).or_default().insert(corners(m, t));
    }
    out
}

/// A strip of `n` triangles starting at `x0`, in the plane z = `z`.
fn strip(x0: f32, z: f32, n: u32) -> TriangleMesh {
    let mut positions = Vec::new();
    for i in 0..=n {
        let x = x0 + i as f32 * 0.37;
        positions.push(Vec3::new(x, 0.1 * i as f32, z));
        positions.push(Vec3::new(x + 0.013, 1.0 + 0.2 * i as f32, z - 0.5));
    }
    let indices = (0..n).map(|i| [i, i + 1, i + 2]).collect();
    TriangleMesh::new(positions, indices)
}

/// Three parts: "wheel" (4 triangles), "empty bracket" (none) and
/// "axle \"A\"" (6 triangles), interleaved in the triangle list and sharing
/// the vertex array.
fn three_parts() -> TriangleMesh {
    let mut m = strip(0.0, 0.0, 4);
    m.append(&strip(-3.5, 2.25, 6));
    // Interleave: move part 1's first triangle before part 0's last.
    m.indices.swap(3, 4);
    m.tri_part.swap(3, 4);
    m.tri_material.swap(3, 4);
    // Part 2 is the second strip; part 1 is empty.
    for p in &mut m.tri_part {
        if *p == 1 {
            *p = 2;
        }
    }
    m.parts = vec![
        Part {
            name: "wheel".into(),
            node: None,
        },
        Part {
            name: "empty bracket".into(),
            node: None,
        },
        Part {
            name: "axle \"A\"".into(),
            node: Some(7),
        },
    ];
    m.compute_vertex_normals();
    m.validate().unwrap();
    m
}

#[test]
fn parts_survive_glb_and_gltf_and_empty_parts_are_dropped() {
    let src = three_parts();
    let want = triangles_by_part(&src);
    assert_eq!(want.len(), 2);
    assert_eq!(want["wheel"].len(), 4);
    assert_eq!(want["axle \"A\""].len(), 6);
    let dir = tempfile::tempdir().unwrap();
    for name in ["parts.glb", "parts.gltf"] {
        let path = dir.path().join(name);
        save_mesh(&path, &src).unwrap();
        let m = load_mesh(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(m.num_triangles(), src.num_triangles(), "{name}");
        let names: Vec<&str> = m.parts.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["wheel", "axle \"A\""], "{name}: parts");
        assert_eq!(triangles_by_part(&m), want, "{name}: triangles per part");
        // Each node holds only its own part's vertices.
        assert_eq!(m.positions.len(), (4 + 2) + (6 + 2), "{name}: vertices");
    }
}

#[test]
fn a_single_part_mesh_keeps_its_vertex_arrays() {
    let mut src = strip(1.0, -1.0, 5);
    src.positions.push(Vec3::new(9.0, 9.0, 9.0)); // unreferenced, still written
    src.parts = vec![Part {
        name: "only".into(),
        node: None,
    }];
    src.tri_part = vec![0; src.num_triangles()];
    let dir = tempfile::tempdir().unwrap();
    for name in ["one.glb", "one.gltf"] {
        let path = dir.path().join(name);
        save_mesh(&path, &src).unwrap();
        let m = load_mesh(&path).unwrap();
        assert_eq!(m.positions, src.positions, "{name}");
        assert_eq!(m.indices, src.indices, "{name}");
        assert_eq!(m.parts.len(), 1, "{name}");
        assert_eq!(m.parts[0].name, "only", "{name}");
    }
}
