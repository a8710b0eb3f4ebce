//! The reference caster: a 2D DDA over the cells the ray crosses (Amanatides
//! and Woo's traversal), testing each cell's two triangles, as the quadtree-box caster's
//! unaccelerated "per-texel exact intersection" baseline.

use crate::heightfield::{GridRay, HeightField, Steps, TerrainHit};

/// The first hit with `t` in `[tmin, tmax]`, marching cell by cell from the
/// ray's entry into the grid's bounding box (or from `tmin` if later).
pub fn march(
    field: &HeightField,
    ray: &GridRay,
    tmin: f64,
    tmax: f64,
    steps: &mut Steps,
) -> Option<TerrainHit> {
    let (t0, t1) = field.clip(ray, tmin, tmax)?;
    march_from(field, ray, t0, t1, steps)
}

/// March the cells the ray crosses for `t` in `[t0, t1]` (already inside
/// the grid's bounding box) and return the first hit.
///
/// Each cell is tested for hits anywhere in `[t0, t1]`: the inside-triangle
/// test already confines a hit to the cell, so a hit lying on a cell border
/// is found whichever side the rounding of the line crossings puts it. The
/// next grid line is computed from the origin at every step (no
/// accumulated error), so cells are visited in order.
pub fn march_from(
    field: &HeightField,
    ray: &GridRay,
    t0: f64,
    t1: f64,
    steps: &mut Steps,
) -> Option<TerrainHit> {
    march_cells(field, ray, t0, t1, steps, |_, _, _, _| true)
}

/// [`march_from`], testing only the cells for which `worth(col, row, t_in,
/// t_out)` is true (`t_in`, `t_out`: where the ray enters and leaves the
/// cell); the caller answers for the others.
pub fn march_cells(
    field: &HeightField,
    ray: &GridRay,
    t0: f64,
    t1: f64,
    steps: &mut Steps,
    worth: impl Fn(usize, usize, f64, f64) -> bool,
) -> Option<TerrainHit> {
    let (cw, ch) = field.cells();
    let p = ray.at(t0);
    let mut c = (p[0].floor().max(0.0) as usize).min(cw - 1);
    let mut r = (p[1].floor().max(0.0) as usize).min(ch - 1);
    let [dx, dy, _] = ray.d;
    // Parameter where the ray leaves the current cell's column / row.
    let exit = |o: f64, d: f64, cell: usize| -> f64 {
        if d > 0.0 {
            (cell as f64 + 1.0 - o) / d
        } else if d < 0.0 {
            (cell as f64 - o) / d
        } else {
            f64::INFINITY
        }
    };
    let mut t_in = t0;
    loop {
        let (tx, ty) = (exit(ray.o[0], dx, c), exit(ray.o[1], dy, r));
        let t_out = tx.min(ty).min(t1);
        if worth(c, r, t_in, t_out) {
            steps.cells += 1;
            if let Some(t) = field.hit_cell(c, r, ray, t0, t1) {
                return Some(TerrainHit {
                    t,
                    col: c as u32,
                    row: r as u32,
                });
            }
        }
        t_in = t_out;
        if tx.min(ty) >= t1 {
            return None;
        }
        if tx <= ty {
            if dx > 0.0 {
                c += 1;
                if c >= cw {
                    return None;
                }
            } else {
                if c == 0 {
                    return None;
                }
                c -= 1;
            }
        } else if dy > 0.0 {
            r += 1;
            if r >= ch {
                return None;
            }
        } else {
            if r == 0 {
                return None;
            }
            r -= 1;
        }
    }
}
