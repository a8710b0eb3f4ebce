//! Meshes at projected coordinates (UTM metres), read with
//! `load_keeping_precision`: each stored position plus the origin must give
//! back, in `f64`, the coordinates the test wrote, to the `f32` spacing at
//! the model's own size; `load` rounds them to `f32` at their magnitude.
//! Written in OBJ, OFF, ASCII PLY and binary PLY with `double` and `float`
//! properties.

use raykit_io::{load, load_keeping_precision, LoadedMesh};
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
