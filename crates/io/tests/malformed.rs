//! Malformed input for every format: truncation at many cut points, wrong
//! counts, NaN/inf, indices out of range, empty meshes, random bytes (fixed
//! seeds) and random mutations of valid files. Every failure must be an `Err`
//! naming the file and a line, byte or JSON location; nothing may panic.

mod common;

use common::*;
use raykit_core::rng::Pcg32;
use raykit_core::TriangleMesh;
use raykit_io::{
    load, load_mesh, parse_mesh, write_mesh, ErrorKind, LoadError, LoadedMesh, MeshFormat,
    PlyEncoding, StlEncoding,
};
use std::io::Write;
use std::path::Path;

fn parse(name: &str, bytes: &[u8]) -> Result<LoadedMesh, LoadError> {
    let r = std::panic::catch_unwind(|| parse_mesh(Path::new(name), bytes));
    match r {
        Ok(r) => r,
        Err(_) => panic!(
            "parser panicked on {name} ({} bytes): {:?}",
            bytes.len(),
            String::from_utf8_lossy(&bytes[..bytes.len().min(200)])
        ),
    }
}

/// Parse, expect an error located in `name`, return it.
#[track_caller]
fn must_fail(name: &str, bytes: &[u8]) -> LoadError {
    match parse(name, bytes) {
        Ok(m) => panic!(
            "{name}: expected an error, loaded {} triangles from {:?}",
            m.mesh.num_triangles(),
            String::from_utf8_lossy(&bytes[..bytes.len().min(300)])
        ),
        Err(e) => {
            assert_located(&e, name);
            e
        }
    }
}

#[track_caller]
fn fails_with(name: &str, text: &str, needle: &str) -> LoadError {
    let e = must_fail(name, text.as_bytes());
    assert!(e.to_string().contains(needle), "{e}\n(expected: {needle})");
    e
}

fn teapot() -> TriangleMesh {
    load_mesh(&shared("meshes/teapot_992.obj")).unwrap()
}

fn encode(m: &TriangleMesh, f: MeshFormat) -> Vec<u8> {
    let mut v = Vec::new();
    write_mesh(&mut v, m, f).unwrap();
    v
}

fn gzip(data: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

/// About `n` cut points spread over `0..len`, plus every cut in the first and
/// last 100 bytes.
fn cut_points(len: usize, n: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (0..len.min(100)).collect();
    v.extend((0..n).map(|k| k * len / n));
    v.extend(len.saturating_sub(100)..len);
    v.sort_unstable();
    v.dedup();
    v
}

#[test]
fn binary_formats_fail_at_every_truncation() {
    let m = teapot();
    for (name, f) in [
        ("t.ply", MeshFormat::Ply(PlyEncoding::BinaryLittleEndian)),
        ("t.ply", MeshFormat::Ply(PlyEncoding::BinaryBigEndian)),
        ("t.stl", MeshFormat::Stl(StlEncoding::Binary)),
        ("t.glb", MeshFormat::Glb),
    ] {
        let full = encode(&m, f);
        assert!(parse(name, &full).is_ok());
        for cut in cut_points(full.len(), 400) {
            let e = must_fail(name, &full[..cut]);
            assert_ne!(e.kind(), ErrorKind::Io);
        }
    }
    // Gzip streams cut anywhere fail too, naming a byte of the .gz file.
    let z = gzip(&encode(&m, MeshFormat::Ply(PlyEncoding::Ascii)));
    for cut in cut_points(z.len(), 200) {
        must_fail("t.ply.gz", &z[..cut]);
    }
}

#[test]
fn text_formats_fail_when_truncated_before_the_last_token() {
    let m = teapot();
    for (name, f, tail) in [
        ("t.ply", MeshFormat::Ply(PlyEncoding::Ascii), None),
        ("t.off", MeshFormat::Off, None),
        (
            "t.stl",
            MeshFormat::Stl(StlEncoding::Ascii),
            Some("endsolid"),
        ),
        ("t.gltf", MeshFormat::Gltf, Some("}")),
    ] {
        let full = encode(&m, f);
        assert!(parse(name, &full).is_ok());
        let text = std::str::from_utf8(&full).unwrap();
        // Cutting inside the last token may leave a valid file (a shorter
        // number); before it, the file must be rejected.
        let must_fail_below = match tail {
            Some(t) => text.rfind(t).unwrap() + t.len() - 1,
            None => text.trim_end().rfind(char::is_whitespace).unwrap() + 1,
        };
        for cut in cut_points(full.len(), 400) {
            if cut <= must_fail_below {
                must_fail(name, &full[..cut]);
            } else if let Err(e) = parse(name, &full[..cut]) {
                assert_located(&e, name);
            }
        }
    }
    // OBJ has no counts: a cut at a line end is a valid smaller file. Every
    // cut must load fewer triangles or fail with a location.
    let full = encode(&m, MeshFormat::Obj);
    for cut in cut_points(full.len(), 400) {
        match parse("t.obj", &full[..cut]) {
            Ok(l) => assert!(l.mesh.num_triangles() <= m.num_triangles()),
            Err(e) => assert_located(&e, "t.obj"),
        }
    }
}

#[test]
fn wrong_element_counts() {
    let m = teapot();
    // PLY: header says more or fewer vertices / faces than present.
    let ascii = String::from_utf8(encode(&m, MeshFormat::Ply(PlyEncoding::Ascii))).unwrap();
    for (from, to) in [
        ("element vertex 792", "element vertex 793"),
        ("element vertex 792", "element vertex 700"),
        ("element face 992", "element face 993"),
    ] {
        must_fail("t.ply", ascii.replace(from, to).as_bytes());
    }
    fails_with(
        "t.ply",
        &ascii.replace("element face 992", "element face 993"),
        "file ends inside face 992 of 993 (truncated?)",
    );
    let bin = encode(&m, MeshFormat::Ply(PlyEncoding::BinaryLittleEndian));
    let text = String::from_utf8_lossy(&bin).into_owned();
    let header_end = text.find("end_header\n").unwrap() + 11;
    let mut more = bin.clone();
    let at = text.find("element vertex 792").unwrap();
    more[at..at + 18].copy_from_slice(b"element vertex 793");
    let e = must_fail("t.ply", &more);
    assert!(e.to_string().contains("t.ply: byte "), "{e}");
    // Binary STL: triangle count disagrees with the size.
    let mut stl = encode(&m, MeshFormat::Stl(StlEncoding::Binary));
    stl[80..84].copy_from_slice(&993u32.to_le_bytes());
    let e = must_fail("t.stl", &stl);
    assert!(
        e.to_string()
            .contains("t.stl: byte 80: binary STL header says 993 triangles"),
        "{e}"
    );
    // OFF: more vertices and faces announced than present.
    let off = String::from_utf8(encode(&m, MeshFormat::Off)).unwrap();
    fails_with("t.off", &off.replace("792 992 0", "800 992 0"), "t.off:");
    fails_with(
        "t.off",
        &off.replace("792 992 0", "792 999 0"),
        "file ends inside face 992 of 999 (truncated?)",
    );
    // glTF: an accessor count larger than its buffer view.
    let gltf = String::from_utf8(encode(&m, MeshFormat::Gltf)).unwrap();
    let e = fails_with(
        "t.gltf",
        &gltf.replace("\"count\":792", "\"count\":793"),
        "do not fit in bufferViews[0]",
    );
    assert!(e.to_string().contains("t.gltf: accessors[0]: "), "{e}");
    // A count far beyond its data is the same fault, not a file too large
    // for memory.
    let e = fails_with(
        "t.gltf",
        &gltf.replace("\"count\":792", "\"count\":3000000000"),
        "do not fit in bufferViews[0]",
    );
    assert!(e.to_string().contains("t.gltf: accessors[0]: "), "{e}");
    assert!(header_end > 0);
}

/// Read in `f64` for far coordinates, a vertex finite there but beyond
/// what `f32` holds from the origin is refused at its line, in every text
/// format that keeps precision.
#[test]
fn coordinates_beyond_f32_are_refused_where_they_are_read() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text, needle) in [
        (
            "b.obj",
            "v 0 0 1e300\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "b.obj:1: vertex (0e0, 0e0, 1e300)",
        ),
        (
            "f.obj",
            "v 5e6 5e6 0\nv 5e6 5e6 1e300\nv 5e6 5.1e6 0\nf 1 2 3\n",
            "f.obj:2: vertex (5e6, 5e6, 1e300) lies beyond",
        ),
        (
            "b.off",
            "OFF\n3 1 0\n0 0 5e6\n1e300 0 5e6\n0 1 5e6\n3 0 1 2\n",
            "b.off:4: vertex 1 of 3: vertex (1e300, 0e0, 5e6) lies beyond",
        ),
        (
            "b.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n\
property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 -1e300\n0 1 0\n3 0 1 2\n",
            "b.ply:11: vertex 1 of 3: vertex (1e0, 0e0, -1e300) lies beyond",
        ),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        let e = raykit_io::load_keeping_precision(&p)
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "{e}\n(expected: {needle})");
    }
}

#[test]
fn nan_and_infinite_coordinates() {
    fails_with(
        "n.obj",
        "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
        "n.obj:2: expected 3 finite numbers after 'v', found 'nan'",
    );
    fails_with(
        "n.obj",
        "v 0 0 0\nv 1 1e39 0\nv 0 1 0\nf 1 2 3\n",
        "n.obj:2:",
    );
    // Finite, but beyond the coordinates a mesh may hold: located too.
    fails_with(
        "n.obj",
        "v 0 0 0\nv 1 2e12 0\nv 0 1 0\nf 1 2 3\n",
        "n.obj:2: vertex (1e0, 2e12, 0e0) lies beyond ±1e12",
    );
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n";
    fails_with(
        "n.ply",
        ply,
        "n.ply:11: vertex 1 of 3 has a NaN or infinite coordinate",
    );
    // Binary PLY with NaN bits: located at the vertex's first byte.
    let m = TriangleMesh::new(
        vec![
            raykit_core::Vec3::ZERO,
            raykit_core::Vec3::X,
            raykit_core::Vec3::Y,
        ],
        vec![[0, 1, 2]],
    );
    let mut bin = encode(&m, MeshFormat::Ply(PlyEncoding::BinaryLittleEndian));
    let body = String::from_utf8_lossy(&bin).find("end_header\n").unwrap() + 11;
    bin[body + 16..body + 20].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = must_fail("n.ply", &bin);
    assert!(
        e.to_string().contains(&format!(
            "n.ply: byte {}: vertex 1 of 3 has a NaN",
            body + 12
        )),
        "{e}"
    );
    let mut stl = encode(&m, MeshFormat::Stl(StlEncoding::Binary));
    stl[84 + 24..84 + 28].copy_from_slice(&f32::INFINITY.to_le_bytes());
    fails_with_bytes(
        "n.stl",
        &stl,
        "n.stl: byte 108: vertex 1 of triangle 0 has a NaN or infinite",
    );
    let stl_text = String::from_utf8(encode(&m, MeshFormat::Stl(StlEncoding::Ascii))).unwrap();
    fails_with(
        "n.stl",
        &stl_text.replacen("vertex 1 0 0", "vertex 1 0 -inf", 1),
        "n.stl:5: expected 3 finite numbers after 'vertex'",
    );
    fails_with(
        "n.off",
        "OFF\n3 1 0\n0 0 0\nNaN 0 0\n0 1 0\n3 0 1 2\n",
        "n.off:4: vertex 1 of 3: expected 3 finite numbers",
    );
    // glTF: a NaN in the position buffer.
    let mut glb = encode(&m, MeshFormat::Glb);
    let bin_start = glb.len() - (3 * 12 + 12);
    glb[bin_start + 12..bin_start + 16].copy_from_slice(&f32::NAN.to_le_bytes());
    fails_with_bytes(
        "n.glb",
        &glb,
        "n.glb: accessors[0]: vertex 1 is NaN or infinite",
    );
}

#[track_caller]
fn fails_with_bytes(name: &str, bytes: &[u8], needle: &str) {
    let e = must_fail(name, bytes);
    assert!(e.to_string().contains(needle), "{e}\n(expected: {needle})");
}

#[test]
fn indices_out_of_range() {
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    fails_with(
        "i.obj",
        &format!("{tri}f 1 2 4\n"),
        "i.obj:4: vertex index 4 is out of range: only 3 'v'",
    );
    fails_with(
        "i.obj",
        &format!("{tri}f 1 2 -4\n"),
        "i.obj:4: relative vertex index -4 is out of range",
    );
    fails_with(
        "i.obj",
        &format!("{tri}vt 0 0\nf 1/2 2/1 3/1\n"),
        "i.obj:5: texture coordinate index 2 is out of range",
    );
    fails_with(
        "i.obj",
        &format!("{tri}vn 0 0 1\nf 1//1 2//-2 3//1\n"),
        "i.obj:5: relative normal index -2",
    );
    fails_with(
        "i.obj",
        &format!("{tri}f 1 2 99999999999999999999\n"),
        "i.obj:4: vertex index 99999999999999999999 is out of range: only 3 'v'",
    );
    fails_with(
        "i.obj",
        &format!("{tri}f 1 2 -9223372036854775808\n"),
        "i.obj:4: relative vertex index -9223372036854775808 is out of range",
    );
    fails_with(
        "i.obj",
        &format!("{tri}f 1 2 3x\n"),
        "i.obj:4: expected vertex indices",
    );
    let ply = |idx: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 {idx}\n"
        )
    };
    fails_with(
        "i.ply",
        &ply("0 1 3"),
        "i.ply:13: face 0 of 1: vertex index 3 is out of range (the file has 3 vertices)",
    );
    fails_with(
        "i.ply",
        &ply("0 -1 2"),
        "i.ply:13: face 0 of 1: vertex index -1 is out of range",
    );
    fails_with(
        "i.off",
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
        "i.off:6: face 0 of 1: vertex index 7 is out of range",
    );
    fails_with(
        "i.off",
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
        "i.off:6: face 0 of 1: expected 3 vertex indices, found '-1'",
    );
    // Binary PLY: an index equal to the vertex count, located at its byte.
    let m = TriangleMesh::new(
        vec![
            raykit_core::Vec3::ZERO,
            raykit_core::Vec3::X,
            raykit_core::Vec3::Y,
        ],
        vec![[0, 1, 2]],
    );
    for enc in [
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ] {
        let mut bin = encode(&m, MeshFormat::Ply(enc));
        let n = bin.len();
        bin[n - 4..].copy_from_slice(&if enc == PlyEncoding::BinaryBigEndian {
            3u32.to_be_bytes()
        } else {
            3u32.to_le_bytes()
        });
        fails_with_bytes(
            "i.ply",
            &bin,
            &format!("i.ply: byte {n}: face 0 of 1: vertex index 3 is out of range"),
        );
    }
    // glTF: an index past the POSITION count.
    let mut glb = encode(&m, MeshFormat::Glb);
    let n = glb.len();
    glb[n - 4..].copy_from_slice(&3u32.to_le_bytes());
    fails_with_bytes(
        "i.glb",
        &glb,
        "i.glb: meshes[0].primitives[0].indices: index 3 at position 2 is out of range",
    );
}

#[test]
fn empty_meshes() {
    for (name, text, needle) in [
        ("e.obj", "", "e.obj:1: the file has no triangles"),
        ("e.obj", "# nothing\nv 0 0 0\nv 1 1 1\n", "e.obj:3: the file has no triangles"),
        ("e.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n", "e.ply:10: the file has no triangles"),
        ("e.ply", "", "e.ply:1: the header never ends"),
        ("e.stl", "solid empty\nendsolid empty\n", "e.stl:2: the file has no triangles"),
        ("e.stl", "", "e.stl: byte 0: file ends after 0 bytes"),
        ("e.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "e.off:5: the file has no triangles"),
        ("e.off", "", "e.off:1: the file is empty"),
        ("e.gltf", r#"{"asset":{"version":"2.0"}}"#, "e.gltf: scene: the file has no triangles"),
        ("e.gltf", "", "e.gltf:1: not valid glTF JSON"),
        ("e.glb", "", "e.glb:1: not valid glTF JSON"),
    ] {
        let e = fails_with(name, text, needle);
        if !text.is_empty() && !name.ends_with(".ply") || name == "e.obj" {
            assert_eq!(e.kind(), ErrorKind::Empty, "{e}");
        }
    }
    let mut stl = vec![b' '; 80];
    stl.extend(0u32.to_le_bytes());
    let e = must_fail("e.stl", &stl);
    assert_eq!(e.kind(), ErrorKind::Empty);
    assert!(
        e.to_string()
            .starts_with("e.stl: byte 84: the file has no triangles"),
        "{e}"
    );
}

/// Random byte strings, and random bodies behind valid-looking headers.
#[test]
fn random_bytes_never_load() {
    let mut rng = Pcg32::new(0x5eed);
    let prefixes: [(&str, &[u8]); 12] = [
        ("r.obj", b""),
        ("r.obj", b"v 0 0 0\nv 1 0 0\nf "),
        ("r.ply", b""),
        ("r.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 9\nproperty float x\nproperty float y\nproperty float z\nelement face 9\nproperty list uchar int vertex_indices\nend_header\n"),
        ("r.ply", b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nproperty list int int junk\nelement face 20\nproperty list int uint vertex_index\nend_header\n"),
        ("r.ply.gz", b""),
        ("r.stl", b""),
        ("r.stl", b"solid x\n facet normal 0 0 1\n outer loop\n vertex "),
        ("r.off", b"OFF\n4 2 0\n"),
        ("r.gltf", b""),
        ("r.glb", b"glTF\x02\x00\x00\x00"),
        ("r.glb", b""),
    ];
    for (name, prefix) in prefixes {
        for _ in 0..150 {
            let len = rng.below(1500) as usize;
            let mut bytes = prefix.to_vec();
            bytes.extend((0..len).map(|_| rng.next_u32() as u8));
            must_fail(name, &bytes);
        }
    }
    // Random printable text (more likely to reach deep into text parsers).
    let alphabet = b"0123456789 .-+e\nvfntg/#solidfacetvertexendloopOFF";
    for name in ["r.obj", "r.stl", "r.off", "r.ply", "r.gltf"] {
        for _ in 0..150 {
            let len = rng.below(600) as usize;
            let bytes: Vec<u8> = (0..len)
                .map(|_| alphabet[rng.below(alphabet.len() as u32) as usize])
                .collect();
            if let Err(e) = parse(name, &bytes) {
                assert_located(&e, name);
            }
        }
    }
    // Valid gzip around garbage: the inner format's error, in decompressed bytes.
    let mut garbage = b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    garbage.extend([1u8, 2, 3]);
    let e = must_fail("g.ply.gz", &gzip(&garbage));
    assert!(e.to_string().contains("g.ply.gz: byte "), "{e}");
    assert!(e.to_string().contains("(decompressed)"), "{e}");
}

/// Random mutations of small valid files of every format: no panics, and any
/// error names the file.
#[test]
fn mutated_valid_files_do_not_panic() {
    let cube = load_mesh(&local("cube.obj")).unwrap();
    let mut rng = Pcg32::new(42);
    for (name, f) in [
        ("m.obj", MeshFormat::Obj),
        ("m.ply", MeshFormat::Ply(PlyEncoding::Ascii)),
        ("m.ply", MeshFormat::Ply(PlyEncoding::BinaryLittleEndian)),
        ("m.ply", MeshFormat::Ply(PlyEncoding::BinaryBigEndian)),
        ("m.stl", MeshFormat::Stl(StlEncoding::Ascii)),
        ("m.stl", MeshFormat::Stl(StlEncoding::Binary)),
        ("m.off", MeshFormat::Off),
        ("m.glb", MeshFormat::Glb),
        ("m.gltf", MeshFormat::Gltf),
    ] {
        let full = encode(&cube, f);
        for _ in 0..400 {
            let mut b = full.clone();
            for _ in 0..=rng.below(4) {
                let i = rng.below(b.len() as u32) as usize;
                match rng.below(4) {
                    0 => b[i] = rng.next_u32() as u8,
                    1 => b[i] ^= 1 << rng.below(8),
                    2 => {
                        b.remove(i);
                    }
                    _ => b.insert(i, b"0123456789 -\n/"[rng.below(14) as usize]),
                }
            }
            match parse(name, &b) {
                Ok(l) => assert!(l.mesh.validate().is_ok()),
                Err(e) => assert!(e.to_string().starts_with(name), "{e}"),
            }
        }
    }
}

#[test]
fn unknown_extension_missing_file_and_gzip_garbage() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("mesh.xyz");
    std::fs::write(&p, b"v 0 0 0").unwrap();
    let e = load(&p).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnknownFormat);
    assert!(
        e.to_string()
            .contains("mesh.xyz: unknown mesh file extension"),
        "{e}"
    );
    let e = load(&dir.path().join("nope.obj")).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Io);
    assert!(
        e.to_string().contains("nope.obj: cannot read the file"),
        "{e}"
    );
    let e = load(dir.path()).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::UnknownFormat);
    let e = must_fail("g.ply.gz", b"this is not gzip");
    assert!(
        e.to_string().contains("g.ply.gz: byte 0: not gzip data"),
        "{e}"
    );
    let mut z = gzip(b"ply\nformat ascii 1.0\n".repeat(50).as_slice());
    let n = z.len();
    for b in &mut z[12..n - 10] {
        *b = !*b;
    }
    must_fail("g.ply.gz", &z);
    // A directory with a mesh extension is an I/O error, not a panic.
    let d = dir.path().join("dir.obj");
    std::fs::create_dir(&d).unwrap();
    assert_eq!(load(&d).unwrap_err().kind(), ErrorKind::Io);
}

/// ASCII PLY holds one element per line: a vertex line with too few or too
/// many values, or a face line with values left over, is an error naming
/// that line, where reading on would take the next line's values.
#[test]
fn ascii_ply_elements_are_one_line_each() {
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                end_header\n";
    fails_with(
        "short.ply",
        &format!("{head}0 0 0\n1 0\n0 1 0 0\n3 0 1 2\n"),
        "short.ply:11: vertex 1 of 3 has fewer values",
    );
    fails_with(
        "long.ply",
        &format!("{head}0 0 0\n1 0 0 7\n0 1 0\n3 0 1 2\n"),
        "long.ply:11: vertex 1 of 3 has more values",
    );
    fails_with(
        "face.ply",
        &format!("{head}0 0 0\n1 0 0\n0 1 0\n3 0 1 2 9\n"),
        "face.ply:13: face 0 of 1 has more values",
    );
    // Blank lines between elements are white space, as before.
    let ok = parse(
        "blank.ply",
        format!("{head}0 0 0\n\n1 0 0\n0 1 0\n\n3 0 1 2\n").as_bytes(),
    )
    .unwrap();
    assert_eq!(ok.mesh.positions[2], raykit_core::Vec3::new(0.0, 1.0, 0.0));
}
