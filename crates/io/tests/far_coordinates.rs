//! Meshes at projected coordinates (UTM metres), read with
//! `load_keeping_precision`: each stored position plus the origin must give
//! back, in `f64`, the coordinates the test wrote, to the `f32` spacing at
//! the model's own size; `load` rounds them to `f32` at their magnitude.
//! Written in OBJ, OFF, ASCII PLY and binary PLY with `double` and `float`
//! properties, and as a GLB placed at UTM by its nodes' transforms.

mod common;

use raykit_core::glam::{DMat4, DQuat, DVec3};
use raykit_core::Light;
use raykit_io::{load, load_gltf_instances, load_keeping_precision, LoadedMesh};
use std::fmt::Write as _;
use std::path::Path;

/// A 100 m grid of 21 × 21 vertices, slightly curved, at UTM zone 32N.
fn vertices() -> Vec<[f64; 3]> {
    let mut v = Vec::new();
    for i in 0..21 {
        for j in 0..21 {
            let (x, y) = (i as f64 * 5.0 + 0.123_456, j as f64 * 5.0 + 0.654_321);
            v.push([429_252.0 + x, 5_150_885.0 + y, 312.0 + 0.01 * x * y / 7.0]);
        }
    }
    v
}

fn triangles() -> Vec<[usize; 3]> {
    let mut t = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            let a = i * 21 + j;
            t.push([a, a + 21, a + 1]);
            t.push([a + 1, a + 21, a + 22]);
        }
    }
    t
}

fn obj(v: &[[f64; 3]]) -> Vec<u8> {
    let mut s = String::new();
    for p in v {
        writeln!(s, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for t in triangles() {
        writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).unwrap();
    }
    s.into_bytes()
}

fn off(v: &[[f64; 3]]) -> Vec<u8> {
    let t = triangles();
    let mut s = format!("OFF\n{} {} 0\n", v.len(), t.len());
    for p in v {
        writeln!(s, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for t in t {
        writeln!(s, "3 {} {} {}", t[0], t[1], t[2]).unwrap();
    }
    s.into_bytes()
}

fn ply_header(format: &str, ty: &str, nv: usize, nf: usize) -> String {
    format!(
        "ply\nformat {format} 1.0\nelement vertex {nv}\nproperty {ty} x\nproperty {ty} y\n\
         property {ty} z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
    )
}

fn ply_ascii(v: &[[f64; 3]], ty: &str) -> Vec<u8> {
    let t = triangles();
    let mut s = ply_header("ascii", ty, v.len(), t.len());
    for p in v {
        writeln!(s, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for t in t {
        writeln!(s, "3 {} {} {}", t[0], t[1], t[2]).unwrap();
    }
    s.into_bytes()
}

fn ply_binary(v: &[[f64; 3]], double: bool) -> Vec<u8> {
    let t = triangles();
    let ty = if double { "double" } else { "float" };
    let mut b = ply_header("binary_little_endian", ty, v.len(), t.len()).into_bytes();
    for p in v {
        for c in p {
            if double {
                b.extend(c.to_le_bytes());
            } else {
                b.extend((*c as f32).to_le_bytes());
            }
        }
    }
    for t in t {
        b.push(3);
        for i in t {
            b.extend((i as i32).to_le_bytes());
        }
    }
    b
}

/// The largest distance between a loaded position (plus its origin) and
/// the coordinates `want`, in f64.
fn worst(loaded: &LoadedMesh, want: &[[f64; 3]]) -> f64 {
    assert_eq!(loaded.mesh.positions.len(), want.len());
    let o = loaded.origin;
    loaded
        .mesh
        .positions
        .iter()
        .zip(want)
        .map(|(p, w)| {
            (0..3)
                .map(|a| (f64::from(p[a]) + o[a] - w[a]).abs())
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

fn write(dir: &Path, name: &str, data: &[u8]) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, data).unwrap();
    p
}

#[test]
fn utm_coordinates_keep_their_precision_in_every_text_and_double_format() {
    let v = vertices();
    let dir = tempfile::tempdir().unwrap();
    for (name, data) in [
        ("grid.obj", obj(&v)),
        ("grid.off", off(&v)),
        ("ascii_double.ply", ply_ascii(&v, "double")),
        ("ascii_float.ply", ply_ascii(&v, "float")),
        ("binary_double.ply", ply_binary(&v, true)),
    ] {
        let path = write(dir.path(), name, &data);
        let kept = load_keeping_precision(&path).unwrap_or_else(|e| panic!("{e}"));
        // f32 is 7.6e-6 apart at 100 m; the origin lies within the grid's
        // reach of its first vertex.
        assert!(worst(&kept, &v) <= 8e-6, "{name}: {} m", worst(&kept, &v));
        assert!(
            (kept.origin[1] - v[0][1]).abs() < 1e4,
            "{name}: {:?}",
            kept.origin
        );
        assert_eq!(kept.mesh.num_triangles(), triangles().len());
        let rounded = load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(rounded.origin, [0.0; 3]);
        assert!(
            worst(&rounded, &v) > 0.05,
            "{name}: f32 at UTM northings is 0.5 m apart"
        );
    }
}

/// Binary `float` PLY holds f32 already: kept exactly, the origin moving
/// them without rounding.
#[test]
fn f32_files_far_away_move_exactly() {
    let v = vertices();
    let as_f32: Vec<[f64; 3]> = v.iter().map(|p| p.map(|c| c as f32 as f64)).collect();
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "binary_float.ply", &ply_binary(&v, false));
    let kept = load_keeping_precision(&path).unwrap();
    assert_ne!(kept.origin, [0.0; 3]);
    assert_eq!(worst(&kept, &as_f32), 0.0);
}

/// A mesh near zero loads as `load` loads it, position for position.
#[test]
fn meshes_near_zero_load_as_before() {
    let v: Vec<[f64; 3]> = vertices()
        .iter()
        .map(|p| [p[0] - 429_252.0, p[1] - 5_150_885.0, p[2]])
        .collect();
    let dir = tempfile::tempdir().unwrap();
    for (name, data) in [
        ("near.obj", obj(&v)),
        ("near.off", off(&v)),
        ("near.ply", ply_ascii(&v, "float")),
    ] {
        let path = write(dir.path(), name, &data);
        let kept = load_keeping_precision(&path).unwrap();
        let plain = load(&path).unwrap();
        assert_eq!(kept.origin, [0.0; 3], "{name}");
        assert_eq!(kept.mesh.positions, plain.mesh.positions, "{name}");
    }
}

/// The grid near zero as `f32` (the GLB's vertex data), and a GLB placing
/// it at UTM through two nodes: a root translated to a northing with
/// millimetre digits, and a child turned by 30° about the vertical and
/// scaled by 1.5 that holds the mesh, with a point light on a second
/// child. Returns the GLB, the `f32` local vertices and the two nodes'
/// world transforms (mesh, light) composed here in `f64`.
fn placed_glb() -> (Vec<u8>, Vec<[f32; 3]>, DMat4, DMat4) {
    let local: Vec<[f32; 3]> = vertices()
        .iter()
        .map(|p| {
            [
                (p[0] - 429_252.0) as f32,
                (p[1] - 5_150_885.0) as f32,
                (p[2] - 312.0) as f32,
            ]
        })
        .collect();
    let tris = triangles();
    let mut bin = Vec::new();
    for p in &local {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    let positions_len = bin.len();
    for t in &tris {
        for &i in t {
            bin.extend((i as u32).to_le_bytes());
        }
    }
    let (lo, hi) = local
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
            )
        });
    let half = 15f64.to_radians();
    let (qz, qw) = (half.sin(), half.cos());
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "extensionsUsed":["KHR_lights_punctual"],
        "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point","intensity":5}}]}}}},
        "nodes":[
          {{"translation":[429252.123,5150885.456,312.789],"children":[1,2]}},
          {{"mesh":0,"rotation":[0,0,{qz},{qw}],"scale":[1.5,1.5,1.5],"translation":[0.25,-0.5,1.125]}},
          {{"translation":[40.007,60.003,80.001],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":{nv},"type":"VEC3","min":{lo:?},"max":{hi:?}}},
          {{"bufferView":1,"componentType":5125,"count":{ni},"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteLength":{positions_len}}},
          {{"buffer":0,"byteOffset":{positions_len},"byteLength":{il}}}],
        "buffers":[{{"byteLength":{total}}}]}}"#,
        nv = local.len(),
        ni = 3 * tris.len(),
        il = bin.len() - positions_len,
        total = bin.len(),
    );
    let root = DMat4::from_translation(DVec3::new(429_252.123, 5_150_885.456, 312.789));
    let mesh_node = DMat4::from_translation(DVec3::new(0.25, -0.5, 1.125))
        * DMat4::from_quat(DQuat::from_xyzw(0.0, 0.0, qz, qw))
        * DMat4::from_scale(DVec3::splat(1.5));
    let light_node = DMat4::from_translation(DVec3::new(40.007, 60.003, 80.001));
    (
        common::glb(&json, &bin),
        local,
        root * mesh_node,
        root * light_node,
    )
}

/// A glTF placed at UTM by its nodes: node transforms are composed in
/// `f64` from the file's digits, so vertices and light come back to a
/// tenth of a millimetre of the `f64` placement; `load`, which rounds to
/// `f32` at the northing, is decimetres off. Its instanced load keeps the
/// `f64` placement too.
#[test]
fn gltf_placed_far_by_its_nodes_keeps_its_precision() {
    let (data, local, mesh_world, light_world) = placed_glb();
    let want: Vec<[f64; 3]> = local
        .iter()
        .map(|p| {
            mesh_world
                .transform_point3(DVec3::from_array(p.map(f64::from)))
                .to_array()
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "placed.glb", &data);
    let kept = load_keeping_precision(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(worst(&kept, &want) <= 1e-4, "{} m", worst(&kept, &want));
    assert!(
        (kept.origin[1] - want[0][1]).abs() < 1e3,
        "{:?}",
        kept.origin
    );
    let light_at = |l: &LoadedMesh| match l.lights.as_slice() {
        [Light::Point(p)] => {
            DVec3::from_array(p.position.to_array().map(f64::from)) + DVec3::from_array(l.origin)
        }
        other => panic!("expected one point light, got {other:?}"),
    };
    let light_want = light_world.transform_point3(DVec3::ZERO);
    assert!((light_at(&kept) - light_want).abs().max_element() <= 1e-4);
    let rounded = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rounded.origin, [0.0; 3]);
    assert!(
        worst(&rounded, &want) > 0.05,
        "{} m",
        worst(&rounded, &want)
    );

    let instanced = load_gltf_instances(&path).unwrap_or_else(|e| panic!("{e}"));
    let [inst] = instanced.instances.as_slice() else {
        panic!("one instance expected");
    };
    let placed = DMat4::from(inst.to_world_f64);
    assert!(
        placed.abs_diff_eq(mesh_world, 1e-9),
        "{placed} against {mesh_world}"
    );
}

/// A glTF near zero loads as `load` loads it, position for position: the
/// shared engine's node hierarchy and the bunny's compressed files.
#[test]
fn gltf_near_zero_loads_as_before() {
    for path in [
        common::shared("meshes/2CylinderEngine.glb"),
        common::local("bunny_meshopt.glb"),
    ] {
        let kept = load_keeping_precision(&path).unwrap_or_else(|e| panic!("{e}"));
        let plain = load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(kept.origin, [0.0; 3], "{}", path.display());
        assert_eq!(
            kept.mesh.positions,
            plain.mesh.positions,
            "{}",
            path.display()
        );
    }
}
