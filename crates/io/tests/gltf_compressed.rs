//! Compressed glTF as tools write it, from the bunny OBJ
//! (`tests/data/README.md`): `KHR_draco_mesh_compression` by Google's Draco
//! encoder through glTF-Transform, and `EXT_meshopt_compression` by
//! glTF-Transform (quantized positions) and by gltfpack (float positions
//! through the exponential filter). Each decoded mesh is checked against
//! the OBJ it was made from, read by a few-line parser here. The encoders
//! renumber points and triangles and quantize positions, so every decoded
//! point must lie within one 14-bit step of an OBJ vertex, distinct points
//! on distinct vertices, and the triangles, mapped to those vertices, must
//! be the OBJ's with their winding. Damaged data is an error naming the
//! extension.

mod common;

use common::{glb, shared};
use raykit_io::load;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Vertices and 0-based triangles of an OBJ of `v x y z` and `f a b c` lines.
fn obj(path: &Path) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let text = std::fs::read_to_string(path).unwrap();
    let (mut v, mut f) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first() {
            Some(&"v") => v.push([1, 2, 3].map(|i| w[i].parse::<f64>().unwrap())),
            Some(&"f") => f.push(
                [1, 2, 3].map(|i| w[i].split('/').next().unwrap().parse::<usize>().unwrap() - 1),
            ),
            _ => {}
        }
    }
    (v, f)
}

#[test]
fn compressed_bunnies_decode_to_the_obj_they_were_made_from() {
    for name in [
        "bunny_draco.glb",
        "bunny_meshopt.glb",
        "bunny_meshopt_exp.glb",
    ] {
        assert_decodes_to_obj(&fixture(name));
    }
}

fn assert_decodes_to_obj(path: &Path) {
    let loaded = load(path).unwrap_or_else(|e| panic!("{e}"));
    let mesh = &loaded.mesh;
    let (v, f) = obj(&shared("meshes/bunny_3674.obj"));
    assert_eq!(mesh.num_triangles(), f.len());

    let (lo, hi) = v
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            (
                [0, 1, 2].map(|a| lo[a].min(p[a])),
                [0, 1, 2].map(|a| hi[a].max(p[a])),
            )
        });
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    // One 14-bit step over the largest side, per axis.
    let step = extent / f64::from((1u32 << 14) - 1);
    let nearest: Vec<usize> = mesh
        .positions
        .iter()
        .map(|p| {
            let d = |q: &[f64; 3]| {
                (0..3)
                    .map(|a| (f64::from(p[a]) - q[a]).abs())
                    .fold(0.0, f64::max)
            };
            let (i, q) = v
                .iter()
                .enumerate()
                .min_by(|a, b| d(a.1).total_cmp(&d(b.1)))
                .unwrap();
            assert!(
                d(q) <= step,
                "decoded point {p} is {} from every vertex (step {step})",
                d(q)
            );
            i
        })
        .collect();
    // Triangles as rotations that start at their smallest vertex, so that
    // the winding is compared.
    let canonical = |t: [usize; 3]| {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap();
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
    };
    let want: HashSet<[usize; 3]> = f.iter().map(|&t| canonical(t)).collect();
    let got: HashSet<[usize; 3]> = mesh
        .indices
        .iter()
        .map(|t| canonical(t.map(|i| nearest[i as usize])))
        .collect();
    assert_eq!(
        got.len(),
        mesh.num_triangles(),
        "two decoded triangles map to one"
    );
    assert_eq!(got, want);
}

/// The fixture's GLB split into JSON and binary chunk.
fn split(glb: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let n = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let json = serde_json::from_slice(&glb[20..20 + n]).unwrap();
    let bin = glb[20 + n + 8..].to_vec();
    (json, bin)
}

fn join(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    glb(&json.to_string(), bin)
}

#[test]
fn damaged_draco_data_is_an_error_naming_the_extension() {
    let (json, bin) = split(&std::fs::read(fixture("bunny_draco.glb")).unwrap());
    let dir = tempfile::tempdir().unwrap();
    let field = "meshes[0].primitives[0].extensions.KHR_draco_mesh_compression";
    let view_len = json["bufferViews"][0]["byteLength"].as_u64().unwrap() as usize;
    let mut cases: Vec<(&str, serde_json::Value, Vec<u8>)> = Vec::new();
    // The bitstream cut short.
    let mut short = json.clone();
    short["bufferViews"][0]["byteLength"] = serde_json::json!(view_len / 3);
    cases.push(("short.glb", short, bin.clone()));
    // Its header overwritten.
    let mut garbled = bin.clone();
    garbled[..16].fill(0xA5);
    cases.push(("garbled.glb", json.clone(), garbled));
    // An attribute id the data does not have.
    let mut missing = json.clone();
    missing["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
        ["attributes"]["POSITION"] = serde_json::json!(7);
    cases.push(("missing.glb", missing, bin.clone()));
    // No buffer view.
    let mut no_view = json.clone();
    no_view["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
        .as_object_mut()
        .unwrap()
        .remove("bufferView");
    cases.push(("no_view.glb", no_view, bin.clone()));
    for (name, json, bin) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, join(&json, &bin)).unwrap();
        let e = load(&path).expect_err(name).to_string();
        assert!(e.contains(field), "{name}: {e}");
    }
}

#[test]
fn damaged_meshopt_data_is_an_error_naming_the_view() {
    let (json, bin) = split(&std::fs::read(fixture("bunny_meshopt.glb")).unwrap());
    let dir = tempfile::tempdir().unwrap();
    let ext = |j: &mut serde_json::Value, v: usize| -> serde_json::Value {
        j["bufferViews"][v]["extensions"]["EXT_meshopt_compression"].take()
    };
    let views = json["bufferViews"].as_array().unwrap().len();
    let mut cases: Vec<(String, serde_json::Value, Vec<u8>, usize)> = Vec::new();
    for v in 0..views {
        let mut j = json.clone();
        let mut e = ext(&mut j, v);
        let len = e["byteLength"].as_u64().unwrap();
        // The compressed bytes cut short.
        e["byteLength"] = serde_json::json!(len / 4);
        j["bufferViews"][v]["extensions"]["EXT_meshopt_compression"] = e.clone();
        cases.push((format!("short{v}.glb"), j.clone(), bin.clone(), v));
        // Running past the end of the buffer.
        e["byteLength"] = serde_json::json!(bin.len() + 1);
        j["bufferViews"][v]["extensions"]["EXT_meshopt_compression"] = e.clone();
        cases.push((format!("past{v}.glb"), j.clone(), bin.clone(), v));
        // A mode and a stride meshoptimizer does not decode.
        e["byteLength"] = serde_json::json!(len);
        e["mode"] = serde_json::json!("TRIANGLES");
        e["byteStride"] = serde_json::json!(3);
        j["bufferViews"][v]["extensions"]["EXT_meshopt_compression"] = e;
        cases.push((format!("stride{v}.glb"), j, bin.clone(), v));
    }
    // The compressed bytes overwritten.
    let mut garbled = bin.clone();
    garbled.iter_mut().for_each(|b| *b = 0xA5);
    cases.push(("garbled.glb".into(), json.clone(), garbled, 0));
    for (name, json, bin, v) in cases {
        let path = dir.path().join(&name);
        std::fs::write(&path, join(&json, &bin)).unwrap();
        let e = load(&path).expect_err(&name).to_string();
        assert!(
            e.contains("extensions.EXT_meshopt_compression") && e.contains("bufferViews["),
            "{name} (view {v}): {e}"
        );
    }
}
