//! `raykit query` as a user runs it on the Stanford bunny: every value of
//! every output file checked against a brute force over all triangles in
//! f64 written here (Ericson's closest point, the solid-angle sum of the
//! winding number, Möller–Trumbore for crossings), and bad input refused
//! with the file and byte offset, never a panic.

use raykit_core::TriangleMesh;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "support/cli.rs"]
mod cli;
use cli::{data, s};

type V = [f64; 3];

fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: V, s: f64) -> V {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V, b: V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: V) -> f64 {
    dot(a, a).sqrt()
}

fn raykit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raykit"))
        .args(args)
        .output()
        .expect("the raykit binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn bunny() -> PathBuf {
    data("meshes/bunny_3674.obj")
}

/// The mesh's triangles in f64, loaded as the binary loads them.
fn triangles(path: &Path) -> Vec<[V; 3]> {
    let mesh: TriangleMesh = raykit_io::load(path).expect("the bunny loads").mesh;
    (0..mesh.num_triangles())
        .map(|t| {
            mesh.triangle(t)
                .map(|c| [c.x as f64, c.y as f64, c.z as f64])
        })
        .collect()
}

/// A small deterministic generator (xorshift64*), uniform in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The mesh's bounding box grown by a quarter of its size on every side.
fn grown_box(tris: &[[V; 3]]) -> (V, V) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in tris {
        for c in t {
            for k in 0..3 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
    }
    let e = scale(sub(hi, lo), 0.25);
    (sub(lo, e), add(hi, e))
}

fn random_points(rng: &mut Rng, n: usize, (lo, hi): (V, V)) -> Vec<[f32; 3]> {
    (0..n)
        .map(|_| std::array::from_fn(|k| (lo[k] + rng.next() * (hi[k] - lo[k])) as f32))
        .collect()
}

fn write_f32s(path: &Path, values: impl IntoIterator<Item = f32>) {
    let bytes: Vec<u8> = values.into_iter().flat_map(f32::to_le_bytes).collect();
    std::fs::write(path, bytes).unwrap();
}

fn read_f32(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes(b[i..i + 4].try_into().unwrap())
}
fn read_u32(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes(b[i..i + 4].try_into().unwrap())
}

/// Ericson's closest point of triangle `(a, b, c)` to `p` (Real-Time
/// Collision Detection, 2005, 5.1.5), in f64.
fn closest_on_triangle(p: V, [a, b, c]: [V; 3]) -> V {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return add(a, scale(ab, d1 / (d1 - d3)));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return add(a, scale(ac, d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return add(b, scale(sub(c, b), w));
    }
    let denom = 1.0 / (va + vb + vc);
    add(a, add(scale(ab, vb * denom), scale(ac, vc * denom)))
}

fn distance_to(p: V, t: [V; 3]) -> f64 {
    norm(sub(p, closest_on_triangle(p, t)))
}

/// Distance from `p` to the nearest triangle, over all of them.
fn brute_distance(tris: &[[V; 3]], p: V) -> f64 {
    tris.iter()
        .map(|&t| distance_to(p, t))
        .fold(f64::INFINITY, f64::min)
}

/// Generalized winding number: the sum of the triangles' signed solid
/// angles (Van Oosterom and Strackee 1983) over 4π.
fn brute_winding(tris: &[[V; 3]], p: V) -> f64 {
    let mut w = 0.0;
    for t in tris {
        let (a, b, c) = (sub(t[0], p), sub(t[1], p), sub(t[2], p));
        let (la, lb, lc) = (norm(a), norm(b), norm(c));
        let num = dot(a, cross(b, c));
        let den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
        w += 2.0 * num.atan2(den);
    }
    w / (4.0 * std::f64::consts::PI)
}

/// Möller–Trumbore in f64: `(t, smallest barycentric)` of the ray's
/// crossing of the triangle's plane inside or near the triangle.
fn crossing(o: V, d: V, [a, b, c]: [V; 3]) -> Option<(f64, f64)> {
    let (e1, e2) = (sub(b, a), sub(c, a));
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if det == 0.0 {
        return None;
    }
    let tv = sub(o, a);
    let u = dot(tv, pv) / det;
    let qv = cross(tv, e1);
    let v = dot(d, qv) / det;
    let t = dot(e2, qv) / det;
    Some((t, u.min(v).min(1.0 - u - v)))
}

/// A crossing: `t` and the triangle.
type Crossing = (f64, u32);

struct TestRay {
    o: V,
    d: V,
    tnear: f64,
    tfar: f64,
}

/// Triangles the ray surely crosses (well inside, `t` well within the
/// interval) and those it may cross within rounding (edges, ends).
fn brute_crossings(tris: &[[V; 3]], r: &TestRay) -> (Vec<Crossing>, Vec<Crossing>) {
    let (mut sure, mut maybe) = (Vec::new(), Vec::new());
    let eps = 1e-4;
    let tol_t = 1e-4 * norm(r.d).recip() + 1e-4 * r.tfar.min(1e6).abs();
    for (i, &t) in tris.iter().enumerate() {
        let Some((th, bmin)) = crossing(r.o, r.d, t) else {
            continue;
        };
        if bmin > -eps && th >= r.tnear - tol_t && th <= r.tfar + tol_t {
            maybe.push((th, i as u32));
            if bmin > eps && th > r.tnear + tol_t && th < r.tfar - tol_t {
                sure.push((th, i as u32));
            }
        }
    }
    (sure, maybe)
}

fn stats_line(o: &Output) -> serde_json::Value {
    let text = stderr(o);
    let line = text.lines().last().expect("a statistics line");
    serde_json::from_str(line).unwrap_or_else(|e| panic!("not JSON ({e}): {line}"))
}

#[test]
fn point_queries_match_brute_force() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = bunny();
    let tris = triangles(&mesh);
    let bounds = grown_box(&tris);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut pts = random_points(&mut rng, 300, bounds);
    // Points on and very near the surface: triangle centroids, nudged.
    for t in tris.iter().step_by(37) {
        let c = scale(add(t[0], add(t[1], t[2])), 1.0 / 3.0);
        pts.push(c.map(|x| (x + 1e-3 * (rng.next() - 0.5)) as f32));
    }
    let points = dir.path().join("p.bin");
    write_f32s(&points, pts.iter().flatten().copied());
    let diag = norm(sub(bounds.1, bounds.0));
    let dist: Vec<f64> = pts
        .iter()
        .map(|p| brute_distance(&tris, p.map(f64::from)))
        .collect();
    let wind: Vec<f64> = pts
        .iter()
        .map(|p| brute_winding(&tris, p.map(f64::from)))
        .collect();
    let tol = 1e-5 * diag;

    let run = |query: &str| -> Vec<u8> {
        let out = dir.path().join(format!("{query}.bin"));
        let o = raykit(&[
            "query",
            query,
            "--mesh",
            s(&mesh),
            "--points",
            s(&points),
            "--out",
            s(&out),
            "--threads",
            "2",
        ]);
        assert!(o.status.success(), "{query}: {}", stderr(&o));
        let st = stats_line(&o);
        assert_eq!(st["query"], query);
        assert_eq!(st["points"], pts.len());
        for k in ["build_ms", "query_ms", "per_s"] {
            assert!(st[k].as_f64().is_some(), "{query}: no {k} in {st}");
        }
        std::fs::read(out).unwrap()
    };

    let d = run("distance");
    assert_eq!(d.len(), 4 * pts.len());
    for (i, want) in dist.iter().enumerate() {
        let got = read_f32(&d, 4 * i) as f64;
        assert!(
            (got - want).abs() <= tol,
            "point {i}: distance {got}, brute {want}"
        );
    }

    // Inside where the exact winding number is at least 1/2; the fast
    // approximation may differ only where the exact number is near 1/2.
    let inside = run("inside");
    assert_eq!(inside.len(), pts.len());
    let mut decided = 0;
    for (i, &w) in wind.iter().enumerate() {
        assert!(inside[i] <= 1, "point {i}: byte {}", inside[i]);
        if (w - 0.5).abs() > 0.05 {
            assert_eq!(inside[i] == 1, w >= 0.5, "point {i}: winding {w}");
            decided += 1;
        }
    }
    assert!(
        decided * 10 >= pts.len() * 9,
        "too few clear cases: {decided}"
    );
    assert!(inside.contains(&1) && inside.contains(&0));

    let sd = run("signed-distance");
    for (i, (&w, want)) in wind.iter().zip(&dist).enumerate() {
        let got = read_f32(&sd, 4 * i) as f64;
        assert!(
            (got.abs() - want).abs() <= tol,
            "point {i}: {got} vs {want}"
        );
        if (w - 0.5).abs() > 0.05 && *want > tol {
            assert_eq!(got < 0.0, w >= 0.5, "point {i}: {got}, winding {w}");
        }
    }

    let c = run("closest");
    assert_eq!(c.len(), 20 * pts.len());
    for (i, (p, want)) in pts.iter().zip(&dist).enumerate() {
        let r = 20 * i;
        let q: V = std::array::from_fn(|k| read_f32(&c, r + 4 * k) as f64);
        let got = read_f32(&c, r + 12) as f64;
        let prim = read_u32(&c, r + 16) as usize;
        let p = p.map(f64::from);
        assert!((got - want).abs() <= tol, "point {i}: {got} vs {want}");
        assert!(prim < tris.len(), "point {i}: triangle {prim}");
        // The point lies on its triangle, at the stated distance, and that
        // triangle is a nearest one.
        assert!(distance_to(q, tris[prim]) <= tol, "point {i}");
        assert!((norm(sub(q, p)) - got).abs() <= tol, "point {i}");
        assert!(
            (distance_to(p, tris[prim]) - want).abs() <= tol,
            "point {i}"
        );
    }
}

#[test]
fn ray_queries_match_brute_force() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = bunny();
    let tris = triangles(&mesh);
    let bounds = grown_box(&tris);
    let (lo, hi) = bounds;
    let centre = scale(add(lo, hi), 0.5);
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut rays = Vec::new();
    for i in 0..300 {
        let o: V = std::array::from_fn(|k| lo[k] + rng.next() * (hi[k] - lo[k]));
        // Half aimed near the centre (many crossings), half anywhere; not
        // unit length, some with a finite interval.
        let d: V = if i % 2 == 0 {
            let aim: V =
                std::array::from_fn(|k| centre[k] + 0.2 * (rng.next() - 0.5) * (hi[k] - lo[k]));
            scale(sub(aim, o), 0.5 + rng.next())
        } else {
            std::array::from_fn(|_| rng.next() - 0.5)
        };
        // Some with a finite interval, some over the whole line.
        let (tnear, tfar) = if i % 3 == 0 {
            (0.1 * rng.next(), 0.5 + rng.next())
        } else if i % 5 == 1 {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (0.0, f64::INFINITY)
        };
        let o = o.map(|x| x as f32 as f64);
        let d = d.map(|x| x as f32 as f64);
        rays.push(TestRay {
            o,
            d,
            tnear: tnear as f32 as f64,
            tfar: tfar as f32 as f64,
        });
    }
    let ray_file = dir.path().join("r.bin");
    write_f32s(
        &ray_file,
        rays.iter().flat_map(|r| {
            [
                r.o[0], r.o[1], r.o[2], r.d[0], r.d[1], r.d[2], r.tnear, r.tfar,
            ]
            .map(|x| x as f32)
        }),
    );
    let brute: Vec<_> = rays.iter().map(|r| brute_crossings(&tris, r)).collect();

    let run_with_stats = |args: &[&str]| -> (Vec<u8>, serde_json::Value) {
        let out = dir.path().join("o.bin");
        let mut all = vec!["query"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["--mesh", s(&mesh), "--rays", s(&ray_file), "--out", s(&out)]);
        let o = raykit(&all);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        let st = stats_line(&o);
        assert_eq!(st["rays"], rays.len());
        assert!(st["per_s"].as_f64().is_some(), "{st}");
        (std::fs::read(out).unwrap(), st)
    };
    let run = |args: &[&str]| run_with_stats(args).0;

    let counts = run(&["count"]);
    assert_eq!(counts.len(), 4 * rays.len());
    let mut total = 0;
    for (i, (sure, maybe)) in brute.iter().enumerate() {
        let n = read_u32(&counts, 4 * i) as usize;
        assert!(
            sure.len() <= n && n <= maybe.len(),
            "ray {i}: {n} crossings, brute force {}..={}",
            sure.len(),
            maybe.len()
        );
        total += n;
    }
    assert!(
        total > rays.len(),
        "the rays should cross the bunny: {total}"
    );

    let cap = 3;
    let (lists, st) = run_with_stats(&["all-hits", "--max-hits", &cap.to_string()]);
    // The rays cut to the cap are those with more crossings than it.
    let over = (0..rays.len())
        .filter(|&i| read_u32(&counts, 4 * i) as usize > cap)
        .count();
    assert!(over > 0, "some rays should cross more than {cap} times");
    assert_eq!(st["truncated"], over, "{st}");
    // --max-hits 0 keeps every hit: each list as long as the ray's count.
    let (every, st) = run_with_stats(&["all-hits", "--max-hits", "0"]);
    assert_eq!(st["truncated"], 0, "{st}");
    let mut at = 0;
    for i in 0..rays.len() {
        let n = read_u32(&every, at);
        assert_eq!(n, read_u32(&counts, 4 * i), "ray {i}");
        at += 4 + 8 * n as usize;
    }
    assert_eq!(at, every.len());
    let mut at = 0;
    for (i, (r, (sure, maybe))) in rays.iter().zip(&brute).enumerate() {
        let n = read_u32(&lists, at) as usize;
        at += 4;
        let want_lo = sure.len().min(cap);
        assert!(
            want_lo <= n && n <= maybe.len().min(cap),
            "ray {i}: {n} hits, brute force {}..={} (cap {cap})",
            sure.len(),
            maybe.len()
        );
        let mut last = f64::NEG_INFINITY;
        let mut got = Vec::new();
        for _ in 0..n {
            let t = read_f32(&lists, at) as f64;
            let prim = read_u32(&lists, at + 4);
            at += 8;
            let m = maybe.iter().find(|h| h.1 == prim);
            let (bt, _) = m.unwrap_or_else(|| panic!("ray {i}: triangle {prim} is not crossed"));
            let tol = 1e-4 * (1.0 + bt.abs()) / norm(r.d).min(1.0);
            assert!((t - bt).abs() <= tol, "ray {i}: t {t} vs {bt}");
            assert!(t >= last, "ray {i}: hits not sorted");
            last = t;
            got.push((t, prim));
        }
        // Every sure hit nearer than the last kept one is kept.
        if n == cap {
            for &(bt, prim) in sure {
                if bt < last - 1e-4 * (1.0 + last.abs()) {
                    assert!(got.iter().any(|g| g.1 == prim), "ray {i}: missed {prim}");
                }
            }
        } else {
            for &(_, prim) in sure {
                assert!(got.iter().any(|g| g.1 == prim), "ray {i}: missed {prim}");
            }
        }
    }
    assert_eq!(at, lists.len(), "trailing bytes in the all-hits file");
}

#[test]
fn bad_points_are_refused_or_answered_with_nan() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = bunny();
    let points = dir.path().join("p.bin");
    let out = dir.path().join("o.bin");
    // Two whole points and 5 bytes of a third.
    let mut bytes: Vec<u8> = [0.1f32, 0.2, 0.3, 1.0, 2.0, 3.0]
        .into_iter()
        .flat_map(f32::to_le_bytes)
        .collect();
    bytes.extend_from_slice(&[0u8; 5]);
    std::fs::write(&points, &bytes).unwrap();
    let args = |q: &'static str| {
        [
            "query",
            q,
            "--mesh",
            s(&mesh),
            "--points",
            s(&points),
            "--out",
            s(&out),
        ]
        .map(str::to_owned)
    };
    let o = raykit(&args("distance").each_ref().map(String::as_str));
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(!e.contains("panicked"), "{e}");
    assert!(e.contains("p.bin") && e.contains("24"), "{e}");
    assert!(!out.exists(), "no output on error");

    // A NaN point: NaN distances, no answer for the closest point, outside.
    write_f32s(&points, [f32::NAN, 0.0, 0.0, 0.0, 0.1, 0.0]);
    let tris = triangles(&mesh);
    let want = brute_distance(&tris, [0.0, 0.1, 0.0]);
    for q in ["distance", "signed-distance"] {
        let o = raykit(&args(q).each_ref().map(String::as_str));
        assert!(o.status.success(), "{}", stderr(&o));
        let d = std::fs::read(&out).unwrap();
        assert!(read_f32(&d, 0).is_nan(), "{q}");
        assert!((read_f32(&d, 4).abs() as f64 - want).abs() < 1e-4, "{q}");
    }
    let o = raykit(&args("closest").each_ref().map(String::as_str));
    assert!(o.status.success(), "{}", stderr(&o));
    let c = std::fs::read(&out).unwrap();
    assert!((0..4).all(|k| read_f32(&c, 4 * k).is_nan()));
    assert_eq!(read_u32(&c, 16), u32::MAX);
    let o = raykit(&args("inside").each_ref().map(String::as_str));
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(&out).unwrap()[0], 0);

    // Rays where points are wanted, and a truncated ray file.
    let o = raykit(&[
        "query",
        "count",
        "--mesh",
        s(&mesh),
        "--points",
        s(&points),
        "--out",
        s(&out),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--rays"), "{}", stderr(&o));
    let rays = dir.path().join("r.bin");
    std::fs::write(&rays, [0u8; 40]).unwrap();
    let o = raykit(&[
        "query",
        "count",
        "--mesh",
        s(&mesh),
        "--rays",
        s(&rays),
        "--out",
        s(&out),
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        !e.contains("panicked") && e.contains("r.bin") && e.contains("32"),
        "{e}"
    );
}

#[test]
fn outputs_are_checked_before_the_work_and_flags_that_do_not_apply_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = bunny();
    let points = dir.path().join("p.bin");
    write_f32s(&points, [0.0f32; 6]);
    // `query distance` from MESH to OUT with EXTRA arguments, which fails.
    let refused = |mesh: &str, out: &Path, extra: &[&str]| {
        let mut all = vec!["query", "distance", "--mesh", mesh, "--points", s(&points)];
        all.extend_from_slice(&["--out", s(out)]);
        all.extend_from_slice(extra);
        let o = raykit(&all);
        assert!(!o.status.success(), "{all:?} should fail");
        stderr(&o)
    };
    // A missing output folder is named before anything is loaded.
    let missing = dir.path().join("nowhere").join("o.bin");
    let e = refused(s(&mesh), &missing, &[]);
    assert!(e.contains("nowhere") && e.contains("does not exist"), "{e}");
    // --max-hits is for all-hits only.
    let out = dir.path().join("o.bin");
    let e = refused(s(&mesh), &out, &["--max-hits", "5"]);
    assert!(e.contains("--max-hits") && e.contains("all-hits"), "{e}");
    assert!(!out.exists());
    // A missing mesh is said once, not with its cause repeated.
    let e = refused("no-such-mesh.obj", &out, &[]);
    assert!(e.contains("no-such-mesh.obj"), "{e}");
    let cause = "No such file or directory";
    assert_eq!(e.matches(cause).count(), 1, "{e}");
    // A thread count no machine has is refused at once, not attempted.
    let e = refused(s(&mesh), &out, &["--threads", "100000"]);
    assert!(
        e.contains("--threads 100000") && e.contains("at most 4096"),
        "{e}"
    );
}
