//! The ground-truth evaluator: which triangles of a
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
//! Every escaping ray found is then shared with the neighbouring triangles
//! ([`crate::shared_escapes`]), which finds what is seen through narrow
//! openings far sooner than random sampling.
//!
//! Sample counts are doubled each round with fresh random samples — the rays
//! per triangle (points and viewpoints on odd rounds, directions per point
//! on even ones) — for [`EvalOptions::growth_rounds`] rounds, then repeated
//! with fresh samples; the labels of all rounds are united, until
//! [`QUIET_ROUNDS`] rounds in a row find no new visible triangle (converged)
//! or the rounds run out. Every
//! visible label rests on a ray that met nothing; a hidden label is
//! evidence, not proof: a triangle seen only through a very small solid
//! angle may be missed.

use crate::escape::{
    beam_escapes, escape_direction, fibonacci, is_degenerate, off_surface, RayConfirm,
};
use crate::shared_escapes::{SharedEscapes, SHARING_CELLS};
use raykit_core::{Accel, Ray, TriangleMesh, UnitScale, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Settings of [`evaluate`]: the counts of the first round (each later
/// round doubles them) and the cap on rounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvalOptions {
    /// Sample points per triangle in the first round (the centroid and
    /// uniform points).
    pub points: u32,
    /// Random directions per sample point and face in the first round.
    pub directions: u32,
    /// Viewpoints of the renders in the first round (0: no renders).
    pub viewpoints: usize,
    /// Side of each render in pixels.
    pub image: usize,
    /// Most rounds (2 to [`MAX_ROUNDS`], so that two rounds can be compared).
    pub max_rounds: usize,
    /// Rounds whose sample counts double; later rounds repeat the last
    /// counts with fresh samples (so that a long search grows linearly).
    pub growth_rounds: usize,
    /// Seed of the random samples.
    pub seed: u64,
    /// Narrowest opening that counts, as a fraction of the model's bounding
    /// box diagonal: an escape needs a beam this wide (see
    /// [`crate::escape::beam_escapes`]), so cracks between independently
    /// tessellated faces do not make hidden triangles visible. 0 (the
    /// default definition): any single ray.
    pub min_opening: f32,
}

impl Default for EvalOptions {
    fn default() -> Self {
        EvalOptions {
            points: 4,
            directions: 16,
            viewpoints: 10_000,
            image: 32,
            max_rounds: 16,
            growth_rounds: 6,
            seed: 0x0006_e7a1,
            min_opening: 0.0,
        }
    }
}

impl EvalOptions {
    /// The settings of [`crate::CullOptions::confirm`]: the ground truth's
    /// search with its own seed (any single ray counts, as in the ground
    /// truth's default), at most 6 rounds.
    pub fn confirmation() -> Self {
        EvalOptions {
            seed: 0x0003_c011,
            min_opening: 0.0,
            max_rounds: 6,
            ..Default::default()
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
    /// True when the last [`QUIET_ROUNDS`] rounds changed nothing.
    pub converged: bool,
    /// Sample points per triangle of the last round.
    pub points: u32,
    /// Directions per point and face of the last round.
    pub directions: u32,
    /// Viewpoints of the last round.
    pub viewpoints: usize,
    /// Side of the renders in pixels.
    pub image: usize,
    /// Width of the beams that had to escape, in model units.
    pub beam: f32,
    /// Rays cast, all rounds together (an upper bound: tries stop at the
    /// first escape, and beam side rays are not counted).
    pub rays: u64,
    /// Triangles of zero area (no face to sample; labelled hidden unless a
    /// render hits them).
    pub degenerate: usize,
    /// Seconds, all rounds together.
    pub seconds: f64,
    /// What each round found.
    pub round_log: Vec<RoundLog>,
}

/// What one round of [`evaluate`] found.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct RoundLog {
    /// Sample points per triangle.
    pub points: u32,
    /// Directions per point and face.
    pub directions: u32,
    /// Viewpoints of the renders.
    pub viewpoints: usize,
    /// Triangles newly found by random rays from their surface.
    pub by_surface_rays: usize,
    /// Triangles newly found by the renders (and not by surface rays).
    pub by_renders: usize,
    /// Triangles newly found by directions shared from neighbours.
    pub by_sharing: usize,
    /// Passes of sharing.
    pub sharing_passes: usize,
    /// Seconds of this round.
    pub seconds: f64,
}

/// Most rounds of [`evaluate`].
pub const MAX_ROUNDS: usize = 32;

/// Rounds in a row that must find nothing new for [`evaluate`] to call its
/// labels converged.
pub const QUIET_ROUNDS: usize = 2;

/// Where [`evaluate_with_progress`] stands: work items (candidate triangles,
/// then viewpoints) of the current round.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvalProgress {
    /// Round, from 0.
    pub round: usize,
    /// Work items of this round done.
    pub done: u64,
    /// Work items of this round in all.
    pub total: u64,
    /// Triangles labelled visible before this round.
    pub visible: usize,
}

/// The ground truth of `mesh`'s visibility from outside, by rays through
/// `accel` (built on `mesh`).
pub fn evaluate(mesh: &TriangleMesh, accel: &dyn Accel, options: &EvalOptions) -> GroundTruth {
    evaluate_with_progress(mesh, accel, options, &|_| {})
}

/// [`evaluate`], calling `progress` as work items finish (from any thread).
pub fn evaluate_with_progress(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    options: &EvalOptions,
    progress: &(dyn Fn(EvalProgress) + Sync),
) -> GroundTruth {
    let known = vec![false; mesh.num_triangles()];
    evaluate_beyond(mesh, accel, options, known, progress)
}

/// [`evaluate_with_progress`] for the triangles not yet `known` visible:
/// those start labelled visible and are not tested again (the confirmation
/// by rays of [`crate::cull`] runs it over its candidates).
/// `known.len()` must be the number of triangles.
pub fn evaluate_beyond(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    options: &EvalOptions,
    known: Vec<bool>,
    progress: &(dyn Fn(EvalProgress) + Sync),
) -> GroundTruth {
    let clock = Instant::now();
    let n = mesh.num_triangles();
    assert_eq!(known.len(), n, "one label per triangle");
    let mut truth = GroundTruth {
        visible_count: known.iter().filter(|&&k| k).count(),
        visible: known,
        image: options.image,
        ..Default::default()
    };
    if n == 0 {
        truth.converged = true;
        return truth;
    }
    let degenerate: Vec<bool> = (0..n).map(|t| is_degenerate(mesh, t)).collect();
    truth.degenerate = degenerate.iter().filter(|&&d| d).count();
    let bounds = mesh.bounds();
    let centre = (bounds.min + bounds.max) * 0.5;
    let radius = ((bounds.max - bounds.min).length() * 0.5).max(1e-20);
    let max_rounds = options.max_rounds.clamp(2, MAX_ROUNDS);
    let beam = options.min_opening.max(0.0) * (bounds.max - bounds.min).length();
    truth.beam = beam;
    let mut shared = SharedEscapes::new(&bounds, SHARING_CELLS);
    let mut quiet = 0;
    for round in 0..max_rounds {
        // Rays per triangle double each growth round: points on odd rounds,
        // directions on even ones; viewpoints double with the points.
        let grow = round.min(options.growth_rounds.clamp(1, 20) - 1);
        let samples = RayConfirm {
            points: options.points.max(1).saturating_mul(1 << grow.div_ceil(2)),
            directions: options.directions.max(1).saturating_mul(1 << (grow / 2)),
            seed: options.seed.wrapping_add(round as u64 * 0x9e37_79b9),
            beam,
        };
        let viewpoints = options.viewpoints.saturating_mul(1 << grow.div_ceil(2));
        let candidates: Vec<usize> = (0..n)
            .filter(|&t| !truth.visible[t] && !degenerate[t])
            .collect();
        let total = (candidates.len() + viewpoints) as u64;
        let done = AtomicU64::new(0);
        let visible_before = truth.visible_count;
        let tick = || {
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(EvalProgress {
                round,
                done: d,
                total,
                visible: visible_before,
            });
        };

        // Rays from the surface, for the triangles not yet seen.
        let round_clock = Instant::now();
        let mut found: Vec<(usize, Vec3)> = candidates
            .par_iter()
            .with_min_len(16)
            .filter_map(|&t| {
                let d = escape_direction(mesh, accel, t, &samples);
                tick();
                d.map(|d| (t, d))
            })
            .collect();
        truth.rays +=
            candidates.len() as u64 * u64::from(samples.points) * 2 * u64::from(samples.directions);

        // Renders of triangle ids; each triangle seen keeps the direction
        // back to the eye of its smallest (viewpoint, pixel) key (it escapes:
        // nothing lies between, and the eye is outside the bounding sphere).
        let keys: Vec<AtomicU64> = (0..n).map(|_| AtomicU64::new(u64::MAX)).collect();
        let cameras: Vec<RenderCamera> = (0..viewpoints)
            .map(|i| RenderCamera::new(centre, radius, fibonacci(i, viewpoints), options.image))
            .collect();
        cameras
            .par_iter()
            .enumerate()
            .with_min_len(4)
            .for_each(|(i, camera)| {
                render(mesh, accel, camera, i, beam, &keys);
                tick();
            });
        let seen: Vec<(usize, Vec3)> = keys
            .iter()
            .enumerate()
            .filter_map(|(t, k)| {
                let k = k.load(Ordering::Relaxed);
                (k != u64::MAX).then(|| {
                    let camera = &cameras[(k >> 32) as usize];
                    (t, -camera.pixel((k & 0xffff_ffff) as usize))
                })
            })
            .collect();
        let by_surface_rays = found.len();
        found.extend(seen);
        truth.rays += (viewpoints * options.image * options.image) as u64;
        let mut log = RoundLog {
            points: samples.points,
            directions: samples.directions,
            viewpoints,
            by_surface_rays,
            ..Default::default()
        };

        // Directions shared with neighbours, until they find nothing new.
        let spread = shared.spread(
            mesh,
            accel,
            &mut truth.visible,
            &|t| degenerate[t],
            found,
            samples.points.min(4),
            samples.seed,
            beam,
            None,
        );
        truth.rays += spread.rays;
        log.by_renders = spread.direct - by_surface_rays;
        log.by_sharing = spread.by_sharing;
        log.sharing_passes = spread.passes;
        let change = spread.direct + spread.by_sharing;
        log.seconds = round_clock.elapsed().as_secs_f64();
        truth.round_log.push(log);
        truth.visible_count += change;
        truth.rounds = round + 1;
        truth.last_change = change;
        truth.points = samples.points;
        truth.directions = samples.directions;
        truth.viewpoints = viewpoints;
        quiet = if change == 0 { quiet + 1 } else { 0 };
        if quiet >= QUIET_ROUNDS {
            truth.converged = true;
            break;
        }
    }
    truth.seconds = clock.elapsed().as_secs_f64();
    truth
}

/// The pinhole camera of one render: from `centre + 2 radius · dir`, an
/// `image × image` image looking at `centre` whose view cone just holds the
/// bounding sphere.
#[derive(Clone, Copy, Debug)]
struct RenderCamera {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    image: usize,
}

impl RenderCamera {
    fn new(centre: Vec3, radius: f32, dir: Vec3, image: usize) -> Self {
        let forward = -dir;
        let helper = if forward.z.abs() < 0.9 {
            Vec3::Z
        } else {
            Vec3::X
        };
        let right = forward.cross(helper).normalize();
        RenderCamera {
            eye: centre + dir * (2.0 * radius),
            forward,
            right,
            up: right.cross(forward),
            image: image.max(1),
        }
    }

    /// The primary ray direction of pixel `p` (row-major).
    fn pixel(&self, p: usize) -> Vec3 {
        // Half-angle asin(1/2) = 30°: the cone tangent to the bounding
        // sphere; the square image holds the cone's disc.
        let half = 30f32.to_radians().tan();
        let n = self.image as f32;
        let (i, j) = ((p % self.image) as f32, (p / self.image) as f32);
        let u = ((i + 0.5) / n * 2.0 - 1.0) * half;
        let v = ((j + 0.5) / n * 2.0 - 1.0) * half;
        (self.forward + u * self.right + v * self.up).normalize()
    }
}

/// One render, viewpoint `view` of `views`: every triangle hit (through an
/// opening at least `beam` wide) gets the smallest (viewpoint, pixel) key
/// that saw it in `keys`, so the result does not depend on thread timing.
fn render(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    camera: &RenderCamera,
    view: usize,
    beam: f32,
    keys: &[AtomicU64],
) {
    for p in 0..camera.image * camera.image {
        let d = camera.pixel(p);
        let Some(h) = accel.intersect(&Ray::new(camera.eye, d)) else {
            continue;
        };
        let t = h.prim as usize;
        let Some(slot) = keys.get(t) else { continue };
        let key = ((view as u64) << 32) | p as u64;
        if slot.load(Ordering::Relaxed) < key {
            continue; // a smaller key already saw it
        }
        // Seen through an opening at least `beam` wide?
        let n = mesh.face_normal(t).normalize_or_zero();
        let face = if n.dot(d) < 0.0 { n } else { -n };
        let origin = off_surface(mesh, t, camera.eye + d * h.t, face);
        if beam <= 0.0 || beam_escapes(accel, origin, -d, beam) {
            slot.fetch_min(key, Ordering::Relaxed);
        }
    }
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
    /// Triangles of zero area: counted in the removals above, but neither
    /// visible nor hidden, so never a false or a missed removal.
    pub degenerate: usize,
    /// Triangles of positive area the ground truth labels visible.
    pub truly_visible: usize,
    /// Triangles of positive area the ground truth labels hidden.
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
    // In f64, where the area of a triangle a picometre across does not
    // vanish; which triangles have none is judged at unit scale.
    let area = |t: usize| {
        let [a, b, c] = mesh.triangle(t).map(|v| v.as_dvec3());
        0.5 * (b - a).cross(c - a).length()
    };
    let (_, unit) = UnitScale::of(mesh);
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
        if is_degenerate(&unit, t) {
            r.degenerate += 1;
        } else if truth.visible[t] {
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
