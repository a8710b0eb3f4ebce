//! Helpers shared by the integration tests.
#![allow(dead_code)]

use raykit_core::{TriangleMesh, Vec3};
use raykit_io::{LoadError, Location};
use std::path::{Path, PathBuf};

/// The test data folder: `$RAYKIT_SHARED_DATA`, or `<workspace>/data`.
/// Panics (failing the test) with the places it looked when it is missing.
pub fn shared_data() -> PathBuf {
    if let Some(p) = std::env::var_os("RAYKIT_SHARED_DATA") {
        let p = PathBuf::from(p);
        assert!(
            p.is_dir(),
            "RAYKIT_SHARED_DATA is set to {}, which is not a directory",
            p.display()
        );
        return p;
    }
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data");
    assert!(
        p.is_dir(),
        "shared test data not found: looked in {} (CARGO_MANIFEST_DIR/../../data); \
         set RAYKIT_SHARED_DATA to its location",
        p.display()
    );
    p
}

/// A file under the test data folder, which must exist.
pub fn shared(rel: &str) -> PathBuf {
    let p = shared_data().join(rel);
    assert!(p.is_file(), "test data file missing: {}", p.display());
    p
}

/// A file under this crate's `tests/data`.
pub fn local(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(rel)
}

/// Bounds of the vertices referenced by triangles, as (min, max).
pub fn bounds(m: &TriangleMesh) -> (Vec3, Vec3) {
    let b = m.bounds();
    (b.min, b.max)
}

/// The corners of every triangle, in order.
pub fn corner_list(m: &TriangleMesh) -> Vec<[Vec3; 3]> {
    (0..m.num_triangles()).map(|i| m.triangle(i)).collect()
}

/// Assert two meshes have the same triangles (same corner positions, in the
/// same order), bit for bit.
pub fn assert_same_triangles(a: &TriangleMesh, b: &TriangleMesh, what: &str) {
    assert_eq!(
        a.num_triangles(),
        b.num_triangles(),
        "{what}: triangle count"
    );
    for i in 0..a.num_triangles() {
        assert_eq!(a.triangle(i), b.triangle(i), "{what}: triangle {i}");
    }
}

/// Assert an error names `file` (its file name) and a line, byte or JSON
/// location, in both the Display text and the structured fields.
pub fn assert_located(e: &LoadError, file: &str) {
    let s = e.to_string();
    let name = Path::new(file)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    assert!(s.contains(&name), "error does not name {name}: {s}");
    match e.location() {
        Location::Line(l) => {
            assert!(*l >= 1, "{s}");
            assert!(s.contains(&format!(":{l}: ")), "no line in: {s}");
        }
        Location::Byte(b) => assert!(s.contains(&format!(": byte {b}: ")), "no byte in: {s}"),
        Location::DecompressedByte(b) => {
            assert!(s.contains(&format!(": byte {b} (decompressed): ")), "{s}")
        }
        Location::Json(j) => {
            assert!(!j.is_empty());
            assert!(s.contains(&format!(": {j}: ")), "no JSON element in: {s}");
        }
        Location::File => panic!("error has no line/byte/JSON location: {s}"),
    }
}

/// Total area of triangles given by corners, in f64.
pub fn area_of(tris: &[[Vec3; 3]]) -> f64 {
    tris.iter()
        .map(|[a, b, c]| {
            let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// A GLB of `json` and the binary chunk `bin`, each padded to four bytes.
pub fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut v = b"glTF".to_vec();
    for x in [2, total as u32, json.len() as u32, 0x4E4F_534A] {
        v.extend_from_slice(&x.to_le_bytes());
    }
    v.extend_from_slice(&json);
    v.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    v.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    v.extend_from_slice(&bin);
    v
}
