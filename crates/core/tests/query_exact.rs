//! The exact triangle tests of the game queries (Kim 2013) against
//! independent references: dense point sampling of the triangle (a sample
//! inside the shape ⇒ the test must report overlap), the separating axis
//! theorem as a second algorithm for boxes and frustums (on cases clearly
//! away from touching), and a second closest-point algorithm for balls.

use raykit_core::glam::DVec3;
use raykit_core::query::exact::{
    closest_point_on_segment, closest_point_on_triangle, triangle_overlaps_box,
    triangle_overlaps_polytope, triangle_overlaps_sphere, Triangle64,
};
use raykit_core::query::{Frustum, Plane};
use raykit_core::rng::Pcg32;
use raykit_core::{Camera, Vec3};

/// A random f32 triangle near `center`: mostly ordinary, some tiny, some
/// large, some slivers and some collinear.
fn random_triangle(rng: &mut Pcg32, center: Vec3, scale: f32) -> Triangle64 {
    let size = scale * [0.01, 0.3, 1.0, 3.0][rng.below(4) as usize];
    let c = center + rng.unit_vector() * scale * rng.next_f32();
    let a = c + rng.unit_vector() * size;
    let b = c + rng.unit_vector() * size;
    let third = match rng.below(10) {
        0 => a + (b - a) * rng.next_f32(), // collinear
        1 => a + (b - a) * 0.5 + rng.unit_vector() * size * 1e-3, // sliver
        _ => c + rng.unit_vector() * size,
    };
    [a, b, third].map(|p| p.as_dvec3())
}

/// Points of the triangle on a barycentric grid with `n` steps per edge.
fn samples(tri: &Triangle64, n: usize) -> impl Iterator<Item = DVec3> + '_ {
    (0..=n).flat_map(move |i| {
        (0..=n - i).map(move |j| {
            let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
            tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v
        })
    })
}

/// Separating axis theorem for a triangle and a convex polytope given by
/// its vertices, face normals and edge directions: the largest gap between
/// the projections over the candidate axes (normalised), positive when
/// separated, negative (minus a penetration depth) when overlapping.
fn sat_gap(tri: &Triangle64, verts: &[DVec3], normals: &[DVec3], edges: &[DVec3]) -> f64 {
    let tri_edges = [tri[1] - tri[0], tri[2] - tri[1], tri[0] - tri[2]];
    let mut axes: Vec<DVec3> = normals.to_vec();
    axes.push(tri_edges[0].cross(tri_edges[1]));
    for e in tri_edges {
        for d in edges {
            axes.push(e.cross(*d));
        }
    }
    let mut gap = f64::NEG_INFINITY;
    for axis in axes {
        let len = axis.length();
        if len < 1e-9 {
            continue;
        }
        let axis = axis / len;
        let span = |pts: &mut dyn Iterator<Item = DVec3>| {
            pts.map(|p| p.dot(axis))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                    (lo.min(x), hi.max(x))
                })
        };
        let (t0, t1) = span(&mut tri.iter().copied());
        let (p0, p1) = span(&mut verts.iter().copied());
        gap = gap.max(t0 - p1).max(p0 - t1);
    }
    gap
}

fn box_vertices(lo: DVec3, hi: DVec3) -> Vec<DVec3> {
    (0..8)
        .map(|i| {
            DVec3::select(
                raykit_core::glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
                hi,
                lo,
            )
        })
        .collect()
}

/// The corners of the region inside all planes: every point where three
/// planes meet that lies inside the others.
fn polytope_vertices(planes: &[Plane]) -> Vec<DVec3> {
    let mut out = Vec::new();
    for i in 0..planes.len() {
        for j in i + 1..planes.len() {
            for k in j + 1..planes.len() {
                let (a, b, c) = (planes[i], planes[j], planes[k]);
                let det = a.normal.dot(b.normal.cross(c.normal));
                if det.abs() < 1e-12 {
                    continue;
                }
                let p = (b.normal.cross(c.normal) * -a.offset
                    + c.normal.cross(a.normal) * -b.offset
                    + a.normal.cross(b.normal) * -c.offset)
                    / det;
                let scale = 1e-9 * (1.0 + p.abs().max_element());
                if planes.iter().all(|pl| pl.distance(p) >= -scale) {
                    out.push(p);
                }
            }
        }
    }
    out
}

fn random_frustum(rng: &mut Pcg32) -> Frustum {
    let camera = Camera {
        eye: rng.in_box(Vec3::splat(-3.0), Vec3::splat(3.0)),
        target: rng.in_box(Vec3::splat(-0.5), Vec3::splat(0.5)),
        up: rng.unit_vector(),
        vfov_deg: rng.range_f32(5.0, 150.0),
    };
    let near = [0.0, 0.1, 1.0][rng.below(3) as usize];
    let far = near + [0.5, 3.0, 20.0][rng.below(3) as usize];
    Frustum::from_camera(&camera, rng.range_f32(0.3, 3.0), near, far)
}

/// How many of the cases were clear overlaps and clear separations.
#[derive(Default, Debug)]
struct Tally {
    overlap: usize,
    apart: usize,
    sampled_inside: usize,
}

impl Tally {
    fn assert_balanced(&self, n: usize) {
        assert!(
            self.overlap > n / 10 && self.apart > n / 10 && self.sampled_inside > n / 20,
            "unbalanced cases: {self:?}"
        );
    }
}

#[test]
fn triangle_box_agrees_with_sat_and_sampling() {
    let mut rng = Pcg32::new(31);
    let mut tally = Tally::default();
    let n = 20_000;
    for _ in 0..n {
        let tri = random_triangle(&mut rng, Vec3::ZERO, 1.0);
        let c = rng.in_box(Vec3::splat(-1.0), Vec3::splat(1.0)).as_dvec3();
        let h = rng.in_box(Vec3::splat(0.01), Vec3::splat(1.0)).as_dvec3();
        let (lo, hi) = (c - h, c + h);
        let got = triangle_overlaps_box(&tri, lo, hi);
        let gap = sat_gap(&tri, &box_vertices(lo, hi), &DVec3::AXES, &DVec3::AXES);
        if gap.abs() > 1e-9 {
            assert_eq!(got, gap < 0.0, "{tri:?} box {lo} {hi}: SAT gap {gap}");
            if gap < 0.0 {
                tally.overlap += 1;
            } else {
                tally.apart += 1;
            }
        }
        let inside = |p: DVec3| p.cmpgt(lo + 1e-12).all() && p.cmplt(hi - 1e-12).all();
        if samples(&tri, 24).any(inside) {
            tally.sampled_inside += 1;
            assert!(got, "{tri:?}: a sampled point is inside {lo} {hi}");
        }
    }
    tally.assert_balanced(n);
}

#[test]
fn triangle_frustum_agrees_with_sat_and_sampling() {
    let mut rng = Pcg32::new(32);
    let mut tally = Tally::default();
    let n = 8_000;
    for _ in 0..n {
        let f = random_frustum(&mut rng);
        let planes = f.planes();
        let verts = polytope_vertices(planes);
        assert!(verts.len() >= 8, "a camera frustum has 8 corners");
        let normals: Vec<DVec3> = planes.iter().map(|p| p.normal).collect();
        let mut edges = Vec::new();
        for i in 0..6 {
            for j in i + 1..6 {
                edges.push(normals[i].cross(normals[j]));
            }
        }
        let tri = random_triangle(&mut rng, Vec3::ZERO, 1.5);
        let got = triangle_overlaps_polytope(&tri, planes);
        let gap = sat_gap(&tri, &verts, &normals, &edges);
        if gap.abs() > 1e-7 {
            assert_eq!(got, gap < 0.0, "{tri:?} {f:?}: SAT gap {gap}");
            if gap < 0.0 {
                tally.overlap += 1;
            } else {
                tally.apart += 1;
            }
        }
        let inside = |p: DVec3| planes.iter().all(|pl| pl.distance(p) > 1e-12);
        if samples(&tri, 24).any(inside) {
            tally.sampled_inside += 1;
            assert!(got, "{tri:?}: a sampled point is inside {f:?}");
        }
    }
    tally.assert_balanced(n);
}

/// Second algorithm for the closest point: the projection onto the plane
/// when it falls inside the triangle (barycentric coordinates by solving
/// the 2 × 2 normal equations), else the nearest of the edges' closest
/// points.
fn closest_distance_reference(p: DVec3, tri: &Triangle64) -> f64 {
    let [a, b, c] = *tri;
    let edges = [(a, b), (b, c), (c, a)]
        .into_iter()
        .map(|(s, e)| closest_point_on_segment(p, s, e).distance(p))
        .fold(f64::INFINITY, f64::min);
    let (e0, e1, d) = (b - a, c - a, p - a);
    let (m00, m01, m11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let det = m00 * m11 - m01 * m01;
    if det <= 1e-12 * m00 * m11 {
        return edges;
    }
    let (r0, r1) = (e0.dot(d), e1.dot(d));
    let u = (m11 * r0 - m01 * r1) / det;
    let v = (m00 * r1 - m01 * r0) / det;
    if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
        edges.min((a + e0 * u + e1 * v).distance(p))
    } else {
        edges
    }
}

#[test]
fn triangle_sphere_agrees_with_a_second_algorithm_and_sampling() {
    let mut rng = Pcg32::new(33);
    let mut tally = Tally::default();
    let n = 20_000;
    for _ in 0..n {
        let tri = random_triangle(&mut rng, Vec3::ZERO, 1.0);
        let c = rng.in_box(Vec3::splat(-1.5), Vec3::splat(1.5)).as_dvec3();
        let r = 1.2 * rng.next_f64();
        let q = closest_point_on_triangle(c, &tri);
        let dist = q.distance(c);
        let want = closest_distance_reference(c, &tri);
        let size = (tri[1] - tri[0]).length() + (tri[2] - tri[0]).length();
        assert!(
            (dist - want).abs() <= 1e-9 * (1.0 + size),
            "{tri:?} {c}: Ericson {dist}, reference {want}"
        );
        // The point lies on the triangle: no sample is nearer than it.
        let sampled = samples(&tri, 24)
            .map(|p| p.distance(c))
            .fold(f64::INFINITY, f64::min);
        assert!(
            dist <= sampled + 1e-12,
            "{tri:?} {c}: {dist} > sampled {sampled}"
        );
        let got = triangle_overlaps_sphere(&tri, c, r);
        if (dist - r).abs() > 1e-9 {
            assert_eq!(got, dist < r);
            if got {
                tally.overlap += 1;
            } else {
                tally.apart += 1;
            }
        }
        if sampled < r - 1e-12 {
            tally.sampled_inside += 1;
            assert!(got, "{tri:?}: a sampled point is inside the ball {c} {r}");
        }
    }
    tally.assert_balanced(n);
}
