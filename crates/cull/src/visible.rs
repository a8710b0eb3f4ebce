//! The visible set (Min 2008, third stage) and the conservative additions that
//! keep triangles the grid cannot clearly hide.

use crate::distance_field::DirectedDistanceField;
use crate::escape::{escape_direction, is_degenerate, RayConfirm};
use crate::propagate::Classification;
use crate::shared_escapes::SharedEscapes;
use raykit_core::{Accel, TriangleMesh, Vec3};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};

/// Triangles met by the directed rays of outside grid points (Min (2008),
/// third stage: "the triangle id found there is visible").
///
/// `depth_cells` is the conservative dilation: along each such ray, the
/// triangles hit within `depth_cells` grid spacings beyond the first surface
/// are marked visible too. It keeps surfaces that lie closer behind a visible
/// one than the grid can resolve — thin gaps, slots and small openings next
/// to the first surface, where the true outside reaches between the grid
/// points. 0 gives Min's (2008) rule exactly.
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

/// Ray budget of [`confirm_frontier`]'s candidates (about 3 s on 2 cores
/// for a million-triangle model): a wide frontier (coarse grids on big
/// assemblies) gets fewer rays per candidate, down to one per face, and
/// sharing stops early. The seeds' rays (a few kept triangles per cell)
/// come on top.
pub const FRONTIER_RAY_BUDGET: u64 = 1 << 23;

/// Most kept triangles per cell whose escapes seed [`confirm_frontier`].
pub const SEEDS_PER_CELL: usize = 8;

/// Conservative mode, confirmation at the frontier: the candidate (not
/// `visible`) triangles next to kept ones — within one cell of the
/// [`SharedEscapes`] grid of a kept triangle — are tested by `c`'s random
/// rays, and every candidate may then try the escape directions found from
/// its kept or newly kept neighbours ([`SharedEscapes::spread`]). This keeps
/// what is seen through openings finer than the culling grid next to a
/// visible surface (a bolt in its hole, a seam between parts) at a cost
/// proportional to the frontier, not to the hidden interior, and at most
/// [`FRONTIER_RAY_BUDGET`] rays. Returns how many were kept this way, and
/// whether the budget cut the search short (fewer rays per candidate than
/// `c` asks, or sharing stopped early).
pub fn confirm_frontier(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    visible: &mut [bool],
    c: &RayConfirm,
    cells_per_axis: usize,
) -> (usize, bool) {
    let n = visible.len();
    let mut shared = SharedEscapes::new(&mesh.bounds(), cells_per_axis);
    let cells = |keep: bool, visible: &[bool]| -> HashSet<[usize; 3]> {
        (0..n)
            .filter(|&t| visible[t] == keep)
            .map(|t| shared.cell_of_triangle(mesh, t))
            .collect()
    };
    let candidate_cells = cells(false, visible);
    if candidate_cells.is_empty() {
        return (0, false);
    }
    // Kept triangles next to a candidate, a few per cell: their escapes
    // seed the sharing.
    let near: Vec<usize> = (0..n)
        .into_par_iter()
        .filter(|&t| visible[t] && shared.near_any(mesh, t, &candidate_cells))
        .collect();
    let mut per_cell: HashMap<[usize; 3], usize> = HashMap::new();
    let kept_near: Vec<usize> = near
        .into_iter()
        .filter(|&t| {
            let k = per_cell
                .entry(shared.cell_of_triangle(mesh, t))
                .or_default();
            *k += 1;
            *k <= SEEDS_PER_CELL
        })
        .collect();
    let kept_cells: HashSet<[usize; 3]> = kept_near
        .iter()
        .map(|&t| shared.cell_of_triangle(mesh, t))
        .collect();
    let mut found: Vec<(usize, Vec3)> = kept_near
        .par_iter()
        .with_min_len(16)
        .filter_map(|&t| escape_direction(mesh, accel, t, c).map(|d| (t, d)))
        .collect();
    // Candidates next to a kept triangle: random rays of their own.
    let frontier: Vec<usize> = (0..n)
        .into_par_iter()
        .filter(|&t| !visible[t] && shared.near_any(mesh, t, &kept_cells))
        .collect();
    // Half the ray budget for the candidates' own random rays: fewer
    // directions (then points) per candidate on a wide frontier.
    let mut own = *c;
    let rays = |o: &RayConfirm| u64::from(o.points) * u64::from(o.directions);
    let per = |o: &RayConfirm| frontier.len() as u64 * 2 * rays(o);
    while per(&own) > FRONTIER_RAY_BUDGET / 2 && rays(&own) > 1 {
        if own.directions > 1 {
            own.directions /= 2;
        } else {
            own.points /= 2;
        }
    }
    found.par_extend(
        frontier
            .par_iter()
            .with_min_len(16)
            .filter_map(|&t| escape_direction(mesh, accel, t, &own).map(|d| (t, d))),
    );
    let degenerate = |t: usize| is_degenerate(mesh, t);
    let s = shared.spread(
        mesh,
        accel,
        visible,
        &degenerate,
        found,
        c.points,
        c.seed,
        c.beam,
        Some(FRONTIER_RAY_BUDGET / 2),
    );
    (s.direct + s.by_sharing, s.cut_short || own != *c)
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
