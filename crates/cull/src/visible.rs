//! The visible set (paper 003, step 3) and the conservative additions that
//! keep triangles the grid cannot clearly hide.

use crate::distance_field::DirectedDistanceField;
use crate::propagate::Classification;
use raykit_core::rng::Pcg32;
use raykit_core::{Accel, Ray, TriangleMesh, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Triangles met by the directed rays of outside grid points (paper 003,
/// step 3: "the triangle id found there is visible").
///
/// `depth_cells` is the conservative dilation: along each such ray, the
/// triangles hit within `depth_cells` grid spacings beyond the first surface
/// are marked visible too. It keeps surfaces that lie closer behind a visible
/// one than the grid can resolve — thin gaps, slots and small openings next
/// to the first surface, where the true outside reaches between the grid
/// points. 0 gives paper 003's rule exactly.
pub fn visible_from_outside(
    field: &DirectedDistanceField,
    class: &Classification,
    triangles: usize,
    depth_cells: f32,
) -> Vec<bool> {
    let g = &field.grid;
    let depth = depth_cells.max(0.0) * g.spacing;
    let visible: Vec<AtomicBool> = (0..triangles).map(|_| AtomicBool::new(false)).collect();
    let mark = |prim: u32| {
        if let Some(v) = visible.get(prim as usize) {
            v.store(true, Ordering::Relaxed);
        }
    };
    for axis in 0..3 {
        (0..g.lines(axis))
            .into_par_iter()
            .with_min_len(64)
            .for_each(|l| {
                let (t, prim) = field.line_hits(axis, l);
                if t.is_empty() {
                    return;
                }
                // Index of the first hit not before the previous outside
                // point, so each hit run is marked once per side.
                let (mut last_fwd, mut last_bwd) = (usize::MAX, usize::MAX);
                let mut m = 0; // hits with t < s
                for i in 0..g.dims[axis] {
                    let s = i as f32 * g.spacing;
                    while m < t.len() && t[m] < s {
                        m += 1;
                    }
                    if !class.is_outside(g.index(g.line_point(axis, l, i))) {
                        continue;
                    }
                    // +axis: first hit with t >= s, and those within `depth`.
                    if m < t.len() && m != last_fwd {
                        last_fwd = m;
                        let end = t[m] + depth;
                        for k in m..t.len() {
                            if t[k] > end {
                                break;
                            }
                            mark(prim[k]);
                        }
                    }
                    // −axis: last hit with t <= s, and those within `depth`.
                    let mut b = m;
                    while b < t.len() && t[b] <= s {
                        b += 1;
                    }
                    if b > 0 && b - 1 != last_bwd {
                        last_bwd = b - 1;
                        let end = t[b - 1] - depth;
                        for k in (0..b).rev() {
                            if t[k] < end {
                                break;
                            }
                            mark(prim[k]);
                        }
                    }
                }
            });
    }
    visible.into_iter().map(AtomicBool::into_inner).collect()
}

/// Settings of the confirmation by rays (conservative mode).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RayConfirm {
    /// Sample points per candidate triangle (each used on both faces).
    pub points: u32,
    /// Random directions per point and face.
    pub directions: u32,
    /// Seed of the sample sequence (per triangle streams: results do not
    /// depend on the thread count).
    pub seed: u64,
}

impl Default for RayConfirm {
    fn default() -> Self {
        RayConfirm {
            points: 4,
            directions: 8,
            seed: 0x0003_c011,
        }
    }
}

/// True when some ray from a sample point on triangle `tri` (either face) in
/// a random direction of that face's hemisphere meets no triangle: it leaves
/// the model's bounding sphere, so the triangle is seen from outside.
/// Triangles of zero area have no face to sample and count as escaping.
pub fn escapes(mesh: &TriangleMesh, accel: &dyn Accel, tri: usize, c: &RayConfirm) -> bool {
    let [a, b, cc] = mesh.triangle(tri);
    let n = (b - a).cross(cc - a);
    let n = n.normalize_or_zero();
    if n == Vec3::ZERO {
        // No area, no face to judge: keeping it costs nothing.
        return true;
    }
    let scale = a.abs().max(b.abs()).max(cc.abs()).max_element().max(1e-30);
    // Start a hair off the surface so the triangle does not hit itself.
    let offset = scale * 1e-5;
    let mut rng = Pcg32::with_stream(c.seed, tri as u64);
    for _ in 0..c.points {
        let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p = a + u * (b - a) + v * (cc - a);
        for side in [1.0f32, -1.0] {
            let face = n * side;
            for _ in 0..c.directions {
                let mut d = rng.unit_vector();
                if d.dot(face) < 0.0 {
                    d = -d;
                }
                if escapes_from(accel, p + face * offset, d, tri as u32) {
                    return true;
                }
            }
        }
    }
    false
}

/// True when the ray from `origin` along `dir` meets no triangle other than
/// `own` (hits on `own` itself, from grazing directions, are stepped over).
fn escapes_from(accel: &dyn Accel, origin: Vec3, dir: Vec3, own: u32) -> bool {
    let mut tnear = 0.0f32;
    for _ in 0..4 {
        match accel.intersect(&Ray::segment(origin, dir, tnear, f32::INFINITY)) {
            None => return true,
            Some(h) if h.prim == own => tnear = h.t.next_up(),
            Some(_) => return false,
        }
    }
    false
}

/// Conservative mode, confirmation by rays: every candidate (not `visible`)
/// triangle is tested with [`escapes`]; those that escape are marked visible.
/// Returns how many were kept this way. Parallel over triangles.
pub fn confirm_by_rays(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    visible: &mut [bool],
    c: &RayConfirm,
) -> usize {
    let kept: Vec<usize> = visible
        .par_iter()
        .enumerate()
        .with_min_len(64)
        .filter(|(t, v)| !**v && escapes(mesh, accel, *t, c))
        .map(|(t, _)| t)
        .collect();
    for &t in &kept {
        visible[t] = true;
    }
    kept.len()
}

/// Most grid points examined per triangle by [`touches_outside`]; a triangle
/// whose box spans more is kept without looking (conservative).
pub const MAX_CORNERS_PER_TRIANGLE: usize = 1 << 16;

/// Conservative mode, contact with the outside: every candidate triangle
/// whose bounding box, widened to the grid cells it overlaps, holds an
/// outside grid point is marked visible. A visible triangle borders outside
/// air; where the grid resolved that air but no axis ray happened to meet the
/// triangle (triangles smaller than a cell, grazing faces), this keeps it.
/// Returns how many were kept this way.
pub fn touches_outside(
    mesh: &TriangleMesh,
    grid: &crate::Grid,
    class: &Classification,
    visible: &mut [bool],
) -> usize {
    let kept: Vec<usize> = visible
        .par_iter()
        .enumerate()
        .with_min_len(256)
        .filter(|(t, v)| !**v && near_outside(mesh, grid, class, *t))
        .map(|(t, _)| t)
        .collect();
    for &t in &kept {
        visible[t] = true;
    }
    kept.len()
}

fn near_outside(mesh: &TriangleMesh, grid: &crate::Grid, class: &Classification, t: usize) -> bool {
    let b = mesh.triangle_bounds(t);
    let lo = ((b.min - grid.origin) / grid.spacing).floor();
    let hi = ((b.max - grid.origin) / grid.spacing).floor() + Vec3::ONE;
    let clamp = |x: f32, a: usize| (x.max(0.0) as usize).min(grid.dims[a] - 1);
    let lo = [0, 1, 2].map(|a| clamp(lo[a], a));
    let hi = [0, 1, 2].map(|a| clamp(hi[a], a));
    let count: usize = (0..3).map(|a| hi[a] - lo[a] + 1).product();
    if count > MAX_CORNERS_PER_TRIANGLE {
        return true;
    }
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            for i in lo[0]..=hi[0] {
                if class.is_outside(grid.index([i, j, k])) {
                    return true;
                }
            }
        }
    }
    false
}
