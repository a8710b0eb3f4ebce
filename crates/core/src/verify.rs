//! Ray-by-ray comparison of two sets of answers to the same rays: nearest
//! hits (hit or miss, distance within [`T_TOLERANCE`], ties on shared edges
//! counted as agreement) and occlusion flags, with the disagreements that a
//! ray grazing a triangle edge explains (the two sides round the edge test
//! differently) counted apart. `raykit trace --verify`, `raykit bench
//! --verify` and the experiments use it to check a structure, another
//! engine or a GPU kernel against brute force.

use crate::tri::MAX_EDGE_TOLERANCE;
use crate::Hit;
use crate::{Ray, TriangleMesh};
use serde::Serialize;

/// Relative tolerance on hit distances.
pub const T_TOLERANCE: f32 = 1e-5;

/// Outcome of a comparison.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Verdict {
    /// Rays compared.
    pub checked: usize,
    /// Hit in one answer, miss in the other.
    pub hit_miss: usize,
    /// Both hit, at distances more than the tolerance apart.
    pub distance: usize,
    /// Both hit at the same distance but on different triangles (shared
    /// edges or duplicates): counted as agreement.
    pub ties: usize,
    /// Of the disagreements, those explained by the ray grazing a triangle
    /// edge (see [`edge_grazes`]): filled in only where the two sides round
    /// differently (another engine, a GPU), never against brute force with
    /// the same test.
    pub edge_grazes: usize,
}

impl Verdict {
    /// True when every ray agrees, edge grazes aside.
    pub fn ok(&self) -> bool {
        self.unexplained() == 0
    }

    /// Disagreements that are not edge grazes.
    pub fn unexplained(&self) -> usize {
        self.disagreements().saturating_sub(self.edge_grazes)
    }

    /// Rays that disagree (hit/miss or distance; ties agree).
    pub fn disagreements(&self) -> usize {
        self.hit_miss + self.distance
    }
}

/// `k` indices spread evenly over `0..n` (all of them when `k >= n`).
pub fn sample(n: usize, k: usize) -> Vec<usize> {
    if k >= n {
        return (0..n).collect();
    }
    (0..k).map(|i| i * n / k).collect()
}

/// Compare nearest-hit answers.
pub fn compare_hits(reference: &[Option<Hit>], got: &[Option<Hit>]) -> Verdict {
    let mut v = Verdict {
        checked: reference.len(),
        ..Default::default()
    };
    for (r, g) in reference.iter().zip(got) {
        match (r, g) {
            (None, None) => {}
            (Some(r), Some(g)) => {
                let tol = T_TOLERANCE * r.t.abs().max(g.t.abs()).max(f32::MIN_POSITIVE);
                if (r.t - g.t).abs() > tol {
                    v.distance += 1;
                } else if r.prim != g.prim {
                    v.ties += 1;
                }
            }
            _ => v.hit_miss += 1,
        }
    }
    v
}

/// Compare occlusion answers.
pub fn compare_occlusion(reference: &[bool], got: &[bool]) -> Verdict {
    Verdict {
        checked: reference.len(),
        hit_miss: reference.iter().zip(got).filter(|(a, b)| a != b).count(),
        ..Default::default()
    }
}

/// Barycentric distance (f64) of `ray`'s crossing of triangle `prim` from
/// the triangle's nearest edge: negative outside, positive inside.
pub fn edge_margin(mesh: &TriangleMesh, ray: &Ray, prim: u32) -> f64 {
    let [a, b, c] = mesh.triangle(prim as usize).map(|p| p.as_dvec3());
    let (o, d) = (ray.origin.as_dvec3(), ray.dir().as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return 0.0;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let v = d.dot(s.cross(e1)) / det;
    u.min(v).min(1.0 - u - v)
}

/// Half-width of the band around a triangle's edges, in barycentric units,
/// within which the two engines may legitimately disagree: our triangle
/// tests widen their edges by a bound on their own rounding error, capped at
/// [`MAX_EDGE_TOLERANCE`] per test and staying within 2√3 times that of the
/// triangle (see `raykit_core::tri`), so that no ray slips between
/// triangles sharing an edge; Embree's test does not widen them.
pub const EDGE_BAND: f64 = 2.0 * 1.732_050_8 * MAX_EDGE_TOLERANCE as f64;

/// How many of the disagreements between `a` and `b` are edge grazes or
/// same-triangle distance differences: the nearer answer's triangle is
/// met within [`EDGE_BAND`] (barycentric, f64) of its edge, so one engine
/// catches the ray where the other, rounding differently, slips past; or
/// both report the same triangle at distances that differ because the ray
/// runs nearly in its plane, where `t` is ill-conditioned.
pub fn edge_grazes(
    mesh: &TriangleMesh,
    rays: &[Ray],
    a: &[Option<Hit>],
    b: &[Option<Hit>],
) -> usize {
    rays.iter()
        .zip(a.iter().zip(b))
        .filter(|(ray, (x, y))| {
            let near = match (x, y) {
                (Some(x), Some(y)) => {
                    // The same distance tolerance as `compare_hits`.
                    let tol = T_TOLERANCE * x.t.abs().max(y.t.abs()).max(f32::MIN_POSITIVE);
                    if (x.t - y.t).abs() <= tol {
                        return false;
                    }
                    if x.prim == y.prim {
                        // The same triangle at two distances: a ray nearly in
                        // the triangle's plane, where t is ill-conditioned.
                        return true;
                    }
                    if x.t < y.t {
                        x
                    } else {
                        y
                    }
                }
                (Some(x), None) | (None, Some(x)) => x,
                (None, None) => return false,
            };
            edge_margin(mesh, ray, near.prim).abs() < EDGE_BAND
        })
        .count()
}

/// Of the rays whose occlusion answers `x` and `y` differ, how many are
/// edge grazes: `nearest(differ)` gives both sides' nearest hits along those
/// rays' segments, and the blocker of the side that found one is checked as
/// in [`edge_grazes`]. Also returns the differing rays' indices.
pub fn occlusion_grazes(
    mesh: &TriangleMesh,
    rays: &[Ray],
    x: &[bool],
    y: &[bool],
    nearest: impl FnOnce(&[Ray]) -> (Vec<Option<Hit>>, Vec<Option<Hit>>),
) -> (usize, Vec<usize>) {
    let differ: Vec<usize> = (0..rays.len()).filter(|&i| x[i] != y[i]).collect();
    if differ.is_empty() {
        return (0, differ);
    }
    let r: Vec<Ray> = differ.iter().map(|&i| rays[i]).collect();
    let (a, b) = nearest(&r);
    let pick = |h: &[Option<Hit>], occ: &[bool]| -> Vec<Option<Hit>> {
        differ
            .iter()
            .zip(h)
            .map(|(&i, h)| h.filter(|_| occ[i]))
            .collect()
    };
    let grazes = edge_grazes(mesh, &r, &pick(&a, x), &pick(&b, y));
    (grazes, differ)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(t: f32, prim: u32) -> Option<Hit> {
        Some(Hit {
            t,
            u: 0.0,
            v: 0.0,
            prim,
        })
    }

    #[test]
    fn counts_each_kind_of_difference() {
        let r = [None, hit(1.0, 0), hit(2.0, 1), hit(3.0, 2), None];
        let g = [None, hit(1.0, 0), hit(2.0, 7), hit(3.1, 2), hit(1.0, 1)];
        let v = compare_hits(&r, &g);
        assert_eq!(
            v,
            Verdict {
                checked: 5,
                hit_miss: 1,
                distance: 1,
                ties: 1,
                edge_grazes: 0
            }
        );
        assert!(!v.ok());
    }

    /// A unit square split along its diagonal: a ray through the diagonal
    /// grazes both triangles' edge, a ray through a triangle's centre none.
    #[test]
    fn edge_grazes_tells_a_diagonal_crossing_from_an_interior_one() {
        use crate::glam::Vec3;
        let mesh = TriangleMesh::new(
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        let down = |x: f32, y: f32| Ray::new(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let rays = [down(0.5, 0.5), down(0.75, 0.25), down(0.25, 0.75)];
        // One side hits each ray at t = 1, the other misses all three.
        let a = [hit(1.0, 0), hit(1.0, 0), hit(1.0, 1)];
        let b = [None, None, None];
        assert_eq!(edge_grazes(&mesh, &rays, &a, &b), 1);
        assert_eq!(edge_grazes(&mesh, &rays[..1], &a[..1], &b[..1]), 1);
        // Occlusion: only the differing rays are looked at, through the
        // nearest hits the closure returns.
        let x = [true, true, false];
        let y = [false, true, true];
        let (grazes, differ) = occlusion_grazes(&mesh, &rays, &x, &y, |r| {
            assert_eq!(r.len(), 2);
            (vec![hit(1.0, 0), None], vec![None, hit(1.0, 1)])
        });
        assert_eq!(differ, vec![0, 2]);
        assert_eq!(grazes, 1, "ray 0 grazes the diagonal, ray 2 does not");
    }

    #[test]
    fn sample_is_spread_and_bounded() {
        assert_eq!(sample(10, 20), (0..10).collect::<Vec<_>>());
        let s = sample(1000, 10);
        assert_eq!(s.len(), 10);
        assert_eq!(s[1], 100);
        assert!(s.windows(2).all(|w| w[0] < w[1]));
    }
}
