//! Faces of more than three corners (OBJ, PLY and OFF allow any number) cut
//! into triangles. A convex face is cut as a fan from its first corner. A
//! concave one, as CAD and modelling tools export L-shaped panels, letters
//! and cut-outs, is cut by ear clipping (Meisters 1975): a fan there would
//! lay triangles over what is outside the face, surfaces that rays would
//! hit and culling would keep. Corners are taken in the plane across the
//! largest axis of the face's Newell normal, in `f64`.

use raykit_core::Vec3;

/// Faces with more corners than this are cut as fans: ear clipping is
/// quadratic in the corners.
const MAX_CLIPPED: usize = 4096;

/// Reusable scratch space for [`Triangulator::cut`].
#[derive(Default)]
pub(crate) struct Triangulator {
    given: Vec<Option<Vec3>>,
    corners: Vec<[f64; 3]>,
    points: Vec<[f64; 2]>,
    left: Vec<usize>,
    /// The triangles of the last face cut, as corner positions in it.
    pub triangles: Vec<[usize; 3]>,
}

impl Triangulator {
    /// Cut the face whose corners are at `corners` (in order, at least
    /// three) into `self.triangles`, each in the face's winding. Corners of
    /// unknown position (`None`) or a face with no area give the fan.
    pub fn cut(&mut self, corners: impl ExactSizeIterator<Item = Option<Vec3>>) -> &[[usize; 3]] {
        let n = corners.len();
        self.triangles.clear();
        if n == 3 {
            self.triangles.push([0, 1, 2]);
            return &self.triangles;
        }
        let fan =
            |t: &mut Vec<[usize; 3]>| t.extend((1..n.saturating_sub(1)).map(|k| [0, k, k + 1]));
        self.given.clear();
        self.given.extend(corners);
        if let [Some(a), Some(b), Some(c), Some(d)] = self.given[..] {
            // Most faces of more than three corners are quads: the fan's
            // diagonal from corner 0 lies inside unless the two triangles
            // face opposite ways.
            if (b - a).cross(c - a).dot((c - a).cross(d - a)) > 0.0 {
                fan(&mut self.triangles);
                return &self.triangles;
            }
        }
        self.corners.clear();
        for c in &self.given {
            match c {
                Some(c) if n <= MAX_CLIPPED => self.corners.push(c.to_array().map(f64::from)),
                _ => {
                    fan(&mut self.triangles);
                    return &self.triangles;
                }
            }
        }
        let p = &self.corners;
        // Newell's normal: its largest axis is the one to project along,
        // and its sign there the face's orientation.
        let mut normal = [0.0f64; 3];
        for i in 0..n {
            let (a, b) = (p[i], p[(i + 1) % n]);
            normal[0] += (a[1] - b[1]) * (a[2] + b[2]);
            normal[1] += (a[2] - b[2]) * (a[0] + b[0]);
            normal[2] += (a[0] - b[0]) * (a[1] + b[1]);
        }
        let axis = (0..3)
            .max_by(|&i, &j| normal[i].abs().total_cmp(&normal[j].abs()))
            .unwrap_or(2);
        if !(normal[axis].abs() > 0.0 && normal[axis].is_finite()) {
            fan(&mut self.triangles);
            return &self.triangles;
        }
        // The two other axes in cyclic order keep the orientation; a
        // negative normal is mirrored so that the face turns left.
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let mirror = if normal[axis] < 0.0 { -1.0 } else { 1.0 };
        self.points.clear();
        self.points.extend(p.iter().map(|q| [mirror * q[u], q[v]]));
        let pts = &self.points;
        let turn = |a: usize, b: usize, c: usize| {
            let (a, b, c) = (pts[a], pts[b], pts[c]);
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        };
        if (0..n).all(|i| turn((i + n - 1) % n, i, (i + 1) % n) >= 0.0) {
            fan(&mut self.triangles);
            return &self.triangles;
        }
        self.left.clear();
        self.left.extend(0..n);
        let left = &mut self.left;
        let out = &mut self.triangles;
        let mut at = 0;
        let mut since_ear = 0;
        while left.len() > 3 {
            let m = left.len();
            let (a, b, c) = (left[(at + m - 1) % m], left[at % m], left[(at + 1) % m]);
            let ear = turn(a, b, c) > 0.0
                && !left.iter().any(|&q| {
                    q != a
                        && q != b
                        && q != c
                        && pts[q] != pts[a]
                        && pts[q] != pts[b]
                        && pts[q] != pts[c]
                        && turn(a, b, q) >= 0.0
                        && turn(b, c, q) >= 0.0
                        && turn(c, a, q) >= 0.0
                });
            if ear {
                out.push([a, b, c]);
                left.remove(at % m);
                at %= m - 1;
                since_ear = 0;
            } else {
                at = (at + 1) % m;
                since_ear += 1;
                if since_ear > m {
                    // No ear: the face crosses itself. Fan what is left.
                    out.extend((1..m - 1).map(|k| [left[0], left[k], left[k + 1]]));
                    return &self.triangles;
                }
            }
        }
        out.push([left[0], left[1], left[2]]);
        &self.triangles
    }
}

impl Triangulator {
    /// Append the triangles of the face `poly` (indices into `positions`;
    /// one beyond them, of a vertex not read yet, gives the fan) to `out`.
    pub fn cut_face(&mut self, poly: &[u32], positions: &[Vec3], out: &mut Vec<[u32; 3]>) {
        let corners = poly.iter().map(|&i| positions.get(i as usize).copied());
        for t in self.cut(corners) {
            out.push(t.map(|k| poly[k]));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::rng::Pcg32;

    /// Twice the signed area of a 2D polygon (the shoelace formula).
    fn area2(p: &[[f64; 2]]) -> f64 {
        (0..p.len())
            .map(|i| {
                let (a, b) = (p[i], p[(i + 1) % p.len()]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum()
    }

    /// Whether `q` is inside the polygon `p` (even-odd crossings).
    fn inside(p: &[[f64; 2]], q: [f64; 2]) -> bool {
        let mut inside = false;
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            if (a[1] > q[1]) != (b[1] > q[1]) {
                let x = a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if x > q[0] {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// Random simple polygons (star-shaped about a centre: a corner in
    /// each sector of the turn at a random radius, so most are concave), placed in random planes in
    /// both windings: the triangles cover the polygon's area exactly once
    /// (their areas sum to the shoelace area, all wound as the face, each
    /// centroid inside), checked in the polygon's own 2D coordinates.
    #[test]
    fn ear_clipping_covers_concave_faces_exactly() {
        let mut rng = Pcg32::new(5);
        let mut t = Triangulator::default();
        let mut concave = 0;
        for round in 0..2000 {
            let n = 4 + (rng.next_f32() * 20.0) as usize;
            // Each corner in its own sector of the turn: every gap below
            // half a turn, so the polygon is simple.
            let angles: Vec<f64> = (0..n)
                .map(|k| {
                    (k as f64 + 0.8 * rng.next_f32() as f64) / n as f64 * std::f64::consts::TAU
                })
                .collect();
            let flat: Vec<[f64; 2]> = angles
                .iter()
                .map(|a| {
                    let r = 0.2 + rng.next_f32() as f64;
                    [r * a.cos(), r * a.sin()]
                })
                .collect();
            let flat: Vec<[f64; 2]> = if round % 2 == 0 {
                flat
            } else {
                flat.into_iter().rev().collect()
            };
            // A plane through a random point, spanned by two random
            // orthonormal axes.
            let (e1, e2) = {
                let a = rng.unit_vector().normalize();
                let b = (rng.unit_vector() - a * a.dot(rng.unit_vector())).normalize();
                let b = (b - a * a.dot(b)).normalize();
                (a, b)
            };
            let o = rng.in_box(Vec3::splat(-5.0), Vec3::splat(5.0));
            let corners: Vec<Vec3> = flat
                .iter()
                .map(|q| o + e1 * q[0] as f32 + e2 * q[1] as f32)
                .collect();
            let want = area2(&flat);
            let convex = (0..n).all(|i| {
                let (a, b, c) = (flat[(i + n - 1) % n], flat[i], flat[(i + 1) % n]);
                ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) * want.signum()
                    >= 0.0
            });
            concave += usize::from(!convex);
            let tris = t.cut(corners.iter().map(|&c| Some(c))).to_vec();
            assert_eq!(tris.len(), n - 2, "round {round}");
            let mut sum = 0.0;
            for tri in &tris {
                let tp = tri.map(|k| flat[k]);
                let a = area2(&tp);
                assert!(
                    a * want.signum() > -1e-9,
                    "round {round}: a triangle wound against the face"
                );
                sum += a;
                let centroid = [
                    (tp[0][0] + tp[1][0] + tp[2][0]) / 3.0,
                    (tp[0][1] + tp[1][1] + tp[2][1]) / 3.0,
                ];
                if a.abs() > 1e-6 {
                    assert!(
                        inside(&flat, centroid),
                        "round {round}: a triangle outside the face"
                    );
                }
            }
            assert!(
                (sum - want).abs() <= 1e-4 * want.abs(),
                "round {round}: {sum} vs {want}"
            );
        }
        assert!(concave > 1000, "{concave} concave faces");
    }

    /// Convex faces keep the fan from the first corner; triangles and
    /// faces of unknown corners too.
    #[test]
    fn convex_faces_are_fanned() {
        let mut t = Triangulator::default();
        let square = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        assert_eq!(
            t.cut(square.iter().map(|&p| Some(p))),
            &[[0, 1, 2], [0, 2, 3]]
        );
        assert_eq!(
            t.cut([None, None, None, None].into_iter()),
            &[[0, 1, 2], [0, 2, 3]]
        );
        // An L from a corner that does not see the whole face: the fan's
        // triangle (0, 2, 3) would cover the notch [1, 2]².
        let l = [
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::ZERO,
        ];
        let tris = t.cut(l.iter().map(|&p| Some(p))).to_vec();
        assert_eq!(tris.len(), 4);
        assert!(!tris.contains(&[0, 2, 3]), "{tris:?}");
    }
}
