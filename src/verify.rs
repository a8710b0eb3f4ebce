//! Ray-by-ray comparison of answers, used by `trace --verify` and
//! `bench --verify` to check a structure against brute force.

use raykit_core::Hit;
use raykit_core::{Ray, TriangleMesh};
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
}

impl Verdict {
    /// True when every ray agrees.
    pub fn ok(&self) -> bool {
        self.disagreements() == 0
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
#[cfg_attr(not(feature = "embree"), allow(dead_code))]
pub fn edge_margin(mesh: &TriangleMesh, ray: &Ray, prim: u32) -> f64 {
    let [a, b, c] = mesh.triangle(prim as usize).map(|p| p.as_dvec3());
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
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
                ties: 1
            }
        );
        assert!(!v.ok());
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
