//! Clipping a triangle to a box in `f64`: the "perfect split" bounds of
//! Wald & Havran 2006 (section 4.2), so that a triangle straddling a split
//! plane is bounded by the part of it that lies in each child, not by its
//! whole box.

use crate::aabb::Aabb;
use crate::tri::MAX_EDGE_TOLERANCE;
use glam::{DVec3, Vec3};

/// Most vertices a triangle clipped by six planes can have (3 + 6).
const MAX_POLY: usize = 9;

/// Bounds `(min, max)` of the part of triangle `tri` inside the closed box
/// `[lo, hi]`, or `None` when they do not meet.
///
/// Sutherland–Hodgman clipping against the six planes, in `f64` so that the
/// result is accurate to far below the `f32` box it is rounded into.
pub(crate) fn clip_triangle_bounds(
    tri: &[DVec3; 3],
    lo: DVec3,
    hi: DVec3,
) -> Option<(DVec3, DVec3)> {
    let tmin = tri[0].min(tri[1]).min(tri[2]);
    let tmax = tri[0].max(tri[1]).max(tri[2]);
    if tmin.cmpge(lo).all() && tmax.cmple(hi).all() {
        return Some((tmin, tmax));
    }
    if tmax.cmplt(lo).any() || tmin.cmpgt(hi).any() {
        return None;
    }
    let mut poly = [DVec3::ZERO; MAX_POLY + 1];
    poly[..3].copy_from_slice(tri);
    let mut n = 3;
    let mut next = [DVec3::ZERO; MAX_POLY + 1];
    for axis in 0..3 {
        for (bound, keep_below) in [(lo[axis], false), (hi[axis], true)] {
            // Skip planes the polygon does not cross.
            let inside = |p: DVec3| {
                if keep_below {
                    p[axis] <= bound
                } else {
                    p[axis] >= bound
                }
            };
            if poly[..n].iter().all(|&p| inside(p)) {
                continue;
            }
            let mut m = 0;
            for i in 0..n {
                let p = poly[i];
                let q = poly[(i + 1) % n];
                let (pin, qin) = (inside(p), inside(q));
                if pin {
                    next[m] = p;
                    m += 1;
                }
                if pin != qin {
                    let s = (bound - p[axis]) / (q[axis] - p[axis]);
                    let mut x = p + (q - p) * s;
                    x[axis] = bound;
                    next[m] = x;
                    m += 1;
                }
            }
            if m == 0 {
                return None;
            }
            n = m.min(MAX_POLY);
            poly[..n].copy_from_slice(&next[..n]);
        }
    }
    let mut bmin = poly[0];
    let mut bmax = poly[0];
    for p in &poly[1..n] {
        bmin = bmin.min(*p);
        bmax = bmax.max(*p);
    }
    Some((bmin, bmax))
}

/// Width of the band around a triangle in which the triangle tests may
/// report hits: `4 · MAX_EDGE_TOLERANCE` of its largest extent (the tests
/// stay within `2√3 · MAX_EDGE_TOLERANCE` of it, see [`crate::tri`]).
pub(crate) fn band_width(tri: &[DVec3; 3]) -> f64 {
    let e = tri[0].max(tri[1]).max(tri[2]) - tri[0].min(tri[1]).min(tri[2]);
    4.0 * MAX_EDGE_TOLERANCE as f64 * e.max_element()
}

/// The box a kd-tree node keeps for a triangle reference: the bounds of the
/// triangle clipped to the cell widened by the band `w`, widened by `w`
/// again and cut back to the cell, rounded outwards to `f32`.
///
/// Any point of the cell where a triangle test may report the triangle
/// lies within `w` of a triangle point, which lies in the widened cell, so
/// the box contains it: a ray that meets the band inside this cell finds the
/// triangle listed in the cell, and split planes never separate a ray from a
/// hit the brute-force reference would report.
pub(crate) fn reference_box(tri: &[DVec3; 3], w: f64, cell: &Aabb) -> Option<Aabb> {
    let lo = cell.min.as_dvec3() - DVec3::splat(w);
    let hi = cell.max.as_dvec3() + DVec3::splat(w);
    let (bmin, bmax) = clip_triangle_bounds(tri, lo, hi)?;
    let bmin = (bmin - DVec3::splat(w)).max(cell.min.as_dvec3());
    let bmax = (bmax + DVec3::splat(w)).min(cell.max.as_dvec3());
    if bmin.cmpgt(bmax).any() {
        return None;
    }
    Some(Aabb::new(round_down(bmin), round_up(bmax)))
}

/// The `f32` vector no greater than `v`, component-wise.
pub(crate) fn round_down(v: DVec3) -> Vec3 {
    let f = v.as_vec3();
    Vec3::from_array(std::array::from_fn(|i| {
        if (f[i] as f64) > v[i] {
            f[i].next_down()
        } else {
            f[i]
        }
    }))
}

/// The `f32` vector no less than `v`, component-wise.
pub(crate) fn round_up(v: DVec3) -> Vec3 {
    let f = v.as_vec3();
    Vec3::from_array(std::array::from_fn(|i| {
        if (f[i] as f64) < v[i] {
            f[i].next_up()
        } else {
            f[i]
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    /// Reference: sample the triangle densely and keep the samples inside
    /// the box; their bounds lie inside the clipped bounds and approach them.
    #[test]
    fn clipped_bounds_contain_and_approach_sampled_points() {
        let mut rng = Pcg32::new(7);
        for _ in 0..300 {
            let tri: [DVec3; 3] =
                std::array::from_fn(|_| rng.in_box(Vec3::ZERO, Vec3::ONE).as_dvec3());
            let a = rng.in_box(Vec3::splat(-0.2), Vec3::ONE).as_dvec3();
            let b = rng.in_box(Vec3::ZERO, Vec3::splat(1.2)).as_dvec3();
            let (lo, hi) = (a.min(b), a.max(b));
            let got = clip_triangle_bounds(&tri, lo, hi);
            let mut smin = DVec3::splat(f64::INFINITY);
            let mut smax = DVec3::splat(f64::NEG_INFINITY);
            let n = 120;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let p = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v;
                    if p.cmpge(lo).all() && p.cmple(hi).all() {
                        smin = smin.min(p);
                        smax = smax.max(p);
                    }
                }
            }
            if smin.x.is_finite() {
                let (cmin, cmax) = got.expect("samples inside but clip says empty");
                assert!(cmin.cmple(smin + 1e-12).all() && cmax.cmpge(smax - 1e-12).all());
                // Within one sample spacing of the sampled bounds.
                let spacing = (tri[1] - tri[0]).length().max((tri[2] - tri[0]).length()) / n as f64;
                assert!((smin - cmin).max_element() <= 2.0 * spacing + 1e-12);
                assert!((cmax - smax).max_element() <= 2.0 * spacing + 1e-12);
            }
        }
    }

    #[test]
    fn rounding_is_outward() {
        let v = DVec3::new(0.1, -1.0 / 3.0, 1e30);
        assert!(round_down(v).as_dvec3().cmple(v).all());
        assert!(round_up(v).as_dvec3().cmpge(v).all());
    }
}
