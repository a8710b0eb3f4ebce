//! Exact triangle tests in f64 for the game queries of Kim 2013: does a
//! triangle share at least one point with a convex polytope (a frustum), an
//! axis-aligned box, or a ball? Touching the boundary counts as overlapping.
//!
//! Triangle corners are f32 in the mesh, so their f64 copies are exact; the
//! remaining rounding is that of the clipping and projection arithmetic.

use super::frustum::Plane;
use glam::DVec3;

/// A triangle's corners in f64.
pub type Triangle64 = [DVec3; 3];

/// True when the triangle has at least one point inside every plane's
/// half-space (a convex polytope, e.g. a [`super::Frustum`]).
///
/// Quick answers first: a corner inside all planes ⇒ overlap; all corners
/// strictly outside one plane ⇒ none. Otherwise the triangle is clipped by
/// each half-space in turn (Sutherland–Hodgman) and overlaps when a point is
/// left.
pub fn triangle_overlaps_polytope(tri: &Triangle64, planes: &[Plane]) -> bool {
    overlaps_halves(tri, planes)
}

/// True when the triangle has at least one point in the closed box
/// `[min, max]`. The same clipping as [`triangle_overlaps_polytope`] with the
/// box's six faces; a point cut on a face gets that face's coordinate
/// exactly, so triangles meeting the box in an edge or a corner are found.
pub fn triangle_overlaps_box(tri: &Triangle64, min: DVec3, max: DVec3) -> bool {
    let lo = tri[0].min(tri[1]).min(tri[2]);
    let hi = tri[0].max(tri[1]).max(tri[2]);
    if lo.cmpgt(max).any() || hi.cmplt(min).any() {
        return false;
    }
    let face = |axis: usize, value: f64, upper: bool| AxisHalf { axis, value, upper };
    let faces = [
        face(0, min.x, false),
        face(0, max.x, true),
        face(1, min.y, false),
        face(1, max.y, true),
        face(2, min.z, false),
        face(2, max.z, true),
    ];
    overlaps_halves(tri, &faces)
}

/// The point of the triangle closest to `p` (Ericson, "Real-Time Collision
/// Detection", 5.1.5: find the Voronoi region of `p` among the corners,
/// edges and face from dot products, then project onto that feature).
/// Degenerate triangles (zero area) fall back to the closest of their edges.
pub fn closest_point_on_triangle(p: DVec3, tri: &Triangle64) -> DVec3 {
    let [a, b, c] = *tri;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vc = d1 * d4 - d3 * d2;
    let vb = d5 * d2 - d1 * d6;
    let va = d3 * d6 - d5 * d4;
    // va + vb + vc = |ab × ac|²: zero for a degenerate triangle, whose edge
    // regions below would divide by zero.
    let denom = va + vb + vc;
    if denom.is_nan() || denom <= 0.0 || denom <= 1e-14 * ab.length_squared() * ac.length_squared()
    {
        return [(a, b), (b, c), (c, a)]
            .into_iter()
            .map(|(s, e)| closest_point_on_segment(p, s, e))
            .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))
            .unwrap_or(a);
    }
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    // Inside the face; clamping keeps the point on the triangle whatever the
    // rounding of the barycentric coordinates.
    let v = (vb / denom).clamp(0.0, 1.0);
    let w = (vc / denom).clamp(0.0, 1.0 - v);
    a + ab * v + ac * w
}

/// The point of segment `[s, e]` closest to `p`.
pub fn closest_point_on_segment(p: DVec3, s: DVec3, e: DVec3) -> DVec3 {
    let d = e - s;
    let len2 = d.length_squared();
    if len2.is_nan() || len2 <= 0.0 {
        return s;
    }
    s + d * ((p - s).dot(d) / len2).clamp(0.0, 1.0)
}

/// True when the triangle has a point within `radius` of `center` (the
/// closest point, [`closest_point_on_triangle`], is at most `radius` away).
pub fn triangle_overlaps_sphere(tri: &Triangle64, center: DVec3, radius: f64) -> bool {
    if radius.is_nan() || radius < 0.0 {
        return false;
    }
    closest_point_on_triangle(center, tri).distance_squared(center) <= radius * radius
}

/// A closed half-space as the clipper sees it.
trait HalfSpace {
    /// Positive inside, zero on the boundary.
    fn distance(&self, p: DVec3) -> f64;
    /// Put a point computed on the boundary exactly onto it, where the
    /// boundary is simple enough (an axis-aligned face).
    fn snap(&self, p: DVec3) -> DVec3 {
        p
    }
}

impl HalfSpace for Plane {
    #[inline]
    fn distance(&self, p: DVec3) -> f64 {
        Plane::distance(self, p)
    }
}

/// `p[axis] >= value` (or `<=` when `upper`): a face of a box.
struct AxisHalf {
    axis: usize,
    value: f64,
    upper: bool,
}

impl HalfSpace for AxisHalf {
    #[inline]
    fn distance(&self, p: DVec3) -> f64 {
        if self.upper {
            self.value - p[self.axis]
        } else {
            p[self.axis] - self.value
        }
    }

    fn snap(&self, mut p: DVec3) -> DVec3 {
        p[self.axis] = self.value;
        p
    }
}

fn overlaps_halves<H: HalfSpace>(tri: &Triangle64, halves: &[H]) -> bool {
    // A corner inside everything, or all corners outside one half-space.
    if tri
        .iter()
        .any(|&p| halves.iter().all(|h| h.distance(p) >= 0.0))
    {
        return true;
    }
    if halves.iter().any(|h| {
        tri.iter()
            .all(|&p| h.distance(p) < 0.0 || h.distance(p).is_nan())
    }) {
        return false;
    }
    let mut poly = tri.to_vec();
    let mut next = Vec::with_capacity(8);
    for h in halves {
        clip(&poly, h, &mut next);
        if next.is_empty() {
            return false;
        }
        std::mem::swap(&mut poly, &mut next);
    }
    true
}

/// Sutherland–Hodgman: the part of the convex polygon `poly` inside `h`,
/// into `out`. A corner on the plane is kept; an edge crossing it strictly
/// gains the crossing point. Works on degenerate polygons (a point, a
/// segment) as well.
fn clip<H: HalfSpace>(poly: &[DVec3], h: &H, out: &mut Vec<DVec3>) {
    out.clear();
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let (da, db) = (h.distance(a), h.distance(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0) {
            out.push(h.snap(a + (b - a) * (da / (da - db))));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Triangle64 {
        [a.into(), b.into(), c.into()]
    }

    #[test]
    fn box_touching_cases() {
        let (lo, hi) = (DVec3::ZERO, DVec3::ONE);
        // A corner on a face, an edge through a box edge, a triangle whose
        // interior crosses the box with every corner outside.
        assert!(triangle_overlaps_box(
            &tri([1.0, 0.5, 0.5], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0]),
            lo,
            hi
        ));
        assert!(triangle_overlaps_box(
            &tri([0.0, -1.0, 2.0], [0.0, 2.0, -1.0], [-3.0, 0.0, 0.0]),
            lo,
            hi
        ));
        assert!(triangle_overlaps_box(
            &tri([-5.0, -5.0, 0.5], [5.0, -5.0, 0.5], [0.0, 5.0, 0.5]),
            lo,
            hi
        ));
        assert!(!triangle_overlaps_box(
            &tri([1.5, 0.0, 0.0], [0.0, 1.5, 0.0], [0.0, 0.0, 1.5]).map(|p| p + 1.0),
            lo,
            hi
        ));
        // The plane x + y + z = 3 misses the box below its corner (1, 1, 1).
        assert!(!triangle_overlaps_box(
            &tri([3.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 3.0]),
            DVec3::splat(-1.0),
            DVec3::splat(1.0 - 1e-9)
        ));
        assert!(triangle_overlaps_box(
            &tri([3.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 3.0]),
            DVec3::splat(-1.0),
            DVec3::splat(1.0)
        ));
    }

    #[test]
    fn sphere_regions_and_degenerate_triangles() {
        let t = tri([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]);
        let cases = [
            ([0.5, 0.5, 3.0], [0.5, 0.5, 0.0]),
            ([-1.0, -1.0, 0.0], [0.0, 0.0, 0.0]),
            ([3.0, -1.0, 0.0], [2.0, 0.0, 0.0]),
            ([1.0, -2.0, 1.0], [1.0, 0.0, 0.0]),
            ([2.0, 2.0, 0.0], [1.0, 1.0, 0.0]),
        ];
        for (p, want) in cases {
            let got = closest_point_on_triangle(p.into(), &t);
            assert!(got.distance(want.into()) < 1e-12, "{p:?}: {got}");
        }
        // Collinear and coincident corners.
        let seg = tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]);
        let got = closest_point_on_triangle(DVec3::new(1.5, 1.0, 0.0), &seg);
        assert!(got.distance(DVec3::new(1.5, 0.0, 0.0)) < 1e-12);
        let point = tri([1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]);
        assert_eq!(closest_point_on_triangle(DVec3::ZERO, &point), DVec3::ONE);
        assert!(triangle_overlaps_sphere(&point, DVec3::ZERO, 1.7321));
        assert!(!triangle_overlaps_sphere(&point, DVec3::ZERO, 1.7));
        assert!(!triangle_overlaps_sphere(&t, DVec3::ZERO, f64::NAN));
    }

    #[test]
    fn polytope_with_a_corner_on_two_planes() {
        // The wedge x >= 0, y >= 0 touched by a triangle at its edge line.
        let planes = [Plane::new(DVec3::X, 0.0), Plane::new(DVec3::Y, 0.0)];
        let t = tri([0.0, 0.0, 0.0], [-1.0, 1.0, 0.0], [-1.0, -1.0, 5.0]);
        assert!(triangle_overlaps_polytope(&t, &planes));
        let t = tri([-1e-9, 0.0, 0.0], [-1.0, 1.0, 0.0], [-1.0, -1.0, 5.0]);
        assert!(!triangle_overlaps_polytope(&t, &planes));
    }
}
