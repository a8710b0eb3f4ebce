//! Terrain shadow masks (Min 2008): for every grid point, is the light
//! visible from the surface point there? One segment per grid point to the
//! light, tested against the declared surface ([`crate::heightfield`]): in
//! shadow when it crosses the surface between its ends or leaves either end
//! into the ground ([`crate::ground`]).
//!
//! Two exact algorithms give identical masks:
//! - [`ShadowMethod::BruteForce`]: Min's (2008) method, each segment marched
//!   cell by cell;
//! - [`ShadowMethod::Fast`]: for a point light over the grid, the horizon
//!   sweep of [`crate::horizon`] first; then each segment it leaves through
//!   the min/max quadtree ([`crate::pyramid`]), walked from the segment's
//!   own cell upwards, skipping nodes the segment passes above and stopping
//!   at the first node the segment passes wholly *below* (it must then
//!   cross the surface, since both of its ends are on or above it).

use crate::ground::{ground_under_light, leaves_into_ground, place_light};
use crate::heightfield::{index_along, GridRay, HeightField, Steps};
use crate::horizon::{self, UNDECIDED};
use crate::march::march;
use crate::pyramid::MaxMipmap;
use rayon::prelude::*;

/// Where the light is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A point light at world position (metres: x east, y north, z up).
    Point([f64; 3]),
    /// A directional light (the sun): azimuth clockwise from north and
    /// elevation above the horizon, degrees.
    Sun {
        /// Degrees clockwise from north (90 = east).
        azimuth_deg: f64,
        /// Degrees above the horizon.
        elevation_deg: f64,
    },
}

impl Light {
    /// Unit world direction towards the sun.
    pub fn sun_direction(azimuth_deg: f64, elevation_deg: f64) -> [f64; 3] {
        let (a, e) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        [a.sin() * e.cos(), a.cos() * e.cos(), e.sin()]
    }
}

/// Which algorithm computes the mask.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowMethod {
    /// One segment per grid point marched cell by cell (Min 2008).
    BruteForce,
    /// One segment per grid point through the min/max quadtree.
    Fast,
}

/// Segment parameters closer than this to the grid point or to the light
/// are ignored (the point itself, and a light lying on the surface).
const END_EPS: f64 = 1e-9;

/// Margin by which a segment must pass below a node's minimum before the
/// fast method concludes it crosses the surface, metres.
const BELOW_EPS: f64 = 1e-7;

/// The segment from `lift` metres above grid point (`col`, `row`) towards
/// `light`, in grid units with `t` in `[0, tmax]`.
fn segment(
    field: &HeightField,
    light: &Light,
    col: usize,
    row: usize,
    lift: f64,
) -> (GridRay, f64) {
    let p = [col as f64, row as f64, field.at(col, row) as f64 + lift];
    match *light {
        Light::Point(w) => {
            let l = [w[0] / field.sx, -w[1] / field.sy, w[2]];
            (
                GridRay {
                    o: p,
                    d: [l[0] - p[0], l[1] - p[1], l[2] - p[2]],
                },
                1.0 - END_EPS,
            )
        }
        Light::Sun {
            azimuth_deg,
            elevation_deg,
        } => {
            let d = Light::sun_direction(azimuth_deg, elevation_deg);
            (
                GridRay {
                    o: p,
                    d: [d[0] / field.sx, -d[1] / field.sy, d[2]],
                },
                f64::INFINITY,
            )
        }
    }
}

/// Whether the segment from grid point (`col`, `row`) to the light meets
/// the surface, by `method`; `steps` counts the work.
pub fn occluded(
    field: &HeightField,
    pyramid: &MaxMipmap,
    light: &Light,
    col: usize,
    row: usize,
    method: ShadowMethod,
    steps: &mut Steps,
) -> bool {
    occluded_with_hint(field, pyramid, light, col, row, method, &mut None, steps)
}

/// Why a segment is known to be blocked: it meets a cell's triangles
/// (`level` 0, `below` false) or passes wholly below a node's lowest point
/// (`below` true). Neighbouring grid points are usually blocked by the same
/// thing, so the fast method tries the last certificate first; a
/// certificate is a proof, so trying it never changes an answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Blocker {
    /// Pyramid level.
    pub level: u32,
    /// Node column at that level.
    pub i: i64,
    /// Node row at that level.
    pub j: i64,
    /// Passes below the node's minimum (else: meets the cell's triangles).
    pub below: bool,
}

/// [`occluded`], trying `hint` (the blocker of a neighbouring grid point)
/// first with the fast method, and leaving this point's blocker in it.
#[allow(clippy::too_many_arguments)]
pub fn occluded_with_hint(
    field: &HeightField,
    pyramid: &MaxMipmap,
    light: &Light,
    col: usize,
    row: usize,
    method: ShadowMethod,
    hint: &mut Option<Blocker>,
    steps: &mut Steps,
) -> bool {
    occluded_from(
        field,
        Some(pyramid),
        &placed(field, light),
        col,
        row,
        0.0,
        method,
        hint,
        steps,
    )
}

/// [`occluded_with_hint`] for the point `lift` >= 0 metres above the grid
/// point (a target above the ground); without a pyramid the segment is
/// marched cell by cell whatever the method.
#[allow(clippy::too_many_arguments)]
fn occluded_from(
    field: &HeightField,
    pyramid: Option<&MaxMipmap>,
    light: &Light,
    col: usize,
    row: usize,
    lift: f64,
    method: ShadowMethod,
    hint: &mut Option<Blocker>,
    steps: &mut Steps,
) -> bool {
    let (ray, tmax) = segment(field, light, col, row, lift);
    if leaves_an_end_into_the_ground(field, light, &ray, col, row, lift) {
        steps.cells += 1;
        return true;
    }
    match (method, pyramid) {
        (ShadowMethod::BruteForce, _) => march(field, &ray, END_EPS, tmax, steps).is_some(),
        (ShadowMethod::Fast, None) => field
            .clip(&ray, END_EPS, tmax)
            .is_some_and(|(t0, t1)| march_below(field, &ray, t0, t1, steps)),
        (ShadowMethod::Fast, Some(pyramid)) => {
            // A point light over the grid needs no clipping: the segment
            // stays over the grid, and above the highest point nothing is hit.
            let over_grid = matches!(light, Light::Point(_)) && {
                let l = ray.at(1.0);
                let (w, h) = ((field.width - 1) as f64, (field.height - 1) as f64);
                (0.0..=w).contains(&l[0]) && (0.0..=h).contains(&l[1])
            };
            let clipped = if over_grid {
                Some((END_EPS, tmax))
            } else {
                field.clip(&ray, END_EPS, tmax)
            };
            let Some((t0, t1)) = clipped else {
                return false;
            };
            // The early exit needs the far end on or above the surface.
            let end = ray.at(t1);
            let end_above = end[2] >= field.height_at(end[0], end[1]);
            if let Some(b) = *hint {
                if proves(field, pyramid, &ray, t0, t1, end_above, &b, steps) {
                    return true;
                }
            }
            *hint = bottom_up(field, pyramid, &ray, col, row, t0, t1, end_above, steps);
            hint.is_some()
        }
    }
}

/// Whether the segment meets the surface for `t` in `[t0, t1]`, marching
/// it cell by cell like the brute force but testing the triangles only of
/// the cells it does not clear: a cell whose highest corner lies below the
/// segment over the whole cell (by a margin for the triangle test's
/// tolerance beyond the cell's edges) cannot be met.
fn march_below(field: &HeightField, ray: &GridRay, t0: f64, t1: f64, steps: &mut Steps) -> bool {
    let [dx, dy, dz] = ray.d;
    let slope = dz.abs() / dx.hypot(dy).max(1e-300);
    crate::march::march_cells(field, ray, t0, t1, steps, |c, r, ta, tb| {
        let h = [
            field.at(c, r),
            field.at(c + 1, r),
            field.at(c, r + 1),
            field.at(c + 1, r + 1),
        ];
        let (hi, lo) = (
            h.iter().copied().fold(f32::MIN, f32::max) as f64,
            h.iter().copied().fold(f32::MAX, f32::min) as f64,
        );
        let low = (ray.o[2] + ta * dz).min(ray.o[2] + tb * dz);
        low <= hi + slack(hi, lo, slope)
    })
    .is_some()
}

/// How far above the highest corner of a cell, or node, with corners from
/// `lo` to `hi` a segment of `slope` (metres per cell) must pass to miss its
/// triangles: the triangle test accepts hits up to 10⁻⁹ cells outside a
/// triangle, where its plane may stand higher and the segment lower than
/// over the cell.
#[inline]
fn slack(hi: f64, lo: f64, slope: f64) -> f64 {
    1e-6 + 1e-8 * (hi - lo + slope)
}

/// Whether the segment leaves the grid point (`col`, `row`) or a light on
/// the ground into the ground, which makes the point shadowed
/// ([`crate::ground`]). A lifted start is above the ground and cannot.
fn leaves_an_end_into_the_ground(
    field: &HeightField,
    light: &Light,
    ray: &GridRay,
    col: usize,
    row: usize,
    lift: f64,
) -> bool {
    if lift == 0.0 && leaves_into_ground(field, col as f64, row as f64, ray.d) {
        return true;
    }
    // From the surface point under the light, which the placement raised
    // by a rounding margin, so that a segment straight down to its own
    // grid point does not count.
    let Light::Point(w) = *light else {
        return false;
    };
    ground_under_light(field, w).is_some_and(|h| {
        let back = [-ray.d[0], -ray.d[1], ray.o[2] - h];
        leaves_into_ground(field, w[0] / field.sx, -w[1] / field.sy, back)
    })
}

/// The light as the masks test it: a point light on the ground placed just
/// above it ([`place_light`]).
fn placed(field: &HeightField, light: &Light) -> Light {
    match *light {
        Light::Point(w) => Light::Point(place_light(field, w)),
        sun => sun,
    }
}

/// Whether blocker `b` blocks this segment too.
#[allow(clippy::too_many_arguments)]
fn proves(
    field: &HeightField,
    pyramid: &MaxMipmap,
    ray: &GridRay,
    t0: f64,
    t1: f64,
    end_above: bool,
    b: &Blocker,
    steps: &mut Steps,
) -> bool {
    steps.nodes += 1;
    if !b.below {
        steps.cells += 1;
        return field
            .hit_cell(b.i as usize, b.j as usize, ray, t0, t1)
            .is_some();
    }
    if !end_above {
        return false;
    }
    let (x0, x1, y0, y1) = pyramid.extent(b.level as usize, b.i as usize, b.j as usize);
    let lv = &pyramid.levels[b.level as usize];
    let zmin = lv.min(b.j as usize * lv.width + b.i as usize) as f64;
    let lo = [x0 as f64, y0 as f64, f64::NEG_INFINITY];
    let hi = [x1 as f64, y1 as f64, f64::INFINITY];
    match crate::heightfield::slab(ray, lo, hi, t0, t1) {
        Some((ta, tb)) => {
            let (za, zb) = (ray.o[2] + ta * ray.d[2], ray.o[2] + tb * ray.d[2]);
            za.max(zb) < zmin - BELOW_EPS
        }
        None => false,
    }
}

/// The fast test: a stackless walk of the min/max quadtree that starts in
/// the grid point's own cell at level 0 and moves along the segment,
/// climbing a level after every node it leaves and descending where the
/// segment is not clear above a node (the walk of Tevs et al. 2008, started
/// at the segment's origin instead of the root, since every shadow segment
/// starts on the surface). The current cell is kept as integers and only
/// moves forward, so the walk always ends.
#[allow(clippy::too_many_arguments)]
fn bottom_up(
    field: &HeightField,
    pyramid: &MaxMipmap,
    ray: &GridRay,
    col: usize,
    row: usize,
    t0: f64,
    t1: f64,
    early_exit: bool,
    steps: &mut Steps,
) -> Option<Blocker> {
    let [dx, dy, dz] = ray.d;
    let slope = dz.abs() / dx.hypot(dy).max(1e-300);
    let (cw, ch) = field.cells();
    let (cw, ch) = (cw as i64, ch as i64);
    // The cell the segment enters from its grid point.
    let mut ci = index_along(col as f64, dx, 1.0).clamp(0, cw - 1);
    let mut cj = index_along(row as f64, dy, 1.0).clamp(0, ch - 1);
    let mut level = 0u32;
    let mut t = t0;
    let top = pyramid.top() as u32;
    // Per-axis constants: which node side the segment leaves by, and the
    // inverse direction (infinite exits for axis-parallel segments).
    let (step_x, inv_x) = (
        i64::from(dx > 0.0),
        if dx != 0.0 { 1.0 / dx } else { f64::INFINITY },
    );
    let (step_y, inv_y) = (
        i64::from(dy > 0.0),
        if dy != 0.0 { 1.0 / dy } else { f64::INFINITY },
    );
    let exit_along = |n: i64, step: i64, size: f64, o: f64, inv: f64| -> f64 {
        if inv.is_infinite() {
            f64::INFINITY
        } else {
            ((n + step) as f64 * size - o) * inv
        }
    };
    loop {
        steps.nodes += 1;
        let lv = &pyramid.levels[level as usize];
        let (i, j) = (ci >> level, cj >> level);
        let k = j as usize * lv.width + i as usize;
        let size = (1i64 << level) as f64;
        // Where the segment leaves this node's footprint.
        let exit_x = exit_along(i, step_x, size, ray.o[0], inv_x);
        let exit_y = exit_along(j, step_y, size, ray.o[1], inv_y);
        let exit = exit_x.min(exit_y).min(t1).max(t);
        let (za, zb) = (ray.o[2] + t * dz, ray.o[2] + exit * dz);
        let [zmax, zmin] = lv.max_min[k];
        let (zmax, zmin) = (zmax as f64, zmin as f64);
        // Plain comparisons: no NaN can occur here.
        let (lo, hi) = if za < zb { (za, zb) } else { (zb, za) };
        // A flat node's triangles all lie in one horizontal plane, which
        // the segment misses when it passes above it over the whole node by
        // more than the triangle test's reach beyond a cell (10⁻⁹ cells at
        // the segment's slope) and rounding; this settles segments that
        // skim a flat from a light on it.
        let clear = if zmax == zmin {
            lo > zmax + 1e-8 * slope + 1e-13 * (1.0 + zmax.abs() + dz.abs())
        } else {
            lo > zmax + slack(zmax, zmin, slope)
        };
        if !clear {
            if early_exit && hi < zmin - BELOW_EPS {
                return Some(Blocker {
                    level,
                    i,
                    j,
                    below: true,
                });
            }
            if level > 0 {
                level -= 1;
                continue;
            }
            steps.cells += 1;
            if field
                .hit_cell(ci as usize, cj as usize, ray, t0, t1)
                .is_some()
            {
                return Some(Blocker {
                    level: 0,
                    i: ci,
                    j: cj,
                    below: false,
                });
            }
        }
        // Leave the node across the side the segment crosses first; the new
        // current cell is the one just across, along the other axis where
        // the segment is at the exit (kept inside the node's span).
        if exit >= t1 {
            return None;
        }
        t = exit;
        let span = |n: i64| (n << level, ((n + 1) << level) - 1);
        if exit_x <= exit_y {
            ci = if dx > 0.0 {
                (i + 1) << level
            } else {
                (i << level) - 1
            };
            let (lo, hi) = span(j);
            cj = index_along(ray.o[1] + exit * dy, dy, 1.0).clamp(lo, hi.min(ch - 1));
        } else {
            cj = if dy > 0.0 {
                (j + 1) << level
            } else {
                (j << level) - 1
            };
            let (lo, hi) = span(i);
            ci = index_along(ray.o[0] + exit * dx, dx, 1.0).clamp(lo, hi.min(cw - 1));
        }
        if ci < 0 || cj < 0 || ci >= cw || cj >= ch {
            return None;
        }
        if level < top {
            level += 1;
        }
    }
}

/// The mask: per grid point (row-major from the north row) 1 where the
/// light is visible, 0 in shadow (parallel over rows).
pub fn shadow_mask(
    field: &HeightField,
    pyramid: &MaxMipmap,
    light: &Light,
    method: ShadowMethod,
) -> Vec<u8> {
    shadow_mask_with_progress(field, pyramid, light, method, &|_| {})
}

/// [`shadow_mask`], calling `progress` with each finished row's length.
pub fn shadow_mask_with_progress(
    field: &HeightField,
    pyramid: &MaxMipmap,
    light: &Light,
    method: ShadowMethod,
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<u8> {
    shadow_mask_for_targets(field, Some(pyramid), light, method, 0.0, progress)
}

/// [`shadow_mask_with_progress`] for targets `target_height` >= 0 metres
/// above the ground at every grid point (gdal_viewshed's `-tz`): 1 where
/// the segment from the target to the light neither crosses the surface
/// nor leaves either end into the ground ([`crate::ground`]).
/// A negative or non-finite height counts as 0. Without a `pyramid`, the
/// fast method builds one only where it needs one: for a sun, or a point
/// light the sweep cannot take or leaves many points of.
pub fn shadow_mask_for_targets(
    field: &HeightField,
    pyramid: Option<&MaxMipmap>,
    light: &Light,
    method: ShadowMethod,
    target_height: f64,
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<u8> {
    let lift = if target_height.is_finite() {
        target_height.max(0.0)
    } else {
        0.0
    };
    let w = field.width;
    let light = &placed(field, light);
    // A point light over the grid is swept first; the segment test answers
    // the points the sweep leaves.
    let swept = match (method, light) {
        (ShadowMethod::Fast, Light::Point(p)) => horizon::point_light_mask(field, *p, lift),
        _ => None,
    };
    // The points a sweep leaves are marched cell by cell, which needs no
    // quadtree, while there are fewer than about twice the grid's side: a
    // march costs about a side's cells, a quadtree a few passes over all.
    let few_left = swept.as_ref().is_some_and(|m| {
        // Counted in bytes, 255 cells at a time, which compiles to
        // vector operations.
        let left: usize = m
            .par_chunks(255 << 8)
            .map(|c| {
                c.chunks(255)
                    .map(|c| c.iter().fold(0u8, |n, &v| n + u8::from(v == UNDECIDED)) as usize)
                    .sum::<usize>()
            })
            .sum();
        left <= 2 * (w + field.height)
    });
    let built;
    let pyramid = match pyramid {
        _ if few_left || method == ShadowMethod::BruteForce => None,
        Some(p) => Some(p),
        None => {
            built = MaxMipmap::new(field);
            Some(&built)
        }
    };
    let mut mask = swept.unwrap_or_else(|| vec![UNDECIDED; w * field.height]);
    mask.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
        let mut steps = Steps::default();
        // Most lines hold no such point; `contains` finds that fast.
        if !line.contains(&UNDECIDED) {
            progress(w);
            return;
        }
        for (col, m) in line.iter_mut().enumerate() {
            if *m == UNDECIDED {
                *m = u8::from(!occluded_from(
                    field, pyramid, light, col, row, lift, method, &mut None, &mut steps,
                ));
            }
        }
        progress(w);
    });
    mask
}

/// The world position of a point light `height` metres above the ground at
/// map position (`x`, `y`) in world metres (gdal_viewshed's `-ox -oy -oz`),
/// or `None` when (x, y) is outside the grid.
pub fn light_above_ground(field: &HeightField, x: f64, y: f64, height: f64) -> Option<[f64; 3]> {
    let (gx, gy) = (x / field.sx, -y / field.sy);
    let (w, h) = ((field.width - 1) as f64, (field.height - 1) as f64);
    if !(0.0..=w).contains(&gx) || !(0.0..=h).contains(&gy) {
        return None;
    }
    Some([x, y, field.height_at(gx, gy) + height])
}
