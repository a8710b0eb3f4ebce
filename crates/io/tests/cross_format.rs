//! Cross-format checks: real meshes written in every format (by the crate's
//! writers and by an independent writer here) and read back must give the
//! same geometry as the source OBJ/PLY, bit for bit.

mod common;

use common::*;
use raykit_core::{TriangleMesh, Vec2, Vec3};
use raykit_io::{load, load_mesh, save_mesh, save_mesh_as, MeshFormat, PlyEncoding, StlEncoding};
use std::collections::HashSet;

const FORMATS: [(&str, MeshFormat); 11] = [
    ("a_ascii.ply", MeshFormat::Ply(PlyEncoding::Ascii)),
    ("a_le.ply", MeshFormat::Ply(PlyEncoding::BinaryLittleEndian)),
    ("a_be.ply", MeshFormat::Ply(PlyEncoding::BinaryBigEndian)),
    ("a_be.ply.gz", MeshFormat::Ply(PlyEncoding::BinaryBigEndian)),
    ("a.off", MeshFormat::Off),
    ("a.glb", MeshFormat::Glb),
    ("a.gltf", MeshFormat::Gltf),
    ("a.obj", MeshFormat::Obj),
    ("a.OBJ.gz", MeshFormat::Obj),
    ("a_ascii.stl", MeshFormat::Stl(StlEncoding::Ascii)),
    ("a_bin.stl", MeshFormat::Stl(StlEncoding::Binary)),
];

fn distinct_positions(m: &TriangleMesh) -> usize {
    m.indices
        .iter()
        .flatten()
        .map(|&i| {
            m.positions[i as usize]
                .to_array()
                .map(|x| (x + 0.0).to_bits())
        })
        .collect::<HashSet<_>>()
        .len()
}

fn round_trip_everywhere(src: &TriangleMesh, what: &str) {
    let dir = tempfile::tempdir().unwrap();
    for (name, format) in FORMATS {
        let path = dir.path().join(name);
        save_mesh_as(&path, src, format).unwrap();
        let loaded = load(&path).unwrap_or_else(|e| panic!("{what} as {name}: {e}"));
        assert_eq!(loaded.format, format, "{name}");
        assert_eq!(loaded.gzip, name.ends_with(".gz"), "{name}");
        let m = loaded.mesh;
        let label = format!("{what} as {name}");
        assert_same_triangles(src, &m, &label);
        match format {
            MeshFormat::Stl(_) => {
                // STL stores corners; the loader welds identical positions.
                assert_eq!(m.positions.len(), distinct_positions(src), "{label}");
            }
            _ => {
                assert_eq!(m.positions, src.positions, "{label}");
                assert_eq!(m.indices, src.indices, "{label}");
                assert_eq!(m.normals, src.normals, "{label}");
                if format != MeshFormat::Off {
                    assert_eq!(m.uvs, src.uvs, "{label}");
                }
            }
        }
        assert_eq!(bounds(&m), bounds(src), "{label}");
    }
}

#[test]
fn bunny_through_every_format() {
    let bunny = load_mesh(&shared("meshes/bunny_3674.obj")).unwrap();
    round_trip_everywhere(&bunny, "bunny");
}

#[test]
fn teapot_and_dragon_through_every_format() {
    let teapot = load_mesh(&shared("meshes/teapot_992.obj")).unwrap();
    round_trip_everywhere(&teapot, "teapot");
    let dragon = load_mesh(&shared("meshes/dragon_vrip_res4.ply.gz")).unwrap();
    round_trip_everywhere(&dragon, "dragon");
}

#[test]
fn normals_and_uvs_survive_indexed_formats() {
    let cube = load_mesh(&local("cube.obj")).unwrap();
    assert!(cube.normals.is_some() && cube.uvs.is_some());
    round_trip_everywhere(&cube, "cube");
}

#[test]
fn written_files_have_the_documented_layout() {
    let bunny = load_mesh(&shared("meshes/bunny_3674.obj")).unwrap();
    let (nv, nt) = (bunny.positions.len(), bunny.num_triangles());
    let dir = tempfile::tempdir().unwrap();
    // Binary STL: 84 + 50 bytes per triangle, corners as LE f32.
    let p = dir.path().join("b.stl");
    save_mesh(&p, &bunny).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(bytes.len(), 84 + 50 * nt);
    assert!(!bytes.starts_with(b"solid"));
    assert_eq!(
        u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize,
        nt
    );
    let x = f32::from_le_bytes(bytes[96..100].try_into().unwrap());
    assert_eq!(x, bunny.triangle(0)[0].x);
    // Binary big-endian PLY: header, 12 bytes per vertex, 13 per triangle.
    for (enc, be) in [
        (PlyEncoding::BinaryBigEndian, true),
        (PlyEncoding::BinaryLittleEndian, false),
    ] {
        let p = dir.path().join("b.ply");
        save_mesh_as(&p, &bunny, MeshFormat::Ply(enc)).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let end = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        assert_eq!(bytes.len(), end + 12 * nv + 13 * nt);
        let raw: [u8; 4] = bytes[end..end + 4].try_into().unwrap();
        let x = if be {
            f32::from_be_bytes(raw)
        } else {
            f32::from_le_bytes(raw)
        };
        assert_eq!(x, bunny.positions[0].x);
    }
}

#[test]
fn binary_stl_whose_header_starts_with_solid() {
    let bunny = load_mesh(&shared("meshes/bunny_3674.obj")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("solid.stl");
    save_mesh_as(&p, &bunny, MeshFormat::Stl(StlEncoding::Binary)).unwrap();
    let mut bytes = std::fs::read(&p).unwrap();
    bytes[..16].copy_from_slice(b"solid bunny     ");
    std::fs::write(&p, &bytes).unwrap();
    let loaded = load(&p).unwrap();
    assert_eq!(loaded.format, MeshFormat::Stl(StlEncoding::Binary));
    assert_same_triangles(&bunny, &loaded.mesh, "solid-header binary STL");
}

/// An independent PLY writer with an unusual layout: double coordinates,
/// extra scalar and list properties before and after, `vertex_index` as an
/// int list with a ushort count, an unknown element between vertices and
/// faces, and quads where two triangles share an edge diagonal.
fn odd_ply(m: &TriangleMesh, be: bool) -> Vec<u8> {
    let fmt = if be {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\ncomment odd layout\nelement vertex {}\nproperty uchar flag\n\
property double x\nproperty list uchar float junk\nproperty double y\nproperty double z\n\
property short extra\nelement material 2\nproperty list int uchar name\nproperty float k\n\
element face {}\nproperty list uint int junk2\nproperty list ushort int vertex_index\n\
property uchar tag\nend_header\n",
        m.positions.len(),
        m.indices.len()
    )
    .into_bytes();
    let put = |out: &mut Vec<u8>, b: &[u8]| {
        if be {
            out.extend(b.iter().rev());
        } else {
            out.extend(b);
        }
    };
    for (i, p) in m.positions.iter().enumerate() {
        put(&mut out, &[7]);
        put(&mut out, &(p.x as f64).to_le_bytes());
        let n = (i % 3) as u8;
        put(&mut out, &[n]);
        for k in 0..n {
            put(&mut out, &(k as f32).to_le_bytes());
        }
        put(&mut out, &(p.y as f64).to_le_bytes());
        put(&mut out, &(p.z as f64).to_le_bytes());
        put(&mut out, &(-3i16).to_le_bytes());
    }
    for name in ["ab", "cde"] {
        put(&mut out, &(name.len() as i32).to_le_bytes());
        out.extend(name.as_bytes());
        put(&mut out, &1.5f32.to_le_bytes());
    }
    for (i, t) in m.indices.iter().enumerate() {
        put(&mut out, &((i % 2) as u32).to_le_bytes());
        if i % 2 == 1 {
            put(&mut out, &9i32.to_le_bytes());
        }
        put(&mut out, &3u16.to_le_bytes());
        for &v in t {
            put(&mut out, &(v as i32).to_le_bytes());
        }
        put(&mut out, &[1]);
    }
    out
}

#[test]
fn independently_written_odd_binary_ply_both_endians() {
    let bunny = load_mesh(&shared("meshes/bunny_3674.obj")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for be in [false, true] {
        let p = dir.path().join(format!("odd_{be}.ply"));
        std::fs::write(&p, odd_ply(&bunny, be)).unwrap();
        let loaded = load(&p).unwrap();
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        assert_eq!(loaded.mesh.positions, bunny.positions);
        assert_eq!(loaded.mesh.indices, bunny.indices);
    }
}

#[test]
fn independently_written_quads_are_fan_triangulated() {
    // A 2x1 grid of quads in OBJ, PLY and OFF, written here by hand.
    let obj = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nf 1 2 5 4\nf 2 3 6 5\n";
    let ply = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n\
property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n2 0 0\n0 1 0\n1 1 0\n2 1 0\n4 0 1 4 3\n4 1 2 5 4\n";
    let off = "OFF\n6 2 0\n0 0 0\n1 0 0\n2 0 0\n0 1 0\n1 1 0\n2 1 0\n4 0 1 4 3\n4 1 2 5 4\n";
    let dir = tempfile::tempdir().unwrap();
    let expect = vec![[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]];
    for (name, text) in [("q.obj", obj), ("q.ply", ply), ("q.off", off)] {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        let m = load_mesh(&p).unwrap();
        assert_eq!(m.indices, expect, "{name}");
        assert!((m.area() - 2.0).abs() < 1e-12, "{name}");
    }
}

#[test]
fn obj_parts_and_materials_round_trip_with_mtl() {
    let cube = load_mesh(&local("cube.obj")).unwrap();
    // Compressed or not, the OBJ brings its library, under the name
    // without `.gz` and `.obj`.
    for name in ["cube_out.obj", "cube_out.obj.gz"] {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join(name);
        save_mesh(&p, &cube).unwrap();
        assert!(dir.path().join("cube_out.mtl").is_file(), "{name}");
        let back = load_mesh(&p).unwrap();
        assert_materials_survive(&back, &cube);
    }
}

fn assert_materials_survive(back: &TriangleMesh, cube: &TriangleMesh) {
    assert_eq!(back.parts, cube.parts);
    assert_eq!(back.tri_part, cube.tri_part);
    assert_eq!(back.tri_material, cube.tri_material);
    for (a, b) in back.materials.iter().zip(&cube.materials) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.diffuse, b.diffuse);
        assert_eq!(a.specular, b.specular);
        assert_eq!(a.shininess, b.shininess);
        assert_eq!(a.ior, b.ior);
        assert!((a.transmission - b.transmission).abs() < 1e-6);
    }
    assert_eq!(back.uvs.as_ref().map(|u| u[0]), Some(Vec2::new(0.0, 0.0)));
    assert_eq!(back.positions[0], Vec3::ZERO);
}
