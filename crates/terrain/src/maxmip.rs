//! Per-ray maximum-mipmap traversal (Tevs, Ihrke and Seidel 2008; the
//! "per-ray top-down" method): walk the quadtree from the root,
//! skip a node when the ray stays above its maximum over the node's
//! footprint, visit the children in the order the ray crosses them, and
//! test cells at level 0. Exact for the declared surface: a skipped node
//! holds no surface point the ray could reach.

use crate::heightfield::{GridRay, HeightField, Steps, TerrainHit};
use crate::pyramid::MaxMipmap;

/// Slack on the "ray above the node" test, metres: a node is skipped only
/// when the ray clears its maximum by more than this.
const ABOVE_EPS: f64 = 1e-9;

/// The first hit with `t` in `[tmin, tmax]`.
pub fn trace(
    field: &HeightField,
    pyramid: &MaxMipmap,
    ray: &GridRay,
    tmin: f64,
    tmax: f64,
    steps: &mut Steps,
) -> Option<TerrainHit> {
    let (t0, t1) = field.clip(ray, tmin, tmax)?;
    let top = pyramid.top();
    node(field, pyramid, ray, top, 0, 0, t0, t1, (t0, t1), steps)
}

/// Visit node (`i`, `j`) of `level` for the ray interval `[ta, tb]` inside
/// its footprint; `range` is the whole query interval for the cell tests.
#[allow(clippy::too_many_arguments)]
fn node(
    field: &HeightField,
    pyramid: &MaxMipmap,
    ray: &GridRay,
    level: usize,
    i: usize,
    j: usize,
    ta: f64,
    tb: f64,
    range: (f64, f64),
    steps: &mut Steps,
) -> Option<TerrainHit> {
    steps.nodes += 1;
    let lv = &pyramid.levels[level];
    let zmax = lv.max(j * lv.width + i) as f64;
    let (za, zb) = (ray.o[2] + ta * ray.d[2], ray.o[2] + tb * ray.d[2]);
    if za.min(zb) > zmax + ABOVE_EPS {
        return None;
    }
    if level == 0 {
        steps.cells += 1;
        return field
            .hit_cell(i, j, ray, range.0, range.1)
            .map(|t| TerrainHit {
                t,
                col: i as u32,
                row: j as u32,
            });
    }
    // Split lines between the children, in cell units.
    let half = 1usize << (level - 1);
    let xm = ((2 * i + 1) * half) as f64;
    let ym = ((2 * j + 1) * half) as f64;
    let mut cuts = [ta, tb, tb, tb];
    let mut n = 1;
    for (o, d, m) in [(ray.o[0], ray.d[0], xm), (ray.o[1], ray.d[1], ym)] {
        if d != 0.0 {
            let t = (m - o) / d;
            if t > ta && t < tb {
                cuts[n] = t;
                n += 1;
            }
        }
    }
    cuts[n] = tb;
    cuts[1..n].sort_by(f64::total_cmp);
    let child = &pyramid.levels[level - 1];
    for k in 0..n {
        let (a, b) = (cuts[k], cuts[k + 1]);
        if b < a {
            continue;
        }
        let p = ray.at(0.5 * (a + b));
        let ci = 2 * i + usize::from(p[0] >= xm);
        let cj = 2 * j + usize::from(p[1] >= ym);
        if ci >= child.width || cj >= child.height {
            continue;
        }
        if let Some(hit) = node(field, pyramid, ray, level - 1, ci, cj, a, b, range, steps) {
            return Some(hit);
        }
    }
    None
}
