//! Ray-traced visibility from outside: the default culling of `raykit cull`.
//!
//! A triangle is **visible** when some ray leaving a point of it (from either
//! face) meets no triangle — it escapes the model, so an eye far away along
//! that ray sees the point. With [`RayOptions::min_opening`] > 0 an escape
//! must pass as a beam that wide ([`beam_escapes`]), so hairline cracks
//! between independently tessellated CAD faces do not count. Every other
//! triangle is hidden and removed. Visibility is found by ray tracing alone,
//! through an 8-wide BVH ([`raykit_core::accel::Bvh8`], Wald et al. 2014)
//! over Möller–Trumbore packs:
//!
//! 1. **views**: pinhole images from [`RayOptions::viewpoints`] eyes
//!    spread on a sphere (Fibonacci) outside the bounding sphere; the first
//!    triangle each ray meets is visible. Neighbouring pixels' rays are
//!    coherent, so they go through the packet path (coherent packets, Wald
//!    et al. 2001) in parallel.
//! 2. **escape rays** from every triangle not yet seen: stratified points on
//!    it (the centroid first) and, per point, a stratified set of directions
//!    over the whole sphere (a spherical Fibonacci set under a random
//!    rotation), each cast from the face it leaves, a hair off the surface.
//!    The first ray that meets nothing labels the triangle visible.
//! 3. **shared escapes**: every escape direction found is filed under its
//!    triangle's coarse cell and tried by the unseen triangles of that cell
//!    and the 26 around it ([`SharedEscapes`]), which finds surfaces seen
//!    through narrow openings (a slit, the clearance round a bolt) that
//!    random sampling rarely meets.
//! 4. **rounds**: steps 2–3 repeat with fresh samples, the rays per
//!    candidate doubling for [`RayOptions::growth_rounds`] rounds and then
//!    held. Candidates near a visible triangle (within one sharing cell),
//!    where what is still unseen is most likely to be seen (on the
//!    2CylinderEngine over 99% of the later rounds' finds), get
//!    [`RayOptions::frontier_factor`] times more; the others are not spared,
//!    since what is seen through a slit may lie far from every visible
//!    surface. The search stops when
//!    [`QUIET_ROUNDS`] rounds in a row find nothing new (converged) or after
//!    [`RayOptions::max_rounds`].
//!
//! Every visible label rests on a ray that met nothing, so a removal is
//! never wrong in the other direction: a kept triangle is truly visible.
//! A removal is a search that found nothing: [`RayStats`] reports how many
//! rays each removed triangle survived, which bounds the solid angle through
//! which it could still be seen (a triangle whose escaping directions make a
//! fraction `p` of the sphere of directions from every point escapes `k`
//! independent uniform rays with probability `1 - (1 - p)^k`).
//!
//! No region is skipped on the evidence of a grid: an opening narrower than
//! a cell (a slit, a crack) leaves a grid's outside air sealed while rays
//! pass, so a grid cannot prove a region enclosed.

use crate::escape::{beam_escapes, fibonacci, is_degenerate, off_surface, MIN_FACE_COSINE};
use crate::shared_escapes::{SharedEscapes, SHARING_CELLS};
use glam::Quat;
use raykit_core::rng::Pcg32;
use raykit_core::{Accel, Ray, TriangleMesh, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashSet;
use std::time::Instant;

/// Rounds in a row that must find nothing new for the search to stop as
/// converged.
pub const QUIET_ROUNDS: usize = 2;

/// Settings of the ray-traced visibility ([`visible_by_rays`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayOptions {
    /// Views from eyes spread on a sphere around the model (0: none).
    pub viewpoints: usize,
    /// Pixels per side of each view (its cone holds the bounding sphere).
    pub image: usize,
    /// Sample points per candidate triangle in the first round.
    pub points: u32,
    /// Directions per sample point in the first round, over the whole
    /// sphere (about half leave each face).
    pub directions: u32,
    /// Rounds whose ray counts double (points on odd rounds, directions on
    /// even ones); later rounds repeat the last counts with fresh samples.
    pub growth_rounds: usize,
    /// Most rounds of escape rays.
    pub max_rounds: usize,
    /// Rays per candidate near a visible triangle, as a multiple of the
    /// others' (in directions per point).
    pub frontier_factor: u32,
    /// Seed of every random sample.
    pub seed: u64,
    /// Narrowest opening that counts, as a fraction of the bounding-box
    /// diagonal (0: any single ray that escapes shows its triangle).
    pub min_opening: f32,
}

impl Default for RayOptions {
    fn default() -> Self {
        RayOptions {
            viewpoints: 4096,
            image: 64,
            points: 4,
            directions: 16,
            growth_rounds: 5,
            max_rounds: 4,
            frontier_factor: 4,
            seed: 0x7261_7973,
            min_opening: 0.0,
        }
    }
}

/// What one round of escape rays found.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct RayRound {
    /// Candidates (triangles not yet seen, of positive area) at its start.
    pub candidates: usize,
    /// Of them, near a visible triangle (more rays).
    pub frontier: usize,
    /// Sample points × directions per point, per candidate near a visible
    /// triangle (the others get the factor fewer directions).
    pub rays_per_candidate: u64,
    /// Triangles found by their own escape rays.
    pub by_own_rays: usize,
    /// Of them, near a visible triangle.
    pub by_own_rays_in_frontier: usize,
    /// Triangles found by directions shared from neighbours.
    pub by_sharing: usize,
    /// Rays cast (at most: searches stop at the first escape).
    pub rays: u64,
    /// Seconds.
    pub seconds: f64,
}

/// Figures of [`visible_by_rays`]: what each step found, the rays, and how
/// sure the removals are.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct RayStats {
    /// Orthographic views and their side in pixels.
    pub viewpoints: usize,
    /// Pixels per side of each view.
    pub image: usize,
    /// Triangles seen by the views.
    pub by_views: usize,
    /// Seconds of the views.
    pub views_seconds: f64,
    /// Triangles found by escape rays and sharing, all rounds.
    pub by_escape_rays: usize,
    /// Rounds of escape rays run.
    pub rounds: usize,
    /// Triangles the last round found (0 when converged).
    pub last_round_added: usize,
    /// True when the last [`QUIET_ROUNDS`] rounds found nothing.
    pub converged: bool,
    /// Rays cast in all (views, escape rays, sharing).
    pub rays: u64,
    /// Rays per triangle of the model (all rays / triangles).
    pub rays_per_triangle: f64,
    /// Escape rays from its own surface that every removed triangle of
    /// positive area survived (the least over them; the frontier's got more),
    /// besides the views and the shared directions.
    pub rays_per_removed: u64,
    /// How sure the removals are: a removed triangle from which at least
    /// this fraction of (point, direction) samples escape (points uniform
    /// on it, directions uniform over the sphere) would have been found with
    /// probability 95% by the `k` = [`RayStats::rays_per_removed`] rays it
    /// survived: `1 - 0.05^(1/k)`, about `3 / k`. Rarer escapes, through
    /// narrower openings, may still be missed. `None` when no triangle of
    /// positive area is removed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub escape_fraction_95: Option<f64>,
    /// Zero-area triangles (no face to see; removed).
    pub degenerate: usize,
    /// Width of the beam an escape needs (0: a single ray), model units.
    pub beam: f32,
    /// Each round.
    pub round_log: Vec<RayRound>,
}

/// Per triangle of `mesh`: true when visible from outside, found by rays
/// through `accel` (built on `mesh`; a [`raykit_core::accel::Bvh8`] over
/// Möller packs gives the packet path to the views). See the module
/// documentation.
pub fn visible_by_rays(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    options: &RayOptions,
) -> (Vec<bool>, RayStats) {
    visible_by_rays_with_progress(mesh, accel, options, &|_| {})
}

/// [`visible_by_rays`], calling `progress` with the figures so far after the
/// views and after each round.
pub fn visible_by_rays_with_progress(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    options: &RayOptions,
    progress: &dyn Fn(&RayStats),
) -> (Vec<bool>, RayStats) {
    let n = mesh.num_triangles();
    let mut stats = RayStats {
        viewpoints: options.viewpoints,
        image: options.image,
        ..Default::default()
    };
    let mut visible = vec![false; n];
    if n == 0 {
        stats.converged = true;
        return (visible, stats);
    }
    let degenerate: Vec<bool> = (0..n)
        .into_par_iter()
        .map(|t| is_degenerate(mesh, t))
        .collect();
    stats.degenerate = degenerate.iter().filter(|&&d| d).count();
    let bounds = mesh.bounds();
    let beam = options.min_opening.max(0.0) * (bounds.max - bounds.min).length();
    stats.beam = beam;

    // 1. Views.
    let clock = Instant::now();
    let (seen, view_rays) = views(mesh, accel, options, beam);
    stats.rays += view_rays;
    let mut found = Vec::with_capacity(seen.len());
    for (t, d) in seen {
        if !visible[t] && !degenerate[t] {
            visible[t] = true;
            found.push((t, d));
        }
    }
    stats.by_views = found.len();
    stats.views_seconds = clock.elapsed().as_secs_f64();

    // The views' escapes seed the sharing.
    let mut shared = SharedEscapes::new(&bounds, SHARING_CELLS);
    let skip = |t: usize| degenerate[t];
    let spread = shared.spread(
        mesh,
        accel,
        &mut visible,
        &skip,
        found,
        4,
        options.seed,
        beam,
        None,
    );
    stats.rays += spread.rays;
    stats.by_escape_rays += spread.by_sharing;
    progress(&stats);

    // 2–4. Rounds of escape rays and sharing.
    let mut quiet = 0;
    let mut own_rays = vec![0u64; n];
    let grow_max = options.growth_rounds.clamp(1, 16) - 1;
    for round in 0..options.max_rounds.max(1) {
        let clock = Instant::now();
        let grow = round.min(grow_max);
        let points = options.points.max(1).saturating_mul(1 << grow.div_ceil(2));
        let directions = options.directions.max(1).saturating_mul(1 << (grow / 2));
        let candidates: Vec<usize> = (0..n).filter(|&t| !visible[t] && !degenerate[t]).collect();
        if candidates.is_empty() {
            stats.converged = true;
            break;
        }
        let visible_cells: HashSet<[usize; 3]> = (0..n)
            .filter(|&t| visible[t])
            .map(|t| shared.cell_of_triangle(mesh, t))
            .collect();
        let near: Vec<bool> = candidates
            .par_iter()
            .map(|&t| shared.near_any(mesh, t, &visible_cells))
            .collect();
        let round_seed = options.seed ^ (round as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        // Every candidate gets the round's counts; those near a visible
        // triangle get the factor more directions.
        let base: Vec<Vec3> = {
            let k = directions as usize;
            (0..k).map(|i| fibonacci(i, k)).collect()
        };
        let dense: Vec<Vec3> = {
            let k = (directions * options.frontier_factor.max(1)) as usize;
            (0..k).map(|i| fibonacci(i, k)).collect()
        };
        let results: Vec<(Option<Vec3>, u64)> = candidates
            .par_iter()
            .zip(near.par_iter())
            .with_min_len(16)
            .map(|(&t, &near)| {
                let dirs = if near { &dense } else { &base };
                escape_search(mesh, accel, t, points, dirs, round_seed, beam)
            })
            .collect();
        let mut log = RayRound {
            candidates: candidates.len(),
            frontier: near.iter().filter(|&&b| b).count(),
            rays_per_candidate: u64::from(points)
                * u64::from(directions)
                * u64::from(options.frontier_factor.max(1)),
            ..Default::default()
        };
        let mut found = Vec::new();
        for ((&t, &near), (d, rays)) in candidates.iter().zip(&near).zip(&results) {
            own_rays[t] += rays;
            log.rays += rays;
            if let Some(d) = d {
                found.push((t, *d));
                log.by_own_rays_in_frontier += usize::from(near);
            }
        }
        let spread = shared.spread(
            mesh,
            accel,
            &mut visible,
            &skip,
            found,
            points,
            round_seed,
            beam,
            None,
        );
        log.rays += spread.rays;
        log.by_own_rays = spread.direct;
        log.by_sharing = spread.by_sharing;
        log.seconds = clock.elapsed().as_secs_f64();
        let change = spread.direct + spread.by_sharing;
        stats.rays += log.rays;
        stats.by_escape_rays += change;
        stats.round_log.push(log);
        stats.rounds = round + 1;
        stats.last_round_added = change;
        progress(&stats);
        quiet = if change == 0 { quiet + 1 } else { 0 };
        if quiet >= QUIET_ROUNDS {
            stats.converged = true;
            break;
        }
    }
    stats.rays_per_triangle = stats.rays as f64 / n as f64;
    let least = (0..n)
        .filter(|&t| !visible[t] && !degenerate[t])
        .map(|t| own_rays[t])
        .min();
    stats.rays_per_removed = least.unwrap_or(0);
    stats.escape_fraction_95 = least.map(|k| 1.0 - 0.05f64.powf(1.0 / k.max(1) as f64));
    (visible, stats)
}

/// The search of one candidate triangle `t` in one round: `points` sample
/// points (the centroid first, then a stratified (R2 sequence, Roberts 2018)
/// set under a random shift), and per point the spherical set `dirs` under
/// a random rotation, each direction cast from the face it leaves. Returns
/// the first escaping direction, and the rays cast.
fn escape_search(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    t: usize,
    points: u32,
    dirs: &[Vec3],
    seed: u64,
    beam: f32,
) -> (Option<Vec3>, u64) {
    let [a, b, c] = mesh.triangle(t);
    let n = (b - a).cross(c - a).normalize_or_zero();
    let mut rng = Pcg32::with_stream(seed, t as u64);
    let shift = (rng.next_f32(), rng.next_f32());
    let mut rays = 0;
    for k in 0..points {
        let (mut u, mut v) = if k == 0 {
            (1.0 / 3.0, 1.0 / 3.0)
        } else {
            // R2: the plastic number's inverse powers (Roberts 2018).
            let (g1, g2) = (0.754_877_7_f32, 0.569_840_3_f32);
            (
                (shift.0 + g1 * k as f32).fract(),
                (shift.1 + g2 * k as f32).fract(),
            )
        };
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p = a + u * (b - a) + v * (c - a);
        let front = off_surface(mesh, t, p, n);
        let back = off_surface(mesh, t, p, -n);
        let rot = random_rotation(&mut rng);
        for &d0 in dirs {
            let d = rot * d0;
            let cos = d.dot(n);
            if cos.abs() < MIN_FACE_COSINE {
                continue;
            }
            rays += 1;
            let origin = if cos > 0.0 { front } else { back };
            if beam_escapes(accel, origin, d, beam) {
                return (Some(d), rays);
            }
        }
    }
    (None, rays)
}

/// A uniformly random rotation (Shoemake 1992, from three uniforms).
fn random_rotation(rng: &mut Pcg32) -> Quat {
    let (u1, u2, u3) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
    let tau = std::f32::consts::TAU;
    let (s1, s2) = ((1.0 - u1).sqrt(), u1.sqrt());
    Quat::from_xyzw(
        s1 * (tau * u2).sin(),
        s1 * (tau * u2).cos(),
        s2 * (tau * u3).sin(),
        s2 * (tau * u3).cos(),
    )
    .normalize()
}

/// The views: per viewpoint `v` (Fibonacci directions, at three bounding
/// radii from the centre), a pinhole image of `image × image` pixels (one
/// jittered sample each) whose view cone just holds the bounding sphere.
/// Rays of one eye fan out, so that the eyes together thread openings in
/// many directions; neighbouring pixels' rays stay coherent for the packet
/// path. Returns each triangle seen (through an opening at least `beam`
/// wide) with the direction back to the eye (an escape: nothing lies
/// between, and the eye is outside the bounding sphere), in view order,
/// and the rays cast.
fn views(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    options: &RayOptions,
    beam: f32,
) -> (Vec<(usize, Vec3)>, u64) {
    let bounds = mesh.bounds();
    let centre = (bounds.min + bounds.max) * 0.5;
    let radius = ((bounds.max - bounds.min).length() * 0.5).max(1e-20);
    let side = options.image.max(1);
    let count = options.viewpoints;
    // Half-angle asin(1/3): the cone tangent to the bounding sphere.
    let half = (1.0f32 / 3.0).asin().tan();
    let per_view: Vec<Vec<(u32, Vec3)>> = (0..count)
        .into_par_iter()
        .map(|i| {
            let v = fibonacci(i, count);
            let eye = centre + v * (3.0 * radius);
            let right = v.any_orthonormal_vector();
            let up = v.cross(right);
            let mut rng = Pcg32::with_stream(options.seed ^ 0x5649_4557, i as u64);
            let rays: Vec<Ray> = (0..side * side)
                .map(|p| {
                    let x = ((p % side) as f32 + rng.next_f32()) / side as f32 * 2.0 - 1.0;
                    let y = ((p / side) as f32 + rng.next_f32()) / side as f32 * 2.0 - 1.0;
                    Ray::new(eye, (-v + (x * right + y * up) * half).normalize())
                })
                .collect();
            let mut hits = vec![None; rays.len()];
            accel.intersect_batch(&rays, &mut hits);
            let mut seen: Vec<(u32, Vec3)> = rays
                .iter()
                .zip(&hits)
                .filter_map(|(r, h)| {
                    let h = h.as_ref()?;
                    let t = h.prim as usize;
                    if t >= mesh.num_triangles() {
                        return None;
                    }
                    let back = -r.dir();
                    if beam > 0.0 {
                        let n = mesh.face_normal(t).normalize_or_zero();
                        let face = if n.dot(back) > 0.0 { n } else { -n };
                        let origin = off_surface(mesh, t, r.at(h.t), face);
                        if !beam_escapes(accel, origin, back, beam) {
                            return None;
                        }
                    }
                    Some((h.prim, back))
                })
                .collect();
            seen.sort_unstable_by_key(|&(t, _)| t);
            seen.dedup_by_key(|&mut (t, _)| t);
            seen
        })
        .collect();
    let rays = (count * side * side) as u64;
    let out = per_view
        .into_iter()
        .flat_map(|seen| seen.into_iter().map(|(t, d)| (t as usize, d)))
        .collect();
    (out, rays)
}
