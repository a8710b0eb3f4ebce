//! glTF as a scene format: cameras and `KHR_lights_punctual` lights placed by
//! node transforms, base-colour textures (external file, data URI, GLB buffer
//! view; PNG and JPEG), warnings naming unsupported features, errors naming
//! the file and JSON field, and OBJ+MTL `map_Kd` textures.
//!
//! Expected transforms are computed here in f64 from the TRS values written
//! into the files; expected texels from the sRGB formula in f64.

mod common;

use common::{assert_located, glb, shared};
use raykit_core::{Light, Vec2};
use raykit_io::{load, parse_mesh, ErrorKind, LoadError, LoadedMesh, Location};
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::Arc;

// ---------- f64 reference math ----------

type M4 = [[f64; 4]; 4]; // m[row][col]

fn mul(a: &M4, b: &M4) -> M4 {
    let mut r = [[0.0; 4]; 4];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    r
}

/// Translation · rotation (unit quaternion x, y, z, w) · scale.
fn trs(t: [f64; 3], q: [f64; 4], s: [f64; 3]) -> M4 {
    let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    let [x, y, z, w] = q.map(|c| c / n);
    let r = [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ],
        [
            2.0 * (x * y + z * w),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - x * w),
        ],
        [
            2.0 * (x * z - y * w),
            2.0 * (y * z + x * w),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ];
    let mut m = [[0.0; 4]; 4];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = r[i][j] * s[j];
        }
        m[i][3] = t[i];
    }
    m[3][3] = 1.0;
    m
}

fn apply(m: &M4, v: [f64; 3], w: f64) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (i, o) in out.iter_mut().enumerate() {
        *o = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2] + m[i][3] * w;
    }
    out
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = v.iter().map(|c| c * c).sum::<f64>().sqrt();
    v.map(|c| c / n)
}

fn assert_close(got: raykit_core::Vec3, want: [f64; 3], what: &str) {
    for k in 0..3 {
        let (g, w) = (got[k] as f64, want[k]);
        assert!(
            (g - w).abs() <= 1e-5 * w.abs().max(1.0),
            "{what}: got {got:?}, want {want:?}"
        );
    }
}

fn srgb(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The linear RGBA an 8-bit sRGB pixel must decode to.
fn linear(p: [u8; 4]) -> [f64; 4] {
    let c = p.map(|x| x as f64 / 255.0);
    [srgb(c[0]), srgb(c[1]), srgb(c[2]), c[3]]
}

fn assert_texel(got: raykit_core::glam::Vec4, want: [f64; 4], tol: f64, what: &str) {
    for k in 0..4 {
        assert!(
            (got[k] as f64 - want[k]).abs() <= tol,
            "{what}: got {got:?}, want {want:?}"
        );
    }
}

// ---------- file builders ----------

fn b64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = c
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &b)| n | (b as u32) << (16 - 8 * i));
        for k in 0..4 {
            s.push(if k <= c.len() {
                A[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    s
}

/// A triangle: 3 f32 positions then 3 f32 texture coordinates (60 bytes).
fn geometry() -> Vec<u8> {
    let f: [f32; 15] = [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 1.];
    f.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The buffer views and accessors of [`geometry`] in buffer 0, and mesh 0
/// using material `material` if any. `rest` adds further top-level members.
fn gltf_body(buffer: &str, material: Option<usize>, rest: &str) -> String {
    let mat = material.map_or(String::new(), |m| format!(r#", "material": {m}"#));
    let rest = if rest.is_empty() {
        String::new()
    } else {
        format!(",\n{rest}")
    };
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "buffers": [{buffer}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 24}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}{mat}}}]}}]{rest}
}}"#
    )
}

/// A `.gltf` with the geometry in a base64 data URI.
fn gltf(material: Option<usize>, rest: &str) -> String {
    let buffer = format!(
        r#"{{"byteLength": 60, "uri": "data:application/octet-stream;base64,{}"}}"#,
        b64(&geometry())
    );
    gltf_body(&buffer, material, rest)
}

fn write(dir: &Path, name: &str, data: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, data).unwrap();
    p
}

fn load_ok(dir: &Path, name: &str, text: &str) -> LoadedMesh {
    let p = write(dir, name, text.as_bytes());
    load(&p).unwrap_or_else(|e| panic!("{e}"))
}

fn load_err(dir: &Path, name: &str, text: &[u8]) -> (PathBuf, LoadError) {
    let p = write(dir, name, text);
    let e = load(&p).expect_err("the load must fail");
    (p, e)
}

fn png(w: u32, h: u32, px: &[[u8; 4]]) -> Vec<u8> {
    let img = image::RgbaImage::from_fn(w, h, |x, y| image::Rgba(px[(y * w + x) as usize]));
    let mut out = Vec::new();
    img.write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

/// A 3x2 image with distinct pixels (row-major, top row first).
const PIXELS: [[u8; 4]; 6] = [
    [255, 0, 0, 255],
    [0, 128, 0, 200],
    [0, 0, 10, 0],
    [30, 60, 90, 255],
    [200, 201, 202, 17],
    [5, 250, 40, 128],
];

fn assert_pixels(t: &raykit_core::Texture, what: &str) {
    assert_eq!((t.width, t.height), (3, 2), "{what}");
    for (i, p) in PIXELS.iter().enumerate() {
        assert_texel(t.texels[i], linear(*p), 1e-6, &format!("{what} texel {i}"));
    }
}

fn has_warning(l: &LoadedMesh, needles: &[&str]) -> bool {
    l.warnings
        .iter()
        .any(|w| needles.iter().all(|n| w.contains(n)))
}

// ---------- lights and cameras ----------

const Q_PARENT: [f64; 4] = [0.2, -0.4, 0.3, 0.8];
const Q_CAM: [f64; 4] = [-0.1, 0.6, 0.05, 0.7];
const Q_SPOT: [f64; 4] = [0.5, 0.1, -0.3, 0.6];
const Q_SUN: [f64; 4] = [0.6, 0.0, 0.0, 0.8];

fn unit_q(q: [f64; 4]) -> [f64; 4] {
    let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    q.map(|c| c / n)
}

fn scene_json() -> String {
    let (p, c, s, d) = (
        unit_q(Q_PARENT),
        unit_q(Q_CAM),
        unit_q(Q_SPOT),
        unit_q(Q_SUN),
    );
    let rest = format!(
        r#""extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
    {{"type": "point", "color": [1, 0.5, 0.25], "intensity": 10, "range": 50}},
    {{"type": "spot", "color": [0.5, 1, 1], "intensity": 4,
      "spot": {{"innerConeAngle": 0.2, "outerConeAngle": 0.6}}}},
    {{"type": "directional", "color": [0.2, 0.4, 0.6], "intensity": 3}},
    {{"type": "spot", "spot": {{}}}}
  ]}}}},
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.8, "znear": 0.1}}}}],
  "nodes": [
    {{"name": "rig", "translation": [1, 2, 3], "rotation": {p:?}, "scale": [2, 2, 2],
      "children": [1, 2, 3, 4, 5]}},
    {{"translation": [0.5, -1, 4], "rotation": {c:?}, "camera": 0}},
    {{"translation": [1, 0, 0], "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}},
    {{"translation": [0, 3, -1], "rotation": {s:?},
      "extensions": {{"KHR_lights_punctual": {{"light": 1}}}}}},
    {{"rotation": {d:?}, "extensions": {{"KHR_lights_punctual": {{"light": 2}}}}}},
    {{"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 7,8,9,1],
      "extensions": {{"KHR_lights_punctual": {{"light": 3}}}}}},
    {{"mesh": 0}}
  ],
  "scenes": [{{"nodes": [0, 6]}}],
  "scene": 0"#
    );
    gltf(None, &rest)
}

#[test]
fn lights_and_camera_follow_node_transforms() {
    let dir = tempfile::tempdir().unwrap();
    let l = load_ok(dir.path(), "scene.gltf", &scene_json());
    let parent = trs([1.0, 2.0, 3.0], Q_PARENT, [2.0; 3]);
    let world = |t: [f64; 3], q: [f64; 4]| mul(&parent, &trs(t, q, [1.0; 3]));

    // Camera.
    let cam_m = world([0.5, -1.0, 4.0], Q_CAM);
    let eye = apply(&cam_m, [0.0; 3], 1.0);
    let fwd = unit(apply(&cam_m, [0.0, 0.0, -1.0], 0.0));
    let up = unit(apply(&cam_m, [0.0, 1.0, 0.0], 0.0));
    let cam = l.camera.expect("camera");
    assert_close(cam.eye, eye, "eye");
    assert_close(cam.target, [0, 1, 2].map(|k| eye[k] + fwd[k]), "target");
    assert_close(cam.up, up, "up");
    assert!((cam.vfov_deg as f64 - 0.8f64.to_degrees()).abs() < 1e-4);

    assert_eq!(l.lights.len(), 4);
    // Point light: colour × intensity at the transformed origin.
    let Light::Point(p) = l.lights[0] else {
        panic!("{:?}", l.lights[0])
    };
    let pm = world([1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]);
    assert_close(p.position, apply(&pm, [0.0; 3], 1.0), "point position");
    assert_close(p.intensity, [10.0, 5.0, 2.5], "point intensity");

    // Spot light.
    let Light::Spot {
        position,
        direction,
        intensity,
        cos_inner,
        cos_outer,
    } = l.lights[1]
    else {
        panic!("{:?}", l.lights[1])
    };
    let sm = world([0.0, 3.0, -1.0], Q_SPOT);
    assert_close(position, apply(&sm, [0.0; 3], 1.0), "spot position");
    assert_close(
        direction,
        unit(apply(&sm, [0.0, 0.0, -1.0], 0.0)),
        "spot dir",
    );
    assert_close(intensity, [2.0, 4.0, 4.0], "spot intensity");
    assert!((cos_inner as f64 - 0.2f64.cos()).abs() < 1e-6);
    assert!((cos_outer as f64 - 0.6f64.cos()).abs() < 1e-6);

    // Directional light: irradiance, and the direction of -Z.
    let Light::Directional {
        direction,
        irradiance,
    } = l.lights[2]
    else {
        panic!("{:?}", l.lights[2])
    };
    let dm = world([0.0; 3], Q_SUN);
    assert_close(
        direction,
        unit(apply(&dm, [0.0, 0.0, -1.0], 0.0)),
        "sun dir",
    );
    assert_close(irradiance, [0.6, 1.2, 1.8], "sun irradiance");

    // Spot defaults (inner 0, outer π/4, white, intensity 1) under a matrix.
    let Light::Spot {
        position,
        intensity,
        cos_inner,
        cos_outer,
        ..
    } = l.lights[3]
    else {
        panic!("{:?}", l.lights[3])
    };
    let mut mm = [[0.0; 4]; 4];
    for (i, row) in mm.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    mm[0][3] = 7.0;
    mm[1][3] = 8.0;
    mm[2][3] = 9.0;
    assert_close(
        position,
        apply(&mul(&parent, &mm), [0.0; 3], 1.0),
        "default spot",
    );
    assert_close(intensity, [1.0; 3], "default spot intensity");
    assert_eq!(cos_inner, 1.0);
    assert!((cos_outer as f64 - std::f64::consts::FRAC_PI_4.cos()).abs() < 1e-6);

    // `range` is named as ignored.
    assert!(has_warning(&l, &["range"]), "{:?}", l.warnings);
}

#[test]
fn orthographic_cameras_are_skipped_and_the_first_perspective_one_is_used() {
    let rest = r#""cameras": [
    {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "zfar": 10, "znear": 0.1}},
    {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}},
    {"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}
  ],
  "nodes": [
    {"camera": 0},
    {"translation": [0, 0, 5], "children": [2]},
    {"translation": [1, 0, 0], "camera": 2},
    {"translation": [0, 9, 0], "camera": 1},
    {"mesh": 0}
  ],
  "scenes": [{"nodes": [0, 1, 3, 4]}]"#;
    let dir = tempfile::tempdir().unwrap();
    let l = load_ok(dir.path(), "cams.gltf", &gltf(None, rest));
    let cam = l.camera.unwrap();
    // Traversal order: node 0, 1, its child 2, then 3.
    assert_close(cam.eye, [1.0, 0.0, 5.0], "eye");
    assert_close(cam.target, [1.0, 0.0, 4.0], "target");
    assert!((cam.vfov_deg as f64 - 1.0f64.to_degrees()).abs() < 1e-4);
    assert!(has_warning(&l, &["orthographic"]), "{:?}", l.warnings);
    assert!(
        has_warning(&l, &["2 perspective camera", "first"]),
        "{:?}",
        l.warnings
    );
    assert!(l.lights.is_empty());
}

/// A camera whose yfov is not between 0 and π and lights of negative or
/// overflowing power are skipped, each with a warning naming its node.
#[test]
fn cameras_and_lights_out_of_range_are_skipped_by_name() {
    let rest = r#""extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [
    {"type": "point", "intensity": -5},
    {"type": "point", "color": [-1, -1, -1]},
    {"type": "point", "intensity": 1e39},
    {"type": "point", "color": [1, 0.5, 0], "intensity": 2}
  ]}},
  "cameras": [
    {"type": "perspective", "perspective": {"yfov": 3.2, "znear": 0.1}},
    {"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}
  ],
  "nodes": [
    {"camera": 0},
    {"extensions": {"KHR_lights_punctual": {"light": 0}}},
    {"extensions": {"KHR_lights_punctual": {"light": 1}}},
    {"extensions": {"KHR_lights_punctual": {"light": 2}}},
    {"translation": [0, 2, 0], "extensions": {"KHR_lights_punctual": {"light": 3}}},
    {"translation": [0, 0, 5], "camera": 1},
    {"mesh": 0}
  ],
  "scenes": [{"nodes": [0, 1, 2, 3, 4, 5, 6]}]"#;
    let dir = tempfile::tempdir().unwrap();
    let l = load_ok(dir.path(), "ranges.gltf", &gltf(None, rest));
    assert!(has_warning(&l, &["nodes[0]", "yfov"]), "{:?}", l.warnings);
    let cam = l.camera.expect("the second camera");
    assert!((cam.vfov_deg as f64 - 0.7f64.to_degrees()).abs() < 1e-4);
    for node in ["nodes[1]", "nodes[2]", "nodes[3]"] {
        assert!(
            has_warning(&l, &[node, "light skipped"]),
            "{node}: {:?}",
            l.warnings
        );
    }
    assert_eq!(l.lights.len(), 1);
    let Light::Point(p) = l.lights[0] else {
        panic!("{:?}", l.lights[0])
    };
    assert_close(p.intensity, [2.0, 1.0, 0.0], "the one light kept");
}

#[test]
fn material_factors_out_of_range_are_clamped() {
    let rest = r#""extensionsUsed": ["KHR_materials_ior", "KHR_materials_transmission"],
  "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [-0.5, 1e39, 0.25, 1]},
    "emissiveFactor": [-1, 0.5, 7],
    "extensions": {"KHR_materials_ior": {"ior": 0},
                   "KHR_materials_transmission": {"transmissionFactor": 4}}}],
  "nodes": [{"mesh": 0}]"#;
    let dir = tempfile::tempdir().unwrap();
    let l = load_ok(dir.path(), "factors.gltf", &gltf(Some(0), rest));
    let m = &l.mesh.materials[0];
    assert_eq!(m.diffuse, [0.0, 1.0, 0.25]);
    assert_eq!(m.emission, [0.0, 0.5, 1.0]);
    assert_eq!((m.ior, m.transmission), (10.0, 1.0));
}

// ---------- textures ----------

fn textured(image: &str, extra: &str) -> String {
    let rest = format!(
        r#""images": [{image}],
  "textures": [{{"source": 0}}, {{"source": 0}}],
  "materials": [
    {{"name": "a", "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}}}}},
    {{"name": "b", "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 1}}}}}}
  ],
  "meshes": [
    {{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "material": 0}}]}},
    {{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "material": 1}}]}}
  ],
  "nodes": [{{"mesh": 0}}, {{"mesh": 1, "translation": [0, 0, 1]}}]{extra}"#
    );
    // The body's own "meshes" is replaced by the later member (last wins is
    // not guaranteed by every parser), so drop it from the body instead.
    let body = gltf(None, &rest);
    let first = body.find(r#""meshes": [{"primitives""#).unwrap();
    let end = body[first..].find("\n").unwrap() + first;
    format!("{}{}", &body[..first], &body[end + 1..])
}

#[test]
fn external_png_is_decoded_once_and_shared() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tex a.png", &png(3, 2, &PIXELS));
    let l = load_ok(
        dir.path(),
        "ext.gltf",
        &textured(r#"{"uri": "tex%20a.png"}"#, ""),
    );
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    let m = &l.mesh.materials;
    assert_eq!(m.len(), 2);
    let (a, b) = (
        m[0].base_texture.as_ref().unwrap(),
        m[1].base_texture.as_ref().unwrap(),
    );
    assert!(
        Arc::ptr_eq(a, b),
        "one decoded image shared by both materials"
    );
    assert_pixels(a, "external png");
    assert!(a.name.ends_with("tex a.png"), "{}", a.name);
}

#[test]
fn data_uri_png_is_decoded() {
    let dir = tempfile::tempdir().unwrap();
    let image = format!(
        r#"{{"uri": "data:image/png;base64,{}"}}"#,
        b64(&png(3, 2, &PIXELS))
    );
    let l = load_ok(dir.path(), "data.gltf", &textured(&image, ""));
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    assert_pixels(
        l.mesh.materials[0].base_texture.as_ref().unwrap(),
        "data uri",
    );
}

/// `KHR_mesh_quantization` (as gltfpack and glTF-Transform write by
/// default): the shared bunny's positions as 16-bit integers, signed and
/// plain in one node, unsigned and normalised in another, each node's
/// scale and translation undoing the quantization. Every corner loads
/// where the integers and the node's transform put it, computed here in
/// `f64`, and within the quantization step of the original corner.
#[test]
fn quantized_positions_load_dequantized_by_their_nodes() {
    let bunny = load(&shared("meshes/bunny_3674.obj")).unwrap().mesh;
    let (lo, hi) = bunny
        .positions
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
            let p = p.to_array().map(f64::from);
            (
                std::array::from_fn(|k| lo[k].min(p[k])),
                std::array::from_fn(|k| hi[k].max(p[k])),
            )
        });
    let side = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let centre: [f64; 3] = std::array::from_fn(|k| (lo[k] + hi[k]) / 2.0);
    // Signed, plain: p = q * step + centre.
    let step = side / 65534.0;
    let signed: Vec<[i16; 3]> = bunny
        .positions
        .iter()
        .map(|p| std::array::from_fn(|k| ((p[k] as f64 - centre[k]) / step).round() as i16))
        .collect();
    // Unsigned, normalised: p = (q / 65535) * side + lo.
    let unsigned: Vec<[u16; 3]> = bunny
        .positions
        .iter()
        .map(|p| std::array::from_fn(|k| ((p[k] as f64 - lo[k]) / side * 65535.0).round() as u16))
        .collect();
    let mut bin: Vec<u8> = Vec::new();
    // Vertices of 8 bytes (6 used), as glTF's 4-byte alignment asks.
    for q in &signed {
        q.iter()
            .for_each(|c| bin.extend_from_slice(&c.to_le_bytes()));
        bin.extend_from_slice(&[0, 0]);
    }
    let second = bin.len();
    for q in &unsigned {
        q.iter()
            .for_each(|c| bin.extend_from_slice(&c.to_le_bytes()));
        bin.extend_from_slice(&[0, 0]);
    }
    let indices = bin.len();
    for t in &bunny.indices {
        t.iter()
            .for_each(|i| bin.extend_from_slice(&i.to_le_bytes()));
    }
    let n = bunny.positions.len();
    let min_max = |q: &[[i32; 3]]| {
        let mn: [i32; 3] = std::array::from_fn(|k| q.iter().map(|v| v[k]).min().unwrap());
        let mx: [i32; 3] = std::array::from_fn(|k| q.iter().map(|v| v[k]).max().unwrap());
        (mn, mx)
    };
    let (smin, smax) = min_max(&signed.iter().map(|q| q.map(i32::from)).collect::<Vec<_>>());
    let (umin, umax) = min_max(
        &unsigned
            .iter()
            .map(|q| q.map(i32::from))
            .collect::<Vec<_>>(),
    );
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_mesh_quantization"],
  "extensionsRequired": ["KHR_mesh_quantization"],
  "buffers": [{{"byteLength": {len}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": {second}, "byteStride": 8}},
    {{"buffer": 0, "byteOffset": {second}, "byteLength": {second}, "byteStride": 8}},
    {{"buffer": 0, "byteOffset": {indices}, "byteLength": {ilen}}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5122, "count": {n}, "type": "VEC3",
      "min": {smin:?}, "max": {smax:?}}},
    {{"bufferView": 1, "componentType": 5123, "normalized": true, "count": {n}, "type": "VEC3",
      "min": {umin:?}, "max": {umax:?}}},
    {{"bufferView": 2, "componentType": 5125, "count": {icount}, "type": "SCALAR"}}
  ],
  "meshes": [
    {{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 2}}]}},
    {{"primitives": [{{"attributes": {{"POSITION": 1}}, "indices": 2}}]}}
  ],
  "nodes": [
    {{"mesh": 0, "translation": {centre:?}, "scale": [{step:e}, {step:e}, {step:e}]}},
    {{"mesh": 1, "translation": {lo:?}, "scale": [{side:e}, {side:e}, {side:e}]}}
  ],
  "scenes": [{{"nodes": [0, 1]}}]
}}"#,
        len = bin.len(),
        ilen = bin.len() - indices,
        icount = 3 * bunny.indices.len(),
    );
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "quantized.glb", &glb(&json, &bin));
    let loaded = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        !loaded.warnings.iter().any(|w| w.contains("quantization")),
        "{:?}",
        loaded.warnings
    );
    let m = &loaded.mesh;
    let nt = bunny.indices.len();
    assert_eq!(m.indices.len(), 2 * nt);
    for (part, tol) in [(0, 1e-6), (1, 1e-6)] {
        for t in 0..nt {
            let got = m.triangle(part * nt + t);
            for (c, &v) in bunny.indices[t].iter().enumerate() {
                let v = v as usize;
                let want: [f64; 3] = if part == 0 {
                    std::array::from_fn(|k| signed[v][k] as f64 * step + centre[k])
                } else {
                    std::array::from_fn(|k| unsigned[v][k] as f64 / 65535.0 * side + lo[k])
                };
                let original = bunny.positions[v].to_array().map(f64::from);
                for k in 0..3 {
                    let g = got[c][k] as f64;
                    assert!(
                        (g - want[k]).abs() <= tol * side,
                        "node {part} triangle {t}"
                    );
                    assert!((g - original[k]).abs() <= side / 65534.0 + tol * side);
                }
            }
        }
    }
}

/// `EXT_mesh_gpu_instancing` (glTF-Transform's `instance`, gltfpack's
/// `-mi`): one node draws the triangle of [`geometry`] five times, each
/// copy with its own translation, rotation and scale, all moved by the
/// node's own transform. Both loads place every copy where the f64 product
/// of the node's and the copy's TRS puts it: the flattened load as five
/// parts, the instanced load as five instances of one geometry. Copies of
/// unequal counts are an error naming the node's field.
#[test]
fn gpu_instanced_nodes_load_every_copy() {
    let copies: Vec<([f64; 3], [f64; 4], [f64; 3])> = (0..5)
        .map(|i| {
            let a = i as f64;
            (
                [a, 2.0 - a, 0.5 * a],
                [0.1 * a, 0.3, -0.2 * a, 1.0],
                [1.0 + a, 0.5, 2.0 - 0.3 * a],
            )
        })
        .collect();
    let mut bin = geometry();
    let floats = |v: &[f64]| -> Vec<u8> {
        v.iter()
            .flat_map(|&x| (x as f32).to_le_bytes())
            .collect::<Vec<u8>>()
    };
    let t_at = bin.len();
    bin.extend(floats(&copies.iter().flat_map(|c| c.0).collect::<Vec<_>>()));
    let r_at = bin.len();
    // Unit quaternions as f32, as the reference below normalises them too.
    let unit_q = |q: [f64; 4]| {
        let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
        q.map(|c| c / n)
    };
    bin.extend(floats(
        &copies.iter().flat_map(|c| unit_q(c.1)).collect::<Vec<_>>(),
    ));
    let s_at = bin.len();
    bin.extend(floats(&copies.iter().flat_map(|c| c.2).collect::<Vec<_>>()));
    let json = |scale_count: usize| {
        format!(
            r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["EXT_mesh_gpu_instancing"],
  "buffers": [{{"byteLength": {len}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": {t_at}, "byteLength": 60}},
    {{"buffer": 0, "byteOffset": {r_at}, "byteLength": 80}},
    {{"buffer": 0, "byteOffset": {s_at}, "byteLength": 60}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 5, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5126, "count": 5, "type": "VEC4"}},
    {{"bufferView": 3, "componentType": 5126, "count": {scale_count}, "type": "VEC3"}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "nodes": [{{"mesh": 0, "translation": [10, 0, -3], "scale": [2, 2, 2],
    "extensions": {{"EXT_mesh_gpu_instancing":
      {{"attributes": {{"TRANSLATION": 1, "ROTATION": 2, "SCALE": 3}}}}}}}}],
  "scenes": [{{"nodes": [0]}}]
}}"#,
            len = bin.len()
        )
    };
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "gpu.glb", &glb(&json(5), &bin));
    let node = trs([10.0, 0.0, -3.0], [0.0, 0.0, 0.0, 1.0], [2.0; 3]);
    let corners = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let loaded = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        !loaded.warnings.iter().any(|w| w.contains("instancing")),
        "{:?}",
        loaded.warnings
    );
    let m = &loaded.mesh;
    assert_eq!((m.num_triangles(), m.parts.len()), (5, 5));
    let instanced = raykit_io::load_gltf_instances(&path).unwrap();
    assert_eq!(instanced.geometries.len(), 1);
    assert_eq!(instanced.instances.len(), 5);
    for (i, (t, q, s)) in copies.iter().enumerate() {
        let world = mul(&node, &trs(*t, *q, *s));
        let tri = m.triangle(i);
        let to_world = instanced.instances[i].to_world;
        for (c, p) in corners.iter().enumerate() {
            let want = apply(&world, *p, 1.0);
            assert_close(tri[c], want, &format!("copy {i} corner {c}"));
            let placed = to_world.transform_point3(raykit_core::Vec3::new(
                p[0] as f32,
                p[1] as f32,
                p[2] as f32,
            ));
            assert_close(placed, want, &format!("instance {i} corner {c}"));
        }
    }
    let (p, e) = load_err(dir.path(), "uneven.glb", &glb(&json(4), &bin));
    assert_json_error(
        &p,
        &e,
        "nodes[0].extensions.EXT_mesh_gpu_instancing.attributes",
        "different counts",
    );
}

/// A small file can place a mesh so often that the flattened scene would
/// not fit: here a strip of 65,536 vertices drawn by 65,537
/// `EXT_mesh_gpu_instancing` copies and two plain nodes, more vertices than
/// 32-bit indices address, from a file of 1.5 MB. The flattened load is
/// refused before copying, with the counts (computed here from the strip's
/// length and the copies) and the instanced load to use instead; the
/// instanced load takes it. The same file with three copies loads as
/// counted.
#[test]
fn scenes_that_flatten_beyond_32_bit_indices_are_refused_with_their_size() {
    const N: u64 = 65_536;
    let strip: Vec<u8> = (0..N)
        .flat_map(|i| [(i / 2) as f32, (i % 2) as f32, 0.0])
        .flat_map(f32::to_le_bytes)
        .collect();
    let file = |copies: u64| {
        let mut bin = strip.clone();
        let t_at = bin.len();
        bin.extend(
            (0..copies)
                .flat_map(|c| [0.0, 0.0, c as f32])
                .flat_map(f32::to_le_bytes),
        );
        let json = format!(
            r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["EXT_mesh_gpu_instancing"],
  "buffers": [{{"byteLength": {len}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": {t_at}}},
    {{"buffer": 0, "byteOffset": {t_at}, "byteLength": {tl}}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": {N}, "type": "VEC3",
      "min": [0, 0, 0], "max": [{xmax}, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": {copies}, "type": "VEC3"}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "mode": 5}}]}}],
  "nodes": [
    {{"mesh": 0, "extensions": {{"EXT_mesh_gpu_instancing": {{"attributes": {{"TRANSLATION": 1}}}}}}}},
    {{"mesh": 0, "translation": [0, 5, 0]}},
    {{"mesh": 0, "translation": [0, -5, 0]}}
  ],
  "scenes": [{{"nodes": [0, 1, 2]}}]
}}"#,
            len = bin.len(),
            tl = bin.len() - t_at,
            xmax = (N - 1) / 2,
        );
        glb(&json, &bin)
    };
    let dir = tempfile::tempdir().unwrap();
    let copies = 65_537;
    let placements = copies + 2;
    let (p, e) = load_err(dir.path(), "many.glb", &file(copies));
    let msg = e.to_string();
    assert!(msg.starts_with(&p.display().to_string()), "{msg}");
    for needle in [
        format!("places meshes {placements} times"),
        format!(
            "{} triangles and {} vertices",
            (N - 2) * placements,
            N * placements
        ),
        "32-bit indices".to_string(),
        "--instanced".to_string(),
    ] {
        assert!(msg.contains(&needle), "{needle:?} not in: {msg}");
    }
    let instanced = raykit_io::load_gltf_instances(&p).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(instanced.instances.len() as u64, placements);

    let few = write(dir.path(), "few.glb", &file(3));
    let loaded = load(&few).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.mesh.num_triangles() as u64, (N - 2) * 5);
    assert_eq!(loaded.mesh.positions.len() as u64, N * 5);
}

/// Primitives that name the same vertex accessors share their vertices.
/// The writer puts each run of triangles with one material in its own
/// primitive over the part's vertex arrays; a grid of 257 × 257 vertices
/// whose quads alternate between two materials is 65,536 primitives over
/// one array. Copied per primitive, that would be 66,049 · 65,536
/// vertices, more than 32-bit indices address, and the load was refused.
/// It reads back as written: the same vertices, triangles and materials,
/// flattened and instanced. Primitives over the same POSITION but other
/// NORMAL accessors keep their own vertices.
#[test]
fn primitives_over_one_vertex_array_share_its_vertices() {
    use raykit_core::{Material, TriangleMesh, Vec3};
    const SIDE: u32 = 257;
    let positions: Vec<Vec3> = (0..SIDE * SIDE)
        .map(|i| {
            Vec3::new(
                (i % SIDE) as f32,
                ((i * 7919) % 13) as f32 * 0.1,
                (i / SIDE) as f32,
            )
        })
        .collect();
    let mut indices = Vec::new();
    let mut tri_material = Vec::new();
    for z in 0..SIDE - 1 {
        for x in 0..SIDE - 1 {
            let a = z * SIDE + x;
            indices.push([a, a + SIDE, a + 1]);
            indices.push([a + 1, a + SIDE, a + SIDE + 1]);
            tri_material.extend([(x + z) % 2; 2]);
        }
    }
    let mesh = TriangleMesh {
        positions,
        indices,
        tri_material,
        materials: vec![
            Material {
                diffuse: [0.8, 0.1, 0.1],
                ..Material::default()
            },
            Material {
                diffuse: [0.1, 0.1, 0.8],
                ..Material::default()
            },
        ],
        ..TriangleMesh::default()
    };
    let runs = mesh.num_triangles() / 2;
    assert!(
        (runs * mesh.positions.len()) as u64 > u64::from(u32::MAX),
        "a copy per primitive must exceed 32-bit indices"
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grid.glb");
    raykit_io::write_atomic(&path, |w| raykit_io::write_gltf(w, &mesh, true)).unwrap();
    let back = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(back.mesh.positions, mesh.positions);
    assert_eq!(back.mesh.indices, mesh.indices);
    for t in 0..mesh.num_triangles() {
        assert_eq!(
            back.mesh.materials[back.mesh.material_of(t) as usize].diffuse,
            mesh.materials[mesh.tri_material[t] as usize].diffuse,
            "triangle {t}"
        );
    }
    let instanced = raykit_io::load_gltf_instances(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(instanced.geometries.len(), 1);
    assert_eq!(instanced.geometries[0].positions, mesh.positions);
    assert_eq!(instanced.geometries[0].indices, mesh.indices);

    // Two primitives over one POSITION accessor, the second with normals:
    // different vertex arrays, each read.
    let bin: Vec<u8> = [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]]
        .iter()
        .chain(&[[0f32, 0., 1.]; 3])
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let json = r#"{
  "asset": {"version": "2.0"},
  "buffers": [{"byteLength": 72}],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 36},
    {"buffer": 0, "byteOffset": 36, "byteLength": 36}
  ],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
     "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}
  ],
  "meshes": [{"primitives": [
    {"attributes": {"POSITION": 0}},
    {"attributes": {"POSITION": 0}},
    {"attributes": {"POSITION": 0, "NORMAL": 1}}
  ]}],
  "nodes": [{"mesh": 0}],
  "scenes": [{"nodes": [0]}]
}"#;
    let p = write(dir.path(), "mixed.glb", &glb(json, &bin));
    let l = load(&p).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(l.mesh.num_triangles(), 3);
    assert_eq!(
        l.mesh.positions.len(),
        6,
        "the first two share, the third has normals"
    );
    assert_eq!(l.mesh.indices, vec![[0, 1, 2], [0, 1, 2], [3, 4, 5]]);
}

/// A GLB whose image 0 is `image` bytes in buffer view 2.
fn glb_with_image(image: &[u8]) -> Vec<u8> {
    let mut bin = geometry();
    bin.extend_from_slice(image);
    let buffer = format!(r#"{{"byteLength": {}}}"#, bin.len());
    let json = gltf_body(
        &buffer,
        Some(0),
        r#""images": [{"bufferView": 2, "mimeType": "image/png"}],
  "textures": [{"source": 0}],
  "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "nodes": [{"mesh": 0}]"#,
    )
    .replace(
        r#"{"buffer": 0, "byteOffset": 36, "byteLength": 24}"#,
        &format!(
            r#"{{"buffer": 0, "byteOffset": 36, "byteLength": 24}},
    {{"buffer": 0, "byteOffset": 60, "byteLength": {}}}"#,
            image.len()
        ),
    );
    glb(&json, &bin)
}

#[test]
fn glb_buffer_view_png_is_decoded() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "img.glb", &glb_with_image(&png(3, 2, &PIXELS)));
    let l = load(&p).unwrap();
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    assert_pixels(l.mesh.materials[0].base_texture.as_ref().unwrap(), "glb");
}

#[test]
fn glb_with_undecodable_image_warns_and_loads() {
    let dir = tempfile::tempdir().unwrap();
    let mut bad = png(3, 2, &PIXELS);
    bad.truncate(30);
    let p = write(dir.path(), "bad.glb", &glb_with_image(&bad));
    let l = load(&p).unwrap();
    assert!(
        has_warning(&l, &["images[0] (bufferView 2)", "cannot decode"]),
        "{:?}",
        l.warnings
    );
    assert!(l.mesh.materials[0].base_texture.is_none());
}

#[test]
fn jpeg_decodes() {
    let dir = tempfile::tempdir().unwrap();
    let px = [180u8, 90, 30];
    let img = image::RgbImage::from_pixel(16, 16, image::Rgb(px));
    let mut jpg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpg, 100)
        .encode_image(&img)
        .unwrap();
    write(dir.path(), "t.jpg", &jpg);
    let l = load_ok(dir.path(), "jpg.gltf", &textured(r#"{"uri": "t.jpg"}"#, ""));
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    let t = l.mesh.materials[0].base_texture.as_ref().unwrap();
    assert_eq!((t.width, t.height), (16, 16));
    // Lossy: allow 3 code values either way around the encoded colour.
    for (k, &c) in px.iter().enumerate() {
        let lo = srgb((c as f64 - 3.0) / 255.0);
        let hi = srgb((c as f64 + 3.0) / 255.0);
        let got = t.texels[5 * 16 + 7][k] as f64;
        assert!(
            (lo..=hi).contains(&got),
            "channel {k}: {got} not in [{lo}, {hi}]"
        );
    }
    assert_eq!(t.texels[0][3], 1.0);
}

#[test]
fn missing_texture_file_warns_and_the_mesh_loads() {
    let dir = tempfile::tempdir().unwrap();
    let l = load_ok(
        dir.path(),
        "miss.gltf",
        &textured(r#"{"uri": "nope.png"}"#, ""),
    );
    assert_eq!(l.mesh.num_triangles(), 2);
    assert!(l.mesh.materials.iter().all(|m| m.base_texture.is_none()));
    // Once per image, naming the image index, its URI and the file.
    let hits: Vec<_> = l
        .warnings
        .iter()
        .filter(|w| w.contains("images[0] (uri \"nope.png\")") && w.contains("nope.png"))
        .collect();
    assert_eq!(hits.len(), 1, "{:?}", l.warnings);
}

// ---------- unsupported features ----------

#[test]
fn unsupported_features_are_named() {
    let rest = r#""extensionsUsed": ["EXT_foo_bar", "KHR_texture_transform", "KHR_materials_ior"],
  "images": [{"uri": "data:image/png;base64,AAAA"}],
  "samplers": [{"wrapS": 33071}],
  "textures": [{"source": 0, "sampler": 0}],
  "materials": [
    {"normalTexture": {"index": 0}, "occlusionTexture": {"index": 0},
     "emissiveTexture": {"index": 0}, "alphaMode": "MASK",
     "pbrMetallicRoughness": {"metallicRoughnessTexture": {"index": 0},
       "baseColorTexture": {"index": 0, "texCoord": 1}}},
    {"alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
       "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}}}}
  ],
  "skins": [{"joints": [0]}],
  "animations": [{"channels": [], "samplers": []}],
  "nodes": [{"mesh": 0}, {"mesh": 1}],
  "meshes": [
    {"primitives": [{"attributes": {"POSITION": 0}, "material": 0, "targets": [{"POSITION": 0}]}]},
    {"primitives": [{"attributes": {"POSITION": 0}, "material": 1}]}
  ]"#;
    let body = gltf(None, rest);
    let first = body.find(r#""meshes": [{"primitives""#).unwrap();
    let end = body[first..].find('\n').unwrap() + first;
    let text = format!("{}{}", &body[..first], &body[end + 1..]);
    let dir = tempfile::tempdir().unwrap();
    let l = load_ok(dir.path(), "unsupported.gltf", &text);
    let want: &[&[&str]] = &[
        &["EXT_foo_bar"],
        &["KHR_texture_transform", "1 texture"],
        &["normal texture"],
        &["occlusion texture"],
        &["emissive texture"],
        &["metallicRoughness texture"],
        &["texCoord"],
        &["alphaMode MASK"],
        &["alphaMode BLEND"],
        &["1 sampler", "wrapping"],
        &["1 skin"],
        &["morph targets"],
        &["1 animation"],
    ];
    for w in want {
        assert!(
            has_warning(&l, w),
            "no warning with {w:?}: {:?}",
            l.warnings
        );
    }
    assert!(!l.warnings.iter().any(|w| w.contains("KHR_materials_ior")));
    // The texCoord-1 texture is not applied with the wrong coordinates.
    assert!(l.mesh.materials[0].base_texture.is_none());
}

// ---------- malformed files ----------

fn assert_json_error(p: &Path, e: &LoadError, field: &str, needle: &str) {
    assert_eq!(e.path(), p);
    assert_eq!(e.location(), &Location::Json(field.into()), "{e}");
    assert!(e.to_string().contains(needle), "{e}");
    assert_located(e, &p.to_string_lossy());
}

#[test]
fn malformed_scenes_name_the_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let light = gltf(
        None,
        r#""extensions": {"KHR_lights_punctual": {"lights": [{"type": "point"}]}},
  "nodes": [{"mesh": 0}, {"extensions": {"KHR_lights_punctual": {"light": 3}}}]"#,
    );
    let (p, e) = load_err(d, "light.gltf", light.as_bytes());
    assert_json_error(
        &p,
        &e,
        "nodes[1].extensions.KHR_lights_punctual.light",
        "light index 3 is out of range (the file has 1 lights",
    );

    let no_lights = gltf(
        None,
        r#""nodes": [{"mesh": 0, "extensions": {"KHR_lights_punctual": {"light": 0}}}]"#,
    );
    let (p, e) = load_err(d, "nolights.gltf", no_lights.as_bytes());
    assert_json_error(
        &p,
        &e,
        "nodes[0].extensions.KHR_lights_punctual.light",
        "has 0 lights",
    );

    let camera = gltf(None, r#""nodes": [{"mesh": 0, "camera": 2}]"#);
    let (p, e) = load_err(d, "camera.gltf", camera.as_bytes());
    assert_json_error(&p, &e, "nodes[0].camera", "camera index 2 is out of range");

    let basisu = gltf(
        None,
        r#""extensionsUsed": ["KHR_texture_basisu"],
  "extensionsRequired": ["KHR_materials_ior", "KHR_texture_basisu"],
  "nodes": [{"mesh": 0}]"#,
    );
    let (p, e) = load_err(d, "basisu.gltf", basisu.as_bytes());
    assert_json_error(&p, &e, "extensionsRequired[1]", "KHR_texture_basisu");
    assert_eq!(e.kind(), ErrorKind::Unsupported);

    let (p, e) = load_err(
        d,
        "bad.gltf",
        b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [\n",
    );
    assert_eq!(e.path(), p);
    assert!(matches!(e.location(), Location::Line(_)), "{e}");
    assert!(e.to_string().contains("not valid glTF JSON"), "{e}");

    let whole = glb_with_image(&png(3, 2, &PIXELS));
    for cut in [5, 16, 40, whole.len() / 2, whole.len() - 1] {
        let (p, e) = load_err(d, "cut.glb", &whole[..cut]);
        assert_eq!(e.path(), p);
        assert!(matches!(e.location(), Location::Byte(_)), "{e}");
        assert!(e.to_string().contains("truncated"), "{e}");
    }
}

#[test]
fn real_engine_glb_still_loads() {
    let l = load(&shared("meshes/2CylinderEngine.glb")).unwrap();
    assert!(l.mesh.num_triangles() > 0);
}

// ---------- OBJ + MTL ----------

#[test]
fn mtl_map_kd_samples_the_right_texel_with_obj_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("tex")).unwrap();
    write(dir.path(), "tex/wood.png", &png(3, 2, &PIXELS));
    write(
        dir.path(),
        "m.mtl",
        b"newmtl wood\nKd 1 1 1\nmap_Kd -s 1 1 1 tex/wood.png\nnewmtl wood2\nmap_Kd tex/wood.png\n\
          newmtl gone\nmap_Kd tex/none.png\n",
    );
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               usemtl wood\nf 1/1 2/2 3/3\nusemtl wood2\nf 1/1 3/3 4/4\nusemtl gone\nf 1/1 2/2 4/4\n";
    let p = write(dir.path(), "m.obj", obj.as_bytes());
    let l = load(&p).unwrap();
    // OBJ texture coordinates are kept as written.
    assert_eq!(l.mesh.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
    let m = &l.mesh.materials;
    let t = m[0].base_texture.as_ref().unwrap();
    assert!(Arc::ptr_eq(t, m[1].base_texture.as_ref().unwrap()));
    // OBJ v runs up from the bottom of the image: pixel (column c, row r
    // from the top) is at u = (c + 0.5) / w, v = 1 - (r + 0.5) / h.
    for r in 0..2 {
        for c in 0..3 {
            let uv = Vec2::new((c as f32 + 0.5) / 3.0, 1.0 - (r as f32 + 0.5) / 2.0);
            let want = linear(PIXELS[r * 3 + c]);
            assert_texel(t.sample(uv), want, 1e-5, &format!("pixel ({c}, {r})"));
        }
    }
    let gone = m.iter().find(|x| x.name == "gone").unwrap();
    assert!(gone.base_texture.is_none());
    assert!(
        has_warning(&l, &["m.mtl:7", "map_Kd", "none.png"]),
        "{:?}",
        l.warnings
    );
    // Parsing from memory resolves the MTL next to the named path too.
    let again = parse_mesh(&p, obj.as_bytes()).unwrap();
    assert_eq!(again.mesh.materials[0].base_texture, m[0].base_texture);
}

/// A scene written by `write_gltf_scene` reads back with the same
/// materials, camera and lights (of every kind), triangle for triangle.
#[test]
fn written_scene_reads_back_with_materials_camera_and_lights() {
    use raykit_core::{Camera, Light, Material, PointLight, TriangleMesh, Vec3};
    let v = Vec3::new;
    let mut mesh = TriangleMesh {
        positions: vec![v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.), v(1., 1., 0.5)],
        indices: vec![[0, 1, 2], [1, 3, 2], [0, 2, 3]],
        ..TriangleMesh::default()
    };
    mesh.materials = vec![
        Material {
            name: "mirror".into(),
            diffuse: [0.0; 3],
            specular: [0.9, 0.8, 0.7],
            shininess: 300.0,
            reflectivity: 1.0,
            ..Material::default()
        },
        Material {
            name: "glass".into(),
            diffuse: [1.0; 3],
            transmission: 1.0,
            ior: 1.33,
            emission: [0.1, 0.2, 0.3],
            ..Material::default()
        },
    ];
    mesh.tri_material = vec![0, 1, 0];
    let camera = Camera {
        eye: v(3.0, 2.0, 5.0),
        target: v(0.5, 0.4, 0.0),
        up: Vec3::Y,
        vfov_deg: 37.0,
    };
    let lights = vec![
        Light::from(PointLight::new(v(1.0, 4.0, 2.0), v(20.0, 18.0, 16.0))),
        Light::Spot {
            position: v(-2.0, 3.0, 1.0),
            direction: v(0.5, -1.0, -0.2).normalize(),
            intensity: v(5.0, 5.0, 4.0),
            cos_inner: 0.3f32.cos(),
            cos_outer: 0.5f32.cos(),
        },
        Light::Directional {
            direction: v(-0.3, -1.0, 0.4).normalize(),
            irradiance: v(0.7, 0.6, 0.5),
        },
    ];
    let dir = tempfile::tempdir().unwrap();
    for name in ["s.gltf", "s.glb"] {
        let path = dir.path().join(name);
        raykit_io::write_atomic(&path, |w| {
            raykit_io::write_gltf_scene(w, &mesh, Some(&camera), &lights, name.ends_with(".glb"))
        })
        .unwrap();
        let back = raykit_io::load(&path).unwrap();
        assert!(back.warnings.is_empty(), "{:?}", back.warnings);
        // One primitive per material run, over one vertex array read once.
        assert_eq!(back.mesh.positions, mesh.positions, "{name}");
        assert_eq!(back.mesh.indices, mesh.indices, "{name}");
        for t in 0..3 {
            assert_eq!(
                back.mesh.triangle(t),
                mesh.triangle(t),
                "{name}: triangle {t}"
            );
            let (a, b) = (
                &mesh.materials[mesh.tri_material[t] as usize],
                &back.mesh.materials[back.mesh.material_of(t) as usize],
            );
            assert_eq!(
                (a.diffuse, a.specular, a.shininess, a.reflectivity),
                (b.diffuse, b.specular, b.shininess, b.reflectivity),
                "{name}"
            );
            assert_eq!(
                (a.transmission, a.ior, a.emission),
                (b.transmission, b.ior, b.emission),
                "{name}"
            );
        }
        let c = back.camera.expect("a camera");
        assert!((c.eye - camera.eye).length() < 1e-5);
        let (f0, f1) = (
            (camera.target - camera.eye).normalize(),
            (c.target - c.eye).normalize(),
        );
        assert!((f0 - f1).length() < 1e-5, "{f0} vs {f1}");
        assert!(c.up.normalize().dot(Vec3::Y) > 0.9 && (c.vfov_deg - 37.0).abs() < 1e-3);
        assert_eq!(back.lights.len(), 3);
        for (a, b) in lights.iter().zip(&back.lights) {
            assert_eq!(a.kind_name(), b.kind_name());
            // Same light everywhere: compare what it gives a few points.
            for p in [v(0.0, 0.0, 0.0), v(0.5, 0.2, -0.3), v(-1.0, 1.0, 1.0)] {
                let (x, y) = (a.toward(p), b.toward(p));
                assert!(
                    (x.to_light - y.to_light).length() < 1e-5,
                    "{name} {}",
                    a.kind_name()
                );
                assert!(
                    (x.irradiance - y.irradiance).length() < 1e-4 * (1.0 + x.irradiance.length()),
                    "{name} {}: {} vs {}",
                    a.kind_name(),
                    x.irradiance,
                    y.irradiance
                );
            }
        }
    }
}

#[test]
fn a_primitive_without_texture_coordinates_leaves_the_others_theirs() {
    // Mesh 0 has TEXCOORD_0, mesh 1 (the same corners, moved by its node)
    // has none: mesh 0's coordinates must be the file's, mesh 1's zero.
    let dir = tempfile::tempdir().unwrap();
    let rest = r#""meshes": [
    {"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}]},
    {"primitives": [{"attributes": {"POSITION": 0}}]}
  ],
  "nodes": [{"mesh": 0}, {"mesh": 1, "translation": [5, 0, 0]}],
  "scenes": [{"nodes": [0, 1]}]"#;
    let text = gltf(None, rest).replacen(
        r#"  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}]}],"#,
        "",
        1,
    );
    let m = load_ok(dir.path(), "mixed.gltf", &text).mesh;
    assert_eq!(m.num_triangles(), 2);
    let uvs = m
        .uvs
        .as_ref()
        .expect("the texture coordinates of mesh 0 were dropped");
    let file: Vec<f32> = geometry()
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    for t in 0..2 {
        let moved = m.positions[m.indices[t][0] as usize].x >= 4.0;
        for (k, &v) in m.indices[t].iter().enumerate() {
            let want = if moved {
                Vec2::ZERO
            } else {
                Vec2::new(file[9 + 2 * k], file[10 + 2 * k])
            };
            assert_eq!(uvs[v as usize], want, "triangle {t}, corner {k}");
        }
    }
}

#[test]
fn triangle_indices_not_a_multiple_of_three_are_named_in_a_warning() {
    // Five indices (0 1 2 2 1): one whole triangle and two left over.
    let mut data: Vec<u8> = geometry()[..36].to_vec();
    data.extend([0u16, 1, 2, 2, 1].iter().flat_map(|i| i.to_le_bytes()));
    let text = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "buffers": [{{"byteLength": 46, "uri": "data:application/octet-stream;base64,{}"}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 10}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 5, "type": "SCALAR"}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
  "nodes": [{{"mesh": 0}}]
}}"#,
        b64(&data)
    );
    let dir = tempfile::tempdir().unwrap();
    let l = load_ok(dir.path(), "five.gltf", &text);
    assert_eq!(l.mesh.num_triangles(), 1);
    assert!(
        l.warnings
            .iter()
            .any(|w| w.contains("meshes[0].primitives[0]")
                && w.contains("5 indices")
                && w.contains("multiple of 3")),
        "{:?}",
        l.warnings
    );
}
