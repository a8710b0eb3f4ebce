//! `raykit trace` and `raykit query` on several meshes (an instanced
//! scene), run as a user runs them: hits name geometry and instance; the
//! 2CylinderEngine traced with its instancing kept gives the flattened
//! load's answers ray for ray; two meshes against an `f64` brute force
//! written here; the single-mesh hit file keeps its 8-byte records.

use raykit_core::rng::Pcg32;
use raykit_core::tri::reference::{edge_distance_f64, intersect_f64, plane_t_f64};
use raykit_core::{Ray, TriangleMesh, Vec3};
use std::path::Path;
use std::process::Output;

#[path = "support/cli.rs"]
mod cli;
use cli::{data, raykit, s, text};

fn stderr(o: &Output) -> String {
    text(&o.stderr)
}

/// The JSON statistics line of a run.
fn stats(o: &Output) -> serde_json::Value {
    let line = stderr(o)
        .lines()
        .rfind(|l| l.starts_with('{'))
        .expect("a JSON line")
        .to_string();
    serde_json::from_str(&line).expect("valid JSON")
}

/// Rays from a sphere around `b` at points inside it, every fifth a segment.
fn rays_at(b: &raykit_core::Aabb, n: usize, seed: u64) -> Vec<Ray> {
    let (c, r) = (b.center(), b.extent().length());
    let mut rng = Pcg32::new(seed);
    (0..n)
        .map(|i| {
            let o = c + rng.unit_vector() * r;
            let d = rng.in_box(b.min, b.max) - o;
            if i % 5 == 0 {
                Ray::segment(o, d, 0.0, rng.range_f32(0.3, 1.0))
            } else {
                Ray::new(o, d)
            }
        })
        .collect()
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes(b[i..i + 4].try_into().unwrap())
}
fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes(b[i..i + 4].try_into().unwrap())
}

#[test]
fn engine_traced_with_its_instancing_equals_the_flattened_trace() {
    let engine = data("meshes/2CylinderEngine.glb");
    let dir = tempfile::tempdir().unwrap();
    let flat = raykit_io::load_mesh(&engine).unwrap();
    let rays = rays_at(&flat.bounds(), 4000, 5);
    let rays_path = dir.path().join("r.bin");
    raykit_io::write_rays(&rays_path, &rays).unwrap();
    let (hi, hf) = (dir.path().join("hi.bin"), dir.path().join("hf.bin"));
    let o = raykit(&[
        "trace",
        "--mesh",
        s(&engine),
        "--instanced",
        "--rays",
        s(&rays_path),
        "--out",
        s(&hi),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let st = stats(&o);
    let loaded = raykit_io::load_gltf_instances(&engine).unwrap();
    assert_eq!(st["geometries"], loaded.geometries.len());
    assert_eq!(st["instances"], loaded.instances.len());
    assert_eq!(st["stored_triangles"], loaded.stored_triangles());
    assert_eq!(st["instanced_triangles"], flat.num_triangles());
    let o = raykit(&[
        "trace",
        "--mesh",
        s(&engine),
        "--rays",
        s(&rays_path),
        "--out",
        s(&hf),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let inst = raykit_io::read_scene_hits(&hi).unwrap();
    let single = raykit_io::read_hits(&hf).unwrap();
    assert_eq!(std::fs::metadata(&hf).unwrap().len(), 8 * rays.len() as u64);
    assert_eq!(inst.len(), rays.len());
    let mut part_first = vec![usize::MAX; flat.parts.len()];
    for t in (0..flat.num_triangles()).rev() {
        part_first[flat.part_of(t) as usize] = t;
    }
    let (mut hits, mut differ) = (0, 0);
    for (k, (a, b)) in inst.iter().zip(&single).enumerate() {
        match b {
            None => {
                if a.1 != u32::MAX {
                    differ += 1;
                }
            }
            Some(b) => {
                let part = flat.part_of(b.prim as usize);
                let local = b.prim - part_first[part as usize] as u32;
                if (a.3, a.1) == (part, local) {
                    hits += 1;
                    assert!((a.0 - b.t).abs() <= 1e-3 * b.t, "ray {k}: {a:?} vs {b:?}");
                    assert_eq!(a.2, loaded.instances[part as usize].geometry, "ray {k}");
                } else {
                    // Another triangle at (almost) the same distance: CAD
                    // surfaces that touch, or a ray through a shared edge.
                    assert!(
                        a.0.is_finite() && (a.0 - b.t).abs() <= 1e-4 * b.t,
                        "ray {k}: {a:?} vs {b:?}"
                    );
                    differ += 1;
                }
            }
        }
    }
    assert!(hits > 2000, "{hits} hits");
    assert!(differ * 100 <= rays.len(), "{differ} rays differ");
}

/// One `f64` crossing of a ray with a mesh: `(t, geometry, prim, edge
/// margin)`.
type Crossing = (f64, u32, u32, f64);

/// Every `f64` crossing of `ray` with the meshes, sorted by `t`.
fn crossings(meshes: &[TriangleMesh], ray: &Ray) -> Vec<Crossing> {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir().as_dvec3());
    let mut out = Vec::new();
    for (g, m) in meshes.iter().enumerate() {
        for t in 0..m.num_triangles() {
            let [a, b, c] = m.triangle(t).map(|v| v.as_dvec3());
            if let Some((th, _, _)) = intersect_f64(a, b, c, o, d) {
                if th >= ray.tnear as f64 && th <= ray.tfar as f64 {
                    out.push((
                        th,
                        g as u32,
                        t as u32,
                        edge_distance_f64(a, b, c, o + d * th),
                    ));
                }
            }
        }
    }
    out.sort_by(|x, y| x.0.total_cmp(&y.0));
    out
}

/// Whether `ray` meets the plane of some triangle, within its reach, at a
/// point within `margin` (relative to the triangle's size) of the
/// triangle's boundary, inside or outside: there f32 tests with a
/// tolerance band and the f64 reference may disagree.
fn grazes(meshes: &[TriangleMesh], ray: &Ray, margin: f64) -> bool {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir().as_dvec3());
    meshes.iter().any(|m| {
        (0..m.num_triangles()).any(|t| {
            let [a, b, c] = m.triangle(t).map(|v| v.as_dvec3());
            plane_t_f64(a, b, c, o, d).is_some_and(|th| {
                th >= ray.tnear as f64
                    && th <= ray.tfar as f64
                    && edge_distance_f64(a, b, c, o + d * th) <= margin
            })
        })
    })
}

#[test]
fn two_meshes_trace_and_query_with_geometry_ids_as_brute_force() {
    let (bunny, teapot) = (data("meshes/bunny_3674.obj"), data("meshes/teapot_992.obj"));
    let meshes = [
        raykit_io::load_mesh(&bunny).unwrap(),
        raykit_io::load_mesh(&teapot).unwrap(),
    ];
    let bounds = meshes[0].bounds().union(meshes[1].bounds());
    let all = rays_at(&bounds, 1500, 7);
    // Rays clear of triangle edges, where f32 tests may disagree.
    let cases: Vec<(Ray, Vec<Crossing>)> = all
        .into_iter()
        .map(|r| {
            let c = crossings(&meshes, &r);
            (r, c)
        })
        .filter(|(r, c)| c.iter().all(|x| x.3 > 1e-4) && !grazes(&meshes, r, 1e-4))
        .collect();
    let rays: Vec<Ray> = cases.iter().map(|c| c.0).collect();
    let dir = tempfile::tempdir().unwrap();
    let rp = dir.path().join("r.bin");
    raykit_io::write_rays(&rp, &rays).unwrap();
    let (h, c, a) = (
        dir.path().join("h.bin"),
        dir.path().join("c.bin"),
        dir.path().join("a.bin"),
    );
    let two = ["--mesh", s(&bunny), "--mesh", s(&teapot)];
    let run = |cmd: &[&str], out: &Path| {
        let mut v: Vec<&str> = cmd.to_vec();
        v.extend(two);
        v.extend(["--rays", s(&rp), "--out", s(out)]);
        let o = raykit(&v);
        assert!(o.status.success(), "{}", stderr(&o));
        o
    };
    let o = run(&["trace"], &h);
    assert_eq!(stats(&o)["geometries"], 2);
    run(&["query", "count"], &c);
    run(&["query", "all-hits", "--max-hits", "1000"], &a);
    let hits = raykit_io::read_scene_hits(&h).unwrap();
    let counts = std::fs::read(&c).unwrap();
    let lists = std::fs::read(&a).unwrap();
    let (mut at, mut with_both) = (0, 0);
    for (k, (ray, want)) in cases.iter().enumerate() {
        let got = hits[k];
        match want.first() {
            None => assert_eq!(got.1, u32::MAX, "ray {k}"),
            Some(w) => {
                // The nearest crossing, or one within f32 rounding of it
                // (the teapot's overlapping spout and body meet at near-ties).
                let same = want
                    .iter()
                    .find(|x| (x.1, x.2) == (got.2, got.1))
                    .unwrap_or_else(|| panic!("ray {k}: {got:?} crosses no triangle it names"));
                assert!(
                    (same.0 - w.0).abs() <= 1e-5 * w.0,
                    "ray {k}: {got:?} vs {w:?}"
                );
                assert_eq!(got.3, got.2, "ray {k}: each file is one instance");
                assert!((got.0 as f64 - w.0).abs() <= 1e-4 * w.0, "ray {k}");
            }
        }
        assert_eq!(u32_at(&counts, 4 * k) as usize, want.len(), "ray {k}");
        let n = u32_at(&lists, at) as usize;
        at += 4;
        assert_eq!(n, want.len(), "ray {k}");
        let mut got_ids = Vec::new();
        for (i, w) in want.iter().enumerate().take(n) {
            let r = at + 16 * i;
            assert!((f32_at(&lists, r) as f64 - w.0).abs() <= 1e-4 * w.0);
            got_ids.push((u32_at(&lists, r + 8), u32_at(&lists, r + 4)));
        }
        at += 16 * n;
        let mut want_ids: Vec<_> = want.iter().map(|w| (w.1, w.2)).collect();
        got_ids.sort_unstable();
        want_ids.sort_unstable();
        assert_eq!(got_ids, want_ids, "ray {k}");
        with_both += (want.iter().any(|w| w.1 == 0) && want.iter().any(|w| w.1 == 1)) as usize;
        let _ = ray;
    }
    assert_eq!(at, lists.len());
    assert!(with_both > 10, "{with_both} rays cross both meshes");
}

#[test]
fn instanced_runs_refuse_what_they_cannot_answer() {
    let bunny = data("meshes/bunny_3674.obj");
    let dir = tempfile::tempdir().unwrap();
    let rp = dir.path().join("r.bin");
    raykit_io::write_rays(&rp, &[Ray::new(Vec3::ZERO, Vec3::X)]).unwrap();
    let pts = dir.path().join("p.bin");
    std::fs::write(&pts, [0u8; 12]).unwrap();
    let out = dir.path().join("o.bin");
    let b = s(&bunny);
    let o = raykit(&[
        "query",
        "distance",
        "--mesh",
        b,
        "--mesh",
        b,
        "--points",
        s(&pts),
        "--out",
        s(&out),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("answers on one mesh"), "{}", stderr(&o));
    let o = raykit(&[
        "trace",
        "--mesh",
        b,
        "--mesh",
        b,
        "--rays",
        s(&rp),
        "--out",
        s(&out),
        "--accel",
        "kd-stack",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("bvh8"), "{}", stderr(&o));
    let o = raykit(&[
        "trace",
        "--mesh",
        b,
        "--mesh",
        s(&dir.path().join("missing.obj")),
        "--rays",
        s(&rp),
        "--out",
        s(&out),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("missing.obj"), "{}", stderr(&o));
    assert!(!out.exists(), "a failed run leaves no output");
}
