//! A ray/triangle test that counts every crossing of a surface exactly once,
//! rays through shared edges and corners included: the watertight test of
//! Woop, Benthin and Wald (2013, "Watertight ray/triangle intersection")
//! with its edge functions evaluated exactly and their zeros broken by a
//! symbolic perturbation of the ray.
//!
//! The corners are moved into the ray's frame (the origin subtracted, the
//! dominant axis of the direction made the depth axis, the other two
//! sheared so that the ray runs along it). Each corner's sheared position
//! depends on that corner and the ray alone, so the triangles sharing a
//! corner see the same rounded point, and the projected triangles tile
//! the plane around the ray as the surface does. The three edge functions
//! are 2 × 2 determinants of those `f32` coordinates: each product is exact
//! in `f64` and the difference correctly rounded, so each sign is exact.
//!
//! An edge function that is exactly zero (the ray meets the edge's line) is
//! given the sign it would have if the ray were moved by `(ε², ε)` in the
//! projected plane, `ε → 0`: the sign of `ax - bx` for the edge from `a` to
//! `b`, or of `by - ay` where those are equal. Both triangles of a shared
//! edge evaluate it from the same two points, with opposite signs, so
//! exactly one of them takes a ray through the edge; at a corner shared by
//! a fan, exactly one triangle of the fan takes it. A ray then crosses a
//! closed surface an even number of times, and a surface without boundary
//! around the crossing exactly once, whatever the tessellation.
//!
//! It is slower than [`super::Moller`]'s test (the frame per call, three
//! `f64` determinants); the multi-hit walks call it only for the crossings
//! that [`super::Moller::crossing`] cannot classify, those within rounding
//! error of an edge or a corner.

use super::TriHit;
use crate::ray::Ray;
use glam::Vec3;

/// The crossing of `ray` with the triangle `tri` over `[ray.tnear, tfar]`,
/// counted as described in the module documentation: `(u, v)` the weights
/// of `tri[1]` and `tri[2]`. None for a triangle seen edge-on from the
/// ray (zero projected area, which includes every degenerate triangle and
/// every ray in the triangle's plane), and for NaN or infinite input.
pub fn crossing_once(tri: &[Vec3; 3], ray: &Ray, tfar: f32) -> Option<TriHit> {
    let d = ray.dir;
    let ad = d.abs();
    let kz = if ad.x >= ad.y && ad.x >= ad.z {
        0
    } else if ad.y >= ad.z {
        1
    } else {
        2
    };
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    if d[kz] == 0.0 || !d[kz].is_finite() {
        return None;
    }
    let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    // The same operations for every corner, so a shared corner lands on
    // the same point.
    let frame = |p: Vec3| {
        let a = p - ray.origin;
        (a[kx] - sx * a[kz], a[ky] - sy * a[kz], sz * a[kz])
    };
    let [a, b, c] = tri.map(frame);
    // The edge function of the edge from `p` to `q` at the ray, exactly
    // signed, its zero broken by the perturbation.
    let edge = |p: (f32, f32, f32), q: (f32, f32, f32)| -> (f64, f64) {
        let e = q.0 as f64 * p.1 as f64 - q.1 as f64 * p.0 as f64;
        let side = if e != 0.0 {
            e
        } else if p.0 != q.0 {
            // Subtracting two f32 never flips the sign of their difference.
            (p.0 - q.0) as f64
        } else {
            (q.1 - p.1) as f64
        };
        (e, side)
    };
    let (w, sw) = edge(a, b);
    let (u, su) = edge(b, c);
    let (v, sv) = edge(c, a);
    let same = (su > 0.0 && sv > 0.0 && sw > 0.0) || (su < 0.0 && sv < 0.0 && sw < 0.0);
    if !same {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let t = (u * a.2 as f64 + v * b.2 as f64 + w * c.2 as f64) / det;
    let hit = TriHit {
        t: t as f32,
        u: (v / det) as f32,
        v: (w / det) as f32,
    };
    let in_range = hit.t >= ray.tnear && hit.t <= tfar && hit.t < f32::INFINITY;
    (in_range && hit.u.is_finite() && hit.v.is_finite()).then_some(hit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    /// A fan of `n` triangles around a centre, in the plane z = 0, some
    /// wound one way and some the other, with corners on a coarse grid so
    /// that rays along z through the centre, the spokes and the rim hit
    /// corners and edges exactly.
    fn fan(n: usize, rng: &mut Pcg32) -> Vec<[Vec3; 3]> {
        let rim: Vec<Vec3> = (0..n)
            .map(|k| {
                let a = std::f32::consts::TAU * k as f32 / n as f32;
                Vec3::new((4.0 * a.cos()).round(), (4.0 * a.sin()).round(), 0.0)
            })
            .collect();
        (0..n)
            .map(|k| {
                let (p, q) = (rim[k], rim[(k + 1) % n]);
                if rng.below(2) == 0 {
                    [Vec3::ZERO, p, q]
                } else {
                    [q, Vec3::ZERO, p]
                }
            })
            .filter(|t| (t[1] - t[0]).cross(t[2] - t[0]) != Vec3::ZERO)
            .collect()
    }

    #[test]
    fn a_ray_through_a_shared_corner_or_edge_crosses_a_fan_once() {
        let mut rng = Pcg32::new(5);
        for n in [3, 5, 8, 12] {
            let tris = fan(n, &mut rng);
            // The centre, points on spokes and inside triangles, from above
            // and below, straight and tilted.
            let targets = [
                Vec3::ZERO,
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.5, 0.25, 0.0),
                Vec3::new(-1.0, -1.0, 0.0),
            ];
            for target in targets {
                for dir in [
                    Vec3::new(0.0, 0.0, 1.0),
                    Vec3::new(0.0, 0.0, -1.0),
                    Vec3::new(0.25, 0.5, 1.0),
                    Vec3::new(-0.75, 0.125, -1.0),
                ] {
                    let ray = Ray::new(target - 3.0 * dir, dir);
                    let inside = tris.iter().any(|t| {
                        // Inside the fan's polygon: some triangle holds the
                        // target (closed), by the f64 reference.
                        let [a, b, c] = t.map(|p| p.as_dvec3());
                        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
                        super::super::reference::intersect_f64(a, b, c, o, d).is_some()
                    });
                    let count = tris
                        .iter()
                        .filter(|t| crossing_once(t, &ray, f32::INFINITY).is_some())
                        .count();
                    assert_eq!(count, inside as usize, "n {n} target {target} dir {dir}");
                }
            }
        }
    }
}
