//! Environments checked against independent references: the shared OpenEXR
//! maps read through the `exr` crate's own API, the direction mapping and
//! bilinear filter written again here in f64, the environment box's exit
//! point computed in f64, and `.hdr` files written by the `image` crate.

use raykit_core::glam::{DVec3, Vec3};
use raykit_core::rng::Pcg32;
use raykit_core::Aabb;
use raykit_render::env::{dir_to_uv, uv_to_dir, EnvError, Environment, EquirectMap};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

// ---------------------------------------------------------------- references

/// `u = 0.5 + atan2(x, -z) / 2π`, `v = acos(y / |d|) / π` in f64.
fn ref_uv(d: DVec3) -> (f64, f64) {
    let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
    let v = (d.y / d.length()).clamp(-1.0, 1.0).acos() / PI;
    (u, v)
}

/// Bilinear filtering in f64: wrap in u, clamp in v; texel centres at
/// `(i + 0.5) / w`.
fn ref_bilinear(map: &EquirectMap, u: f64, v: f64) -> DVec3 {
    let (w, h) = (map.width() as i64, map.height() as i64);
    let x = u.rem_euclid(1.0) * w as f64 - 0.5;
    let y = v.clamp(0.0, 1.0) * h as f64 - 0.5;
    let (fx, fy) = (x - x.floor(), y - y.floor());
    let (i, j) = (x.floor() as i64, y.floor() as i64);
    let at = |i: i64, j: i64| {
        let t = map
            .texel(i.rem_euclid(w) as usize, j.clamp(0, h - 1) as usize)
            .unwrap();
        DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)
    };
    (at(i, j) * (1.0 - fx) + at(i + 1, j) * fx) * (1.0 - fy)
        + (at(i, j + 1) * (1.0 - fx) + at(i + 1, j + 1) * fx) * fy
}

/// The map seen along `d` (f64 reference), with `turn` of a revolution added to u.
fn ref_lookup(map: &EquirectMap, d: DVec3, turn: f64) -> DVec3 {
    let (u, v) = ref_uv(d);
    ref_bilinear(map, u + turn, v)
}

/// Where a ray leaves the box, by the slab method in f64.
fn ref_exit(b: &Aabb, o: DVec3, d: DVec3) -> Option<DVec3> {
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
        } else {
            let (t0, t1) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
            near = near.max(t0.min(t1));
            far = far.min(t0.max(t1));
        }
    }
    (near <= far && far >= 0.0).then(|| o + d * far)
}

fn close(a: Vec3, b: DVec3, tol: f64) -> bool {
    (a.as_dvec3() - b).abs().max_element() <= tol
}

/// A map of random texels in `[0, 1)` (maximal contrast between neighbours).
fn random_map(w: usize, h: usize, seed: u64) -> EquirectMap {
    let mut rng = Pcg32::new(seed);
    let texels = (0..w * h)
        .map(|_| [rng.next_f32(), rng.next_f32(), rng.next_f32()])
        .collect();
    EquirectMap::new(w, h, texels).unwrap()
}

/// Directions that avoid the poles, where u is ill-conditioned.
fn directions(rng: &mut Pcg32, n: usize) -> Vec<Vec3> {
    let mut v = vec![
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Z,
        Vec3::NEG_Z,
        Vec3::new(1.0, 0.0, 1.0),
    ];
    while v.len() < n {
        let d = rng.unit_vector();
        if d.y.abs() < 0.995 {
            v.push(d * rng.range_f32(0.1, 10.0));
        }
    }
    v
}

// ----------------------------------------------------------- the shared maps

/// The eight test maps: `$RAYKIT_SHARED_DATA/envmaps`, or the test data
/// folder next to the project. Missing maps fail the tests.
fn shared_maps() -> Vec<PathBuf> {
    let root = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data"));
    let dir = root.join("envmaps");
    let mut maps: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    maps.retain(|p| p.extension().is_some_and(|e| e == "exr"));
    maps.sort();
    assert_eq!(
        maps.len(),
        8,
        "{}: the tests need the 8 shared environment maps (set RAYKIT_SHARED_DATA)",
        dir.display()
    );
    maps
}

/// The RGB texels of `path` read through the exr crate's generic channel API
/// (not the RGBA convenience reader the loader uses).
fn exr_texels(path: &Path) -> (usize, usize, Vec<[f32; 3]>) {
    let image = exr::prelude::read_first_flat_layer_from_file(path).unwrap();
    let layer = image.layer_data;
    let channel = |name: &str| -> Vec<f32> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name == *name)
            .unwrap_or_else(|| panic!("{}: no {name} channel", path.display()));
        c.sample_data.values_as_f32().collect()
    };
    let (r, g, b) = (channel("R"), channel("G"), channel("B"));
    let texels = (0..r.len()).map(|k| [r[k], g[k], b[k]]).collect();
    (layer.size.0, layer.size.1, texels)
}

#[test]
fn shared_maps_load_and_match_the_exr_crate_texel_for_texel() {
    for path in shared_maps() {
        let map = EquirectMap::load(&path).unwrap();
        assert_eq!(
            (map.width(), map.height()),
            (1024, 512),
            "{}",
            path.display()
        );
        let (w, h, raw) = exr_texels(&path);
        assert_eq!((w, h), (1024, 512));
        let bad = raw
            .iter()
            .filter(|t| t.iter().any(|c| !(c.is_finite() && *c >= 0.0)))
            .count();
        assert_eq!(map.clamped_texels(), bad, "{}", path.display());
        eprintln!("{}: {bad} texels clamped", path.display());
        for j in 0..h {
            for i in 0..w {
                let t = map.texel(i, j).unwrap();
                assert!(t.iter().all(|c| c.is_finite() && *c >= 0.0));
                let expect =
                    raw[j * w + i].map(|c| if c.is_finite() && c >= 0.0 { c } else { 0.0 });
                assert_eq!(t, expect, "{} texel ({i}, {j})", path.display());
                // Exactly the texel at its centre.
                let (u, v) = ((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
                assert_eq!(map.sample_uv(u, v).to_array(), expect);
            }
        }
        // Through directions: the f32 direction of a texel centre lands within
        // rounding of it, so the lookup agrees with the f64 filter there.
        let mut rng = Pcg32::new(7);
        for _ in 0..2000 {
            let (i, j) = (rng.below(w as u32) as usize, rng.below(h as u32) as usize);
            let (u, v) = ((i as f64 + 0.5) / w as f64, (j as f64 + 0.5) / h as f64);
            let d = uv_to_dir(u as f32, v as f32);
            let got = map.lookup(d);
            let want = ref_lookup(&map, d.as_dvec3(), 0.0);
            let t = Vec3::from_array(map.texel(i, j).unwrap()).as_dvec3();
            // An f32 u is good to about 1e-4 texel: allow that fraction of
            // the brightest neighbour (some maps hold bright dots beside black).
            let mut brightest = 0.0f32;
            for dj in -1..=1i64 {
                for di in -1..=1i64 {
                    let ii = (i as i64 + di).rem_euclid(w as i64) as usize;
                    let jj = (j as i64 + dj).clamp(0, h as i64 - 1) as usize;
                    brightest = map
                        .texel(ii, jj)
                        .unwrap()
                        .into_iter()
                        .fold(brightest, f32::max);
                }
            }
            let tol = 5e-4 * (1.0 + brightest as f64);
            assert!(
                close(got, want, tol),
                "{} ({i}, {j}) {d}: {got} vs {want}",
                path.display()
            );
            if j > 2 && j < h - 3 {
                assert!(close(got, t, tol), "{got} vs texel {t}");
            }
        }
    }
}

#[test]
fn truncated_and_garbage_files_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut cases: Vec<(PathBuf, Vec<u8>)> = vec![
        (
            dir.path().join("garbage.exr"),
            b"this is not an exr file".to_vec(),
        ),
        (
            dir.path().join("magic-only.exr"),
            vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0],
        ),
        (
            dir.path().join("garbage.hdr"),
            b"#?RADIANCE\nnonsense".to_vec(),
        ),
        (dir.path().join("empty.hdr"), Vec::new()),
    ];
    if let Some(p) = shared_maps().first() {
        let bytes = std::fs::read(p).unwrap();
        for cut in [20, 400, bytes.len() / 2, bytes.len() - 10] {
            cases.push((
                dir.path().join(format!("cut{cut}.exr")),
                bytes[..cut].to_vec(),
            ));
        }
    }
    for (path, bytes) in cases {
        std::fs::write(&path, bytes).unwrap();
        let e = EquirectMap::load(&path).unwrap_err();
        assert_eq!(e.path(), path);
        assert!(e.to_string().contains(&*path.to_string_lossy()), "{e}");
    }
    // A Radiance file cut short is an error naming the byte where it ends;
    // one cut inside its header, the byte the decoder reached.
    let pixels: Vec<image::Rgb<f32>> = (0..32).map(|i| image::Rgb([i as f32, 1.0, 0.5])).collect();
    let mut whole = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut whole)
        .encode(&pixels, 8, 4)
        .unwrap();
    let body = whole.windows(2).position(|w| w == b"\n\n").unwrap() + 2;
    let size_line = whole[body..].iter().position(|&b| b == b'\n').unwrap() + body + 1;
    for cut in [size_line + 3, whole.len() - 5] {
        let path = dir.path().join(format!("cut{cut}.hdr"));
        std::fs::write(&path, &whole[..cut]).unwrap();
        let e = EquirectMap::load(&path).unwrap_err().to_string();
        assert!(e.contains(&format!("ends at byte {cut}")), "{e}");
    }
    let path = dir.path().join("bad-size.hdr");
    let mut bad = whole[..body].to_vec();
    bad.extend_from_slice(b"-Y zz +X 8\n");
    std::fs::write(&path, &bad).unwrap();
    let e = EquirectMap::load(&path).unwrap_err().to_string();
    assert!(e.contains(&format!("at byte {}", bad.len())), "{e}");

    let missing = dir.path().join("missing.exr");
    let e = EquirectMap::load(&missing).unwrap_err();
    assert!(matches!(e, EnvError::Io { .. }) && e.to_string().contains("missing.exr"));
    let e = EquirectMap::load(dir.path().join("map.png")).unwrap_err();
    assert!(matches!(e, EnvError::UnknownFormat { .. }) && e.to_string().contains("map.png"));
}

/// The bytes of an OpenEXR header claiming a `width` × `height` RGB layer
/// of half floats, uncompressed (OpenEXR's file layout: magic, version, the
/// required attributes, a zero byte), with no offset table or pixels.
fn exr_header(width: i32, height: i32) -> Vec<u8> {
    let attr = |name: &str, kind: &str, value: &[u8]| {
        let mut a = Vec::new();
        for s in [name, kind] {
            a.extend_from_slice(s.as_bytes());
            a.push(0);
        }
        a.extend_from_slice(&(value.len() as i32).to_le_bytes());
        a.extend_from_slice(value);
        a
    };
    let ints = |v: &[i32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let floats = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let mut channels = Vec::new();
    for c in ["B", "G", "R"] {
        channels.extend_from_slice(c.as_bytes());
        channels.push(0);
        channels.extend_from_slice(&ints(&[1, 0, 1, 1]));
    }
    channels.push(0);
    let window = ints(&[0, 0, width - 1, height - 1]);
    let mut out = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
    out.extend(attr("channels", "chlist", &channels));
    out.extend(attr("compression", "compression", &[0]));
    out.extend(attr("dataWindow", "box2i", &window));
    out.extend(attr("displayWindow", "box2i", &window));
    out.extend(attr("lineOrder", "lineOrder", &[0]));
    out.extend(attr("pixelAspectRatio", "float", &floats(&[1.0])));
    out.extend(attr("screenWindowCenter", "v2f", &floats(&[0.0, 0.0])));
    out.extend(attr("screenWindowWidth", "float", &floats(&[1.0])));
    out.push(0);
    out
}

/// A header claiming more than `MAX_TEXELS` is refused by its size before
/// anything is allocated (a 200000² OpenEXR header made the decoder's
/// caller ask for 480 GB and abort); a Radiance map of 12000 × 6000, which
/// the image crate's default memory bound refused, is read (here, cut
/// short after its header, the error is that it ends there).
#[test]
fn maps_are_bounded_by_their_texel_count_not_the_decoders_default() {
    let dir = tempfile::tempdir().unwrap();
    let side = 200_000;
    assert!(side * side > raykit_render::env::MAX_TEXELS);
    let path = dir.path().join("huge.exr");
    std::fs::write(&path, exr_header(side as i32, side as i32)).unwrap();
    let e = EquirectMap::load(&path).unwrap_err();
    assert!(matches!(e, EnvError::Invalid { .. }), "{e}");
    assert!(e.to_string().contains("at most"), "{e}");
    // Within the bound, the same header is read as far as it goes.
    let path = dir.path().join("header-only.exr");
    std::fs::write(&path, exr_header(64, 32)).unwrap();
    let e = EquirectMap::load(&path).unwrap_err();
    assert!(matches!(e, EnvError::Decode { .. }), "{e}");

    let header =
        |w: usize, h: usize| format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n");
    let path = dir.path().join("huge.hdr");
    std::fs::write(&path, header(side, side)).unwrap();
    let e = EquirectMap::load(&path).unwrap_err();
    assert!(matches!(e, EnvError::Invalid { .. }), "{e}");
    assert!(e.to_string().contains("at most"), "{e}");
    let path = dir.path().join("large.hdr");
    let text = header(12_000, 6_000);
    std::fs::write(&path, &text).unwrap();
    let e = EquirectMap::load(&path).unwrap_err().to_string();
    assert!(e.contains(&format!("ends at byte {}", text.len())), "{e}");
}

// ------------------------------------------------------------------- mapping

#[test]
fn direction_mapping_matches_f64_and_round_trips() {
    let mut rng = Pcg32::new(3);
    for _ in 0..20_000 {
        let d = rng.unit_vector() * rng.range_f32(1e-3, 1e3);
        let (u, v) = dir_to_uv(d).unwrap();
        let (ru, rv) = ref_uv(d.as_dvec3());
        // u is periodic: compare around the circle.
        let du = (u as f64 - ru).rem_euclid(1.0);
        assert!(du.min(1.0 - du) < 2e-6, "{d}: u {u} vs {ru}");
        assert!((v as f64 - rv).abs() < 2e-6, "{d}: v {v} vs {rv}");
        let back = uv_to_dir(u, v);
        assert!((back - d.normalize()).length() < 2e-5, "{d} -> {back}");
    }
    for _ in 0..20_000 {
        let (u, v) = (rng.next_f32(), rng.range_f32(0.01, 0.99));
        let (u2, v2) = dir_to_uv(uv_to_dir(u, v)).unwrap();
        let du = (u2 - u).rem_euclid(1.0);
        assert!(
            du.min(1.0 - du) < 2e-6 && (v2 - v).abs() < 2e-6,
            "({u}, {v}) -> ({u2}, {v2})"
        );
    }
}

#[test]
fn lookup_matches_the_f64_filter_and_wraps_across_the_seam() {
    let map = random_map(64, 32, 1);
    let mut rng = Pcg32::new(5);
    for d in directions(&mut rng, 5000) {
        let want = ref_lookup(&map, d.as_dvec3(), 0.0);
        assert!(close(map.lookup(d), want, 2e-4), "{d}");
    }
    // u near 0 and near 1 blend the first and last columns of the row.
    let (first, last) = (
        Vec3::from_array(map.texel(0, 10).unwrap()),
        Vec3::from_array(map.texel(63, 10).unwrap()),
    );
    let v = 10.5 / 32.0;
    assert!(
        (map.sample_uv(0.0, v) - (first + last) * 0.5)
            .abs()
            .max_element()
            < 1e-6
    );
    assert!(
        (map.sample_uv(1.0, v) - (first + last) * 0.5)
            .abs()
            .max_element()
            < 1e-6
    );
    let near0 = map.sample_uv(0.25 / 64.0, v);
    assert!((near0 - (first * 0.75 + last * 0.25)).abs().max_element() < 1e-6);
    let near1 = map.sample_uv(1.0 - 0.25 / 64.0, v);
    assert!((near1 - (first * 0.25 + last * 0.75)).abs().max_element() < 1e-6);
    // Directions on either side of +Z (the seam).
    let y = (PI * (0.5 - v as f64)).sin() as f32;
    for x in [-0.01f32, -1e-6, 0.0, 1e-6, 0.01] {
        let d = Vec3::new(x, y, 1.0);
        let want = ref_lookup(&map, d.as_dvec3(), 0.0);
        assert!(close(map.lookup(d), want, 1e-4), "{d}");
    }
    // Vertical clamping: the poles are the top and bottom rows' average over u.
    let top = map.sample_uv(0.3, 0.0);
    let want = ref_bilinear(&map, 0.3, 0.0);
    assert!(close(top, want, 1e-6));
}

#[test]
fn rotation_and_intensity() {
    let base = random_map(64, 32, 2);
    let map = base.clone().with_rotation_deg(90.0).with_intensity(3.0);
    // After +90° about +Y, what was seen along -Z is seen along -X.
    let (a, b) = (map.lookup(Vec3::NEG_X), base.lookup(Vec3::NEG_Z) * 3.0);
    assert!((a - b).abs().max_element() < 1e-5, "{a} {b}");
    let mut rng = Pcg32::new(9);
    for d in directions(&mut rng, 2000) {
        let want = ref_lookup(&base, d.as_dvec3(), 0.25) * 3.0;
        assert!(close(map.lookup(d), want, 1e-3), "{d}");
        let turned = base.clone().with_rotation_deg(-450.0);
        let want = ref_lookup(&base, d.as_dvec3(), -0.25);
        assert!(close(turned.lookup(d), want, 1e-3), "{d}");
    }
}

// -------------------------------------------------------- the environment box

fn box_env(map: &Arc<EquirectMap>) -> (Environment, Aabb) {
    let scene = Aabb::new(Vec3::new(-2.0, 0.0, -1.0), Vec3::new(2.0, 1.5, 3.0));
    let env = Environment::env_box(map.clone(), scene, 2.0);
    let Environment::Box { bounds, .. } = env else {
        panic!("not a box: {}", env.describe());
    };
    assert_eq!(
        bounds,
        Aabb::new(Vec3::new(-4.0, 0.0, -3.0), Vec3::new(4.0, 2.25, 5.0))
    );
    (env, bounds)
}

#[test]
fn from_the_box_centre_the_box_is_direction_lookup() {
    let map = Arc::new(random_map(128, 64, 3));
    let (env, b) = box_env(&map);
    let dir_env = Environment::map(map.clone());
    let mut rng = Pcg32::new(11);
    for d in directions(&mut rng, 5000) {
        let (got, want) = (env.radiance(b.center(), d), dir_env.radiance(Vec3::ZERO, d));
        assert!(
            (got - want).abs().max_element() < 1e-4,
            "{d}: {got} vs {want}"
        );
    }
}

#[test]
fn from_elsewhere_the_box_looks_up_towards_the_exit_point() {
    let map = Arc::new(random_map(128, 64, 4));
    let (env, b) = box_env(&map);
    let c = b.center().as_dvec3();
    let mut rng = Pcg32::new(12);
    let mut dirs = directions(&mut rng, 3000);
    // Zero components.
    dirs.extend([
        Vec3::new(1.0, 0.0, 0.5),
        Vec3::new(0.0, 0.3, -1.0),
        Vec3::new(-0.2, 0.0, 0.0),
    ]);
    for (k, d) in dirs.iter().enumerate() {
        let o = if k % 3 == 0 {
            Vec3::new(3.0, 0.5, -2.0)
        } else {
            rng.in_box(b.min * 0.95, b.max * 0.95)
        };
        let exit = ref_exit(&b, o.as_dvec3(), d.as_dvec3()).unwrap();
        let q = exit - c;
        if q.y.abs() > 0.995 * q.length() {
            continue; // too near a pole for a stable u
        }
        let want = ref_lookup(&map, q, 0.0);
        let got = env.radiance(o, *d);
        assert!(close(got, want, 1e-3), "o {o} d {d}: {got} vs {want}");
    }
}

#[test]
fn parallel_rays_show_parallax_in_the_box_only() {
    let map = Arc::new(random_map(128, 64, 5));
    let (env, _) = box_env(&map);
    let dir_env = Environment::map(map.clone());
    let d = Vec3::new(0.3, 0.1, -1.0);
    let (o1, o2) = (Vec3::new(-2.0, 0.5, 0.0), Vec3::new(2.5, 1.5, 2.0));
    assert_eq!(dir_env.radiance(o1, d), dir_env.radiance(o2, d));
    let (c1, c2) = (env.radiance(o1, d), env.radiance(o2, d));
    assert!((c1 - c2).abs().max_element() > 0.05, "{c1} {c2}");
    // And each is the map towards its own exit point.
    for (o, c) in [(o1, c1), (o2, c2)] {
        let q = ref_exit(
            &Aabb::new(Vec3::new(-4.0, 0.0, -3.0), Vec3::new(4.0, 2.25, 5.0)),
            o.as_dvec3(),
            d.as_dvec3(),
        )
        .unwrap();
        let want = ref_lookup(&map, q - DVec3::new(0.0, 1.125, 1.0), 0.0);
        assert!(close(c, want, 1e-3));
    }
}

#[test]
fn rays_from_outside_that_miss_fall_back_to_direction_lookup() {
    let map = Arc::new(random_map(128, 64, 6));
    let (env, b) = box_env(&map);
    let mut rng = Pcg32::new(13);
    let mut misses = 0;
    for _ in 0..2000 {
        let o = rng.in_box(Vec3::splat(-20.0), Vec3::splat(20.0));
        let d = rng.unit_vector();
        if b.contains(o) {
            continue;
        }
        match ref_exit(&b, o.as_dvec3(), d.as_dvec3()) {
            None => {
                misses += 1;
                assert_eq!(env.radiance(o, d), map.lookup(d));
            }
            Some(exit) => {
                let want = ref_lookup(&map, exit - b.center().as_dvec3(), 0.0);
                let q = exit - b.center().as_dvec3();
                if q.y.abs() < 0.995 * q.length() {
                    assert!(close(env.radiance(o, d), want, 1e-3));
                }
            }
        }
    }
    assert!(misses > 100);
    // Axis-parallel rays beside the box, and one pointing away from it.
    let beside = Vec3::new(b.max.x + 1.0, 1.0, 0.0);
    assert_eq!(env.radiance(beside, Vec3::Z), map.lookup(Vec3::Z));
    assert_eq!(
        env.radiance(Vec3::new(0.0, 1.0, 50.0), Vec3::Z),
        map.lookup(Vec3::Z)
    );
}

// ---------------------------------------------------------- the other kinds

#[test]
fn sky_constant_and_degenerate_inputs() {
    let mut rng = Pcg32::new(14);
    let c = Vec3::new(0.5, 1.0, 2.0);
    for _ in 0..500 {
        let (o, d) = (
            rng.in_box(Vec3::splat(-5.0), Vec3::splat(5.0)),
            rng.unit_vector(),
        );
        let want = raykit_render::sky::sky(d * 4.0 / (d * 4.0).length());
        let got = Environment::Sky.radiance(o, d * 4.0);
        assert!((got - want).abs().max_element() < 1e-6, "{got} vs {want}");
        assert_eq!(Environment::Constant(c).radiance(o, d), c);
    }
    let map = Arc::new(random_map(8, 4, 1));
    let (env, _) = box_env(&map);
    for e in [Environment::Sky, Environment::map(map.clone()), env] {
        assert_eq!(e.radiance(Vec3::ZERO, Vec3::ZERO), Vec3::ZERO);
        assert_eq!(e.radiance(Vec3::ZERO, Vec3::NAN), Vec3::ZERO);
        assert!(e.radiance(Vec3::NAN, Vec3::X).is_finite());
        assert!(e.radiance(Vec3::splat(f32::INFINITY), Vec3::X).is_finite());
        assert!(e
            .radiance(Vec3::ZERO, Vec3::new(1e-45, 0.0, 0.0))
            .is_finite());
        assert!(!e.describe().is_empty());
    }
    assert!(matches!(
        Environment::env_box(map.clone(), Aabb::EMPTY, 2.0),
        Environment::Map { .. }
    ));
    let described = Environment::env_box(map, Aabb::new(Vec3::ZERO, Vec3::ONE), 2.0).describe();
    assert!(
        described.contains("environment box") && described.contains("8x4"),
        "{described}"
    );
}

// ---------------------------------------------------------------------- .hdr

#[test]
fn hdr_round_trip_within_rgbe_precision() {
    use image::codecs::hdr::HdrEncoder;
    let (w, h) = (37usize, 19usize);
    let mut rng = Pcg32::new(15);
    let px: Vec<image::Rgb<f32>> = (0..w * h)
        .map(|_| {
            let scale = 2f32.powf(rng.range_f32(-10.0, 12.0));
            image::Rgb([
                rng.next_f32() * scale,
                rng.next_f32() * scale,
                rng.next_f32() * scale,
            ])
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("round.hdr");
    let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    HdrEncoder::new(file).encode(&px, w, h).unwrap();
    let map = EquirectMap::load(&path).unwrap();
    assert_eq!((map.width(), map.height(), map.clamped_texels()), (w, h, 0));
    for (k, p) in px.iter().enumerate() {
        let got = map.texel(k % w, k / w).unwrap();
        // RGBE: an 8-bit mantissa per channel under the largest channel's exponent.
        let tol = p.0.iter().cloned().fold(0.0f32, f32::max) / 128.0;
        for c in 0..3 {
            assert!(
                (got[c] - p.0[c]).abs() <= tol,
                "texel {k}: {got:?} vs {:?}",
                p.0
            );
        }
    }
}
