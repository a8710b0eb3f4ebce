//! Every loader on the real files of the test data folder, each checked
//! against an independent reference: a few-line parser written here with
//! `str::split_whitespace` for the text formats, and the `gltf` crate's own
//! accessor reader plus a node walk for the GLB. Counts are the ones the data
//! README gives.

mod common;

use common::*;
use flate2::read::GzDecoder;
use raykit_core::glam::{DMat4, DVec3, Mat4};
use raykit_core::{TriangleMesh, Vec3};
use raykit_io::{load, load_mesh, MeshFormat, PlyEncoding, StlEncoding};
use std::collections::HashSet;
use std::io::Read;
use std::time::Instant;

fn nums<'a>(it: impl Iterator<Item = &'a str>) -> Vec<f32> {
    it.map(|t| t.parse::<f32>().expect("reference parse"))
        .collect()
}

/// Reference OBJ reader: `v` lines and `f` lines (first index of each corner,
/// fan-triangulated).
fn reference_obj(text: &str) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    let mut f = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let n = nums(it.take(3));
                v.push(Vec3::new(n[0], n[1], n[2]));
            }
            Some("f") => {
                let idx: Vec<u32> = it
                    .map(|c| {
                        let i: i64 = c.split('/').next().unwrap().parse().unwrap();
                        if i < 0 {
                            (v.len() as i64 + i) as u32
                        } else {
                            (i - 1) as u32
                        }
                    })
                    .collect();
                for k in 1..idx.len() - 1 {
                    f.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    (v, f)
}

fn check_obj(rel: &str, nv: usize, nt: usize) {
    let path = shared(rel);
    let loaded = load(&path).unwrap();
    assert_eq!(loaded.format, MeshFormat::Obj);
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let m = loaded.mesh;
    let (rv, rf) = reference_obj(&std::fs::read_to_string(&path).unwrap());
    assert_eq!(rv.len(), nv, "{rel}: README vertex count");
    assert_eq!(rf.len(), nt, "{rel}: README triangle count");
    assert_eq!(m.positions, rv, "{rel}: positions");
    assert_eq!(m.indices, rf, "{rel}: indices");
    let (lo, hi) = rf.iter().flatten().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(l, h), &i| (l.min(rv[i as usize]), h.max(rv[i as usize])),
    );
    assert_eq!(bounds(&m), (lo, hi), "{rel}: bounds");
    assert!(m.normals.is_none() && m.uvs.is_none());
    assert!(m.materials.is_empty() && m.parts.is_empty());
}

#[test]
fn teapot_obj() {
    check_obj("meshes/teapot_992.obj", 792, 992);
}

#[test]
fn bunny_obj() {
    check_obj("meshes/bunny_3674.obj", 1839, 3674);
}

/// Reference ASCII PLY reader for files with `x y z` vertices and
/// `n i1 … in` faces.
fn reference_ply(text: &str) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut lines = text.lines();
    let (mut nv, mut nf) = (0, 0);
    for l in lines.by_ref() {
        let w: Vec<&str> = l.split_whitespace().collect();
        match w.as_slice() {
            ["element", "vertex", n] => nv = n.parse().unwrap(),
            ["element", "face", n] => nf = n.parse().unwrap(),
            ["end_header"] => break,
            _ => {}
        }
    }
    let v: Vec<Vec3> = (0..nv)
        .map(|_| {
            let n = nums(lines.next().unwrap().split_whitespace().take(3));
            Vec3::new(n[0], n[1], n[2])
        })
        .collect();
    let mut f = Vec::new();
    for _ in 0..nf {
        let idx: Vec<u32> = lines
            .next()
            .unwrap()
            .split_whitespace()
            .skip(1)
            .map(|t| t.parse().unwrap())
            .collect();
        for k in 1..idx.len() - 1 {
            f.push([idx[0], idx[k], idx[k + 1]]);
        }
    }
    (v, f)
}

fn check_ply_gz(rel: &str, nt: usize) -> TriangleMesh {
    let path = shared(rel);
    let t0 = Instant::now();
    let loaded = load(&path).unwrap();
    eprintln!("{rel}: loaded in {:?}", t0.elapsed());
    assert_eq!(loaded.format, MeshFormat::Ply(PlyEncoding::Ascii));
    assert!(loaded.gzip);
    let m = loaded.mesh;
    let mut text = String::new();
    GzDecoder::new(std::fs::File::open(&path).unwrap())
        .read_to_string(&mut text)
        .unwrap();
    let (rv, rf) = reference_ply(&text);
    assert_eq!(rf.len(), nt, "{rel}: README triangle count");
    assert_eq!(m.num_triangles(), nt);
    assert_eq!(m.positions, rv, "{rel}: positions");
    assert_eq!(m.indices, rf, "{rel}: indices");
    let b = m.bounds();
    // The Stanford dragon is about 0.2 units long.
    assert!(b.min.cmpgt(Vec3::splat(-0.2)).all() && b.max.cmplt(Vec3::splat(0.2)).all());
    m
}

#[test]
fn dragon_res4_ply_gz() {
    check_ply_gz("meshes/dragon_vrip_res4.ply.gz", 11_102);
}

#[test]
fn dragon_res2_ply_gz() {
    let m = check_ply_gz("meshes/dragon_vrip_res2.ply.gz", 202_520);
    // Cross-check the two resolutions: same object, so nearly the same bounds
    // and area.
    let small = load_mesh(&shared("meshes/dragon_vrip_res4.ply.gz")).unwrap();
    let (a, b) = (m.bounds(), small.bounds());
    assert!((a.min - b.min).abs().max_element() < 0.01);
    assert!((a.max - b.max).abs().max_element() < 0.01);
    let (aa, ab) = (m.area(), small.area());
    assert!((aa - ab).abs() / aa < 0.1, "{aa} vs {ab}");
}

#[test]
fn bearing_ascii_stl() {
    let path = shared("meshes/bearing.stl");
    let loaded = load(&path).unwrap();
    assert_eq!(loaded.format, MeshFormat::Stl(StlEncoding::Ascii));
    let m = loaded.mesh;
    // Reference: every `vertex` line, three per facet.
    let text = std::fs::read_to_string(&path).unwrap();
    let corners: Vec<Vec3> = text
        .lines()
        .filter_map(|l| {
            let mut it = l.split_whitespace();
            (it.next() == Some("vertex")).then(|| {
                let n = nums(it);
                Vec3::new(n[0], n[1], n[2])
            })
        })
        .collect();
    let facets = text
        .lines()
        .filter(|l| l.trim_start().starts_with("facet"))
        .count();
    assert_eq!(facets, 24_696, "README triangle count");
    assert_eq!(corners.len(), 3 * facets);
    let reference: Vec<[Vec3; 3]> = corners.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    assert_eq!(corner_list(&m), reference);
    // Welded: one vertex per distinct position.
    let distinct: HashSet<[u32; 3]> = corners
        .iter()
        .map(|p| {
            [
                (p.x + 0.0).to_bits(),
                (p.y + 0.0).to_bits(),
                (p.z + 0.0).to_bits(),
            ]
        })
        .collect();
    assert_eq!(m.positions.len(), distinct.len());
    assert!(m.positions.len() < corners.len() / 4);
    assert!((m.area() - area_of(&reference)).abs() < 1e-6 * m.area());
}

/// Reference GLB walk: the `gltf` crate's reader, node transforms applied one
/// node at a time from the mesh's node up to the root, in f64.
fn reference_glb(path: &std::path::Path) -> (Vec<[DVec3; 3]>, usize, usize, usize) {
    let g = gltf::Gltf::open(path).unwrap();
    let blob = g.blob.as_deref().unwrap();
    let doc = &g.document;
    let mut tris = Vec::new();
    let mut instances = 0;
    fn visit(
        node: gltf::Node<'_>,
        chain: &mut Vec<DMat4>,
        blob: &[u8],
        tris: &mut Vec<[DVec3; 3]>,
        instances: &mut usize,
    ) {
        chain.push(Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4());
        if let Some(mesh) = node.mesh() {
            *instances += 1;
            let det: f64 = chain.iter().map(|m| m.determinant()).product();
            for prim in mesh.primitives() {
                assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
                let r = prim.reader(|_| Some(blob));
                let pos: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
                let idx: Vec<u32> = r.read_indices().unwrap().into_u32().collect();
                let world = |i: u32| {
                    let mut p = Vec3::from_array(pos[i as usize]).as_dvec3();
                    for m in chain.iter().rev() {
                        p = m.transform_point3(p);
                    }
                    p
                };
                for t in idx.chunks(3) {
                    let (a, b, c) = (world(t[0]), world(t[1]), world(t[2]));
                    tris.push(if det < 0.0 { [a, c, b] } else { [a, b, c] });
                }
            }
        }
        for c in node.children() {
            visit(c, chain, blob, tris, instances);
        }
        chain.pop();
    }
    let scene = doc.default_scene().unwrap();
    for n in scene.nodes() {
        visit(n, &mut Vec::new(), blob, &mut tris, &mut instances);
    }
    (tris, doc.meshes().len(), doc.nodes().len(), instances)
}

#[test]
fn engine_glb_matches_independent_node_walk() {
    let path = shared("meshes/2CylinderEngine.glb");
    let loaded = load(&path).unwrap();
    assert_eq!(loaded.format, MeshFormat::Glb);
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let m = loaded.mesh;
    let (reference, meshes, nodes, instances) = reference_glb(&path);
    assert_eq!((meshes, nodes), (29, 82), "README mesh and node counts");
    assert_eq!(reference.len(), 121_496, "README instanced triangle count");
    assert_eq!(m.num_triangles(), 121_496);
    // Parts: one per mesh instance, each naming a node that has a mesh.
    assert_eq!(m.parts.len(), instances);
    assert_eq!(m.tri_part.len(), m.num_triangles());
    let g = gltf::Gltf::open(&path).unwrap();
    let node_list: Vec<_> = g.document.nodes().collect();
    for p in &m.parts {
        let n = p.node.expect("glTF parts carry their node index") as usize;
        assert!(node_list[n].mesh().is_some());
    }
    let used: HashSet<u32> = m.tri_part.iter().copied().collect();
    assert_eq!(used.len(), instances);
    // Geometry: corner by corner, within f32 rounding of the scene size.
    let ext = {
        let b = m.bounds();
        (b.max - b.min).max_element() as f64
    };
    let mut lo = DVec3::splat(f64::MAX);
    let mut hi = DVec3::splat(f64::MIN);
    let mut ref_area = 0.0;
    for (i, r) in reference.iter().enumerate() {
        let got = m.triangle(i);
        for k in 0..3 {
            let d = (got[k].as_dvec3() - r[k]).length();
            assert!(
                d < 1e-5 * ext,
                "triangle {i} corner {k}: {:?} vs {:?}",
                got[k],
                r[k]
            );
            lo = lo.min(r[k]);
            hi = hi.max(r[k]);
        }
        ref_area += 0.5 * (r[1] - r[0]).cross(r[2] - r[0]).length();
        // Same orientation (winding) as the reference.
        let n_ref = (r[1] - r[0]).cross(r[2] - r[0]);
        let n_got = m.face_normal(i).as_dvec3();
        if n_ref.length() > 1e-6 * ext * ext {
            assert!(n_ref.dot(n_got) > 0.0, "triangle {i} winding");
        }
    }
    let b = m.bounds();
    assert!((b.min.as_dvec3() - lo).abs().max_element() < 1e-5 * ext);
    assert!((b.max.as_dvec3() - hi).abs().max_element() < 1e-5 * ext);
    assert!(
        (m.area() - ref_area).abs() < 1e-4 * ref_area,
        "{} vs {ref_area}",
        m.area()
    );
    // Materials: every triangle has one; base colours come from the file.
    assert_eq!(m.tri_material.len(), m.num_triangles());
    let first = g.document.materials().next().unwrap();
    let bc = first.pbr_metallic_roughness().base_color_factor();
    assert!(m
        .materials
        .iter()
        .any(|mat| mat.name == first.name().unwrap() && mat.diffuse == [bc[0], bc[1], bc[2]]));
}
