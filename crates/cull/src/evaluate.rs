//! The ground-truth evaluator of issue 6 (point 4): which triangles of a
//! model are truly visible from outside, by ray casting alone (no grid), and
//! how a culling result compares with it.
//!
//! Two kinds of evidence, both through the given [`Accel`]:
//! - **rays from the surface**: per triangle, sample points on it (both
//!   faces, a hair off the surface along ± its normal) and random directions
//!   in that face's hemisphere; the triangle is visible when some ray meets
//!   nothing (so it leaves the model's bounding sphere);
//! - **renders of triangle ids**: from viewpoints on a sphere around the
//!   model (a Fibonacci sphere, at twice the bounding radius), a small image
//!   of primary rays covering the bounding sphere; every triangle hit is
//!   visible.
//!
//! Sample counts (points, directions, viewpoints) are doubled each round
//! with fresh random samples, and the labels of all rounds are united, until
//! a round finds no new visible triangle (or the rounds run out). The result
//! is evidence, not proof: a triangle seen only through a very small solid
//! angle may be missed (then labelled hidden).

use raykit_core::rng::Pcg32;
use raykit_core::{Accel, Ray, TriangleMesh, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Settings of [`evaluate`]: the counts of the first round (each later
/// round doubles them) and the cap on rounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvalOptions {
    /// Sample points per triangle in the first round.
    pub points: u32,
    /// Random directions per sample point and face in the first round.
    pub directions: u32,
    /// Viewpoints of the renders in the first round (0: no renders).
    pub viewpoints: usize,
    /// Side of each render in pixels.
    pub image: usize,
    /// Most rounds (at least 2, so that two rounds can be compared).
    pub max_rounds: usize,
    /// Seed of the random samples.
    pub seed: u64,
}

impl Default for EvalOptions {
    fn default() -> Self {
        EvalOptions {
            points: 4,
            directions: 16,
            viewpoints: 10_000,
            image: 64,
            max_rounds: 4,
            seed: 0x0006_e7a1,
        }
    }
}

/// What [`evaluate`] found.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct GroundTruth {
    /// Per triangle: true when some ray showed it from outside.
    #[serde(skip)]
    pub visible: Vec<bool>,
    /// Triangles labelled visible.
    pub visible_count: usize,
    /// Rounds run.
    pub rounds: usize,
    /// Triangles newly found visible by the last round (0 when converged).
    pub last_change: usize,
    /// True when the last round changed nothing.
    pub converged: bool,
    /// Sample points per triangle of the last round.
    pub points: u32,
    /// Directions per point and face of the last round.
    pub directions: u32,
    /// Viewpoints of the last round.
    pub viewpoints: usize,
    /// Side of the renders in pixels.
    pub image: usize,
    /// Rays cast, all rounds together.
    pub rays: u64,
    /// Triangles of zero area (no face to sample; labelled hidden unless a
    /// render hits them).
    pub degenerate: usize,
    /// Seconds, all rounds together.
    pub seconds: f64,
}

/// The ground truth of `mesh`'s visibility from outside, by rays through
/// `accel` (built on `mesh`).
pub fn evaluate(mesh: &TriangleMesh, accel: &dyn Accel, options: &EvalOptions) -> GroundTruth {
    let clock = Instant::now();
    let n = mesh.num_triangles();
    let mut truth = GroundTruth {
        visible: vec![false; n],
        image: options.image,
        ..Default::default()
    };
    if n == 0 {
        truth.converged = true;
        return truth;
    }
    truth.degenerate = (0..n)
        .filter(|&t| mesh.face_normal(t).normalize_or_zero() == Vec3::ZERO)
        .count();
    let bounds = mesh.bounds();
    let centre = (bounds.min + bounds.max) * 0.5;
    let radius = ((bounds.max - bounds.min).length() * 0.5).max(1e-20);
    let max_rounds = options.max_rounds.max(2);
    for round in 0..max_rounds {
        let scale = 1u32 << round;
        let points = options.points.max(1).saturating_mul(scale);
        let directions = options.directions.max(1).saturating_mul(scale);
        let viewpoints = options.viewpoints.saturating_mul(scale as usize);
        let seed = options.seed.wrapping_add(round as u64 * 0x9e37_79b9);

        // Rays from the surface, for the triangles not yet seen.
        let from_surface: Vec<usize> = truth
            .visible
            .par_iter()
            .enumerate()
            .with_min_len(64)
            .filter(|(t, v)| !**v && seen_from_surface(mesh, accel, *t, points, directions, seed))
            .map(|(t, _)| t)
            .collect();
        let unseen = truth.visible.iter().filter(|&&v| !v).count() as u64;
        truth.rays += unseen * u64::from(points) * 2 * u64::from(directions);

        // Renders of triangle ids.
        let hit: Vec<AtomicBool> = (0..n).map(|_| AtomicBool::new(false)).collect();
        (0..viewpoints)
            .into_par_iter()
            .with_min_len(4)
            .for_each(|i| {
                render(
                    accel,
                    centre,
                    radius,
                    fibonacci(i, viewpoints),
                    options.image,
                    &hit,
                )
            });
        truth.rays += (viewpoints * options.image * options.image) as u64;

        let mut change = 0;
        for t in from_surface {
            if !truth.visible[t] {
                truth.visible[t] = true;
                change += 1;
            }
        }
        for (t, h) in hit.iter().enumerate() {
            if h.load(Ordering::Relaxed) && !truth.visible[t] {
                truth.visible[t] = true;
                change += 1;
            }
        }
        truth.rounds = round + 1;
        truth.last_change = change;
        truth.points = points;
        truth.directions = directions;
        truth.viewpoints = viewpoints;
        if round > 0 && change == 0 {
            truth.converged = true;
            break;
        }
    }
    truth.visible_count = truth.visible.iter().filter(|&&v| v).count();
    truth.seconds = clock.elapsed().as_secs_f64();
    truth
}

/// Point `i` of the `n`-point Fibonacci sphere (unit vectors, evenly spread).
pub fn fibonacci(i: usize, n: usize) -> Vec3 {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let z = 1.0 - (2.0 * i as f64 + 1.0) / n.max(1) as f64;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = golden * i as f64;
    Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
}

/// One render: from `centre + 2 radius · dir`, an `image × image` pinhole
/// image looking at `centre` whose view cone just holds the bounding sphere;
/// marks the triangles hit.
fn render(
    accel: &dyn Accel,
    centre: Vec3,
    radius: f32,
    dir: Vec3,
    image: usize,
    hit: &[AtomicBool],
) {
    let eye = centre + dir * (2.0 * radius);
    let forward = -dir;
    let helper = if forward.z.abs() < 0.9 {
        Vec3::Z
    } else {
        Vec3::X
    };
    let right = forward.cross(helper).normalize();
    let up = right.cross(forward);
    // Half-angle asin(1/2) = 30°: the cone tangent to the bounding sphere;
    // the square image holds the cone's disc.
    let half = 30f32.to_radians().tan();
    let image = image.max(1);
    for j in 0..image {
        for i in 0..image {
            let u = ((i as f32 + 0.5) / image as f32 * 2.0 - 1.0) * half;
            let v = ((j as f32 + 0.5) / image as f32 * 2.0 - 1.0) * half;
            let d = (forward + u * right + v * up).normalize();
            if let Some(h) = accel.intersect(&Ray::new(eye, d)) {
                if let Some(slot) = hit.get(h.prim as usize) {
                    if !slot.load(Ordering::Relaxed) {
                        slot.store(true, Ordering::Relaxed);
                    }
                }
            }
        }
    }
}

/// True when some of `points` sample points on triangle `t`, on either face,
/// with `directions` random directions of that face's hemisphere, casts a
/// ray that meets no other triangle.
fn seen_from_surface(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    t: usize,
    points: u32,
    directions: u32,
    seed: u64,
) -> bool {
    let [a, b, c] = mesh.triangle(t);
    let n = (b - a).cross(c - a).normalize_or_zero();
    if n == Vec3::ZERO {
        return false;
    }
    let scale = a.abs().max(b.abs()).max(c.abs()).max_element().max(1e-30);
    let offset = scale * 1e-5;
    let mut rng = Pcg32::with_stream(seed, t as u64);
    for k in 0..points {
        let (mut u, mut v) = if k == 0 {
            (1.0 / 3.0, 1.0 / 3.0)
        } else {
            (rng.next_f32(), rng.next_f32())
        };
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p = a + u * (b - a) + v * (c - a);
        for face in [n, -n] {
            let o = p + face * offset;
            for _ in 0..directions {
                let mut d = rng.unit_vector();
                if d.dot(face) < 0.0 {
                    d = -d;
                }
                if escapes(accel, o, d, t as u32) {
                    return true;
                }
            }
        }
    }
    false
}

/// True when the ray meets no triangle but `own` (hits on `own`, from
/// grazing directions, are stepped over).
fn escapes(accel: &dyn Accel, o: Vec3, d: Vec3, own: u32) -> bool {
    let mut tnear = 0.0f32;
    for _ in 0..4 {
        match accel.intersect(&Ray::segment(o, d, tnear, f32::INFINITY)) {
            None => return true,
            Some(h) if h.prim == own => tnear = h.t.next_up(),
            Some(_) => return false,
        }
    }
    false
}

/// Most triangle ids listed in [`EvalReport::false_removal_ids`] and
/// [`EvalReport::missed_removal_ids`].
pub const LISTED_IDS: usize = 20;

/// A culling result (`kept`, per triangle) against the ground truth.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct EvalReport {
    /// Triangles in the model.
    pub triangles: usize,
    /// Triangles removed.
    pub triangles_removed: usize,
    /// Fraction of triangles removed.
    pub removed_fraction_triangles: f64,
    /// Total surface area.
    pub area: f64,
    /// Area removed.
    pub area_removed: f64,
    /// Fraction of the area removed.
    pub removed_fraction_area: f64,
    /// Parts in the model (one when it has none).
    pub parts: usize,
    /// Parts with every triangle removed.
    pub parts_removed: usize,
    /// Fraction of parts removed.
    pub removed_fraction_parts: f64,
    /// Triangles the ground truth labels visible.
    pub truly_visible: usize,
    /// Triangles the ground truth labels hidden.
    pub truly_hidden: usize,
    /// False removals: truly visible but removed.
    pub false_removals: usize,
    /// Area of the false removals.
    pub false_removal_area: f64,
    /// The first few falsely removed triangles.
    pub false_removal_ids: Vec<usize>,
    /// Missed removals: truly hidden but kept.
    pub missed_removals: usize,
    /// Area of the missed removals.
    pub missed_removal_area: f64,
    /// Missed removals over truly hidden triangles (0 when none is hidden).
    pub missed_fraction: f64,
    /// The first few missed triangles.
    pub missed_removal_ids: Vec<usize>,
}

/// Compare the kept triangles `kept` with the ground truth `truth` of `mesh`.
pub fn compare(truth: &GroundTruth, kept: &[bool], mesh: &TriangleMesh) -> EvalReport {
    let n = mesh.num_triangles();
    assert_eq!(kept.len(), n, "one kept flag per triangle");
    assert_eq!(truth.visible.len(), n, "ground truth of this mesh");
    let area = |t: usize| {
        let [a, b, c] = mesh.triangle(t);
        0.5 * f64::from((b - a).cross(c - a).length())
    };
    let mut r = EvalReport {
        triangles: n,
        ..Default::default()
    };
    let parts = mesh
        .parts
        .len()
        .max(
            (0..n)
                .map(|t| mesh.part_of(t) as usize + 1)
                .max()
                .unwrap_or(0),
        )
        .max(usize::from(n > 0));
    let mut part_kept = vec![false; parts];
    for t in 0..n {
        let at = area(t);
        r.area += at;
        if kept[t] {
            part_kept[mesh.part_of(t) as usize] = true;
        } else {
            r.triangles_removed += 1;
            r.area_removed += at;
        }
        if truth.visible[t] {
            r.truly_visible += 1;
            if !kept[t] {
                r.false_removals += 1;
                r.false_removal_area += at;
                if r.false_removal_ids.len() < LISTED_IDS {
                    r.false_removal_ids.push(t);
                }
            }
        } else {
            r.truly_hidden += 1;
            if kept[t] {
                r.missed_removals += 1;
                r.missed_removal_area += at;
                if r.missed_removal_ids.len() < LISTED_IDS {
                    r.missed_removal_ids.push(t);
                }
            }
        }
    }
    let frac = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
    r.parts = parts;
    r.parts_removed = part_kept.iter().filter(|&&k| !k).count();
    r.removed_fraction_triangles = frac(r.triangles_removed as f64, n as f64);
    r.removed_fraction_area = frac(r.area_removed, r.area);
    r.removed_fraction_parts = frac(r.parts_removed as f64, parts as f64);
    r.missed_fraction = frac(r.missed_removals as f64, r.truly_hidden as f64);
    r
}
