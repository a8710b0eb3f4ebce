//! Escape rays from a triangle's surface: the sample points on it, the
//! origins a hair off either face, the random directions of each face's
//! hemisphere and the test that a ray (or a beam of rays) meets nothing.
//! The shared vocabulary of every ray search of this crate (the confirmation
//! of the grid modes, [`crate::shared_escapes`], the ray-traced visibility
//! of `rays` and the ground truth of [`crate::evaluate`]); it
//! depends on no other module of the crate.

use raykit_core::rng::Pcg32;
use raykit_core::{Accel, Ray, TriangleMesh, Vec3};

/// Settings of an escape search by random rays: sample points, directions
/// per point and face, seed, beam width.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RayConfirm {
    /// Sample points per candidate triangle (each used on both faces).
    pub points: u32,
    /// Random directions per point and face.
    pub directions: u32,
    /// Seed of the sample sequence (per triangle streams: results do not
    /// depend on the thread count).
    pub seed: u64,
    /// Width of the beam that must escape, in model units (0: a single
    /// ray). See [`beam_escapes`].
    pub beam: f32,
}

impl Default for RayConfirm {
    fn default() -> Self {
        RayConfirm {
            points: 4,
            directions: 8,
            seed: 0x0003_c011,
            beam: 0.0,
        }
    }
}

/// True when the ray from `origin` (a hair off triangle `tri`'s surface)
/// along `d` meets no triangle, and, for `beam > 0`, so do the four parallel
/// rays from `origin + 2 beam · d ± beam · e` for two directions `e`
/// perpendicular to `d` and to each other: openings narrower than about
/// `beam` (the cracks between independently tessellated CAD faces, hairline
/// seams) count as closed. The side rays start two beam widths out along
/// the central ray, so that near an inside corner they do not start behind
/// the neighbouring face.
pub fn beam_escapes(accel: &dyn Accel, origin: Vec3, d: Vec3, beam: f32) -> bool {
    if accel.occluded(&Ray::new(origin, d)) {
        return false;
    }
    if beam <= 0.0 {
        return true;
    }
    let e1 = d.any_orthonormal_vector();
    let e2 = d.cross(e1);
    let start = origin + d * (2.0 * beam);
    [e1, -e1, e2, -e2]
        .iter()
        .all(|&e| !accel.occluded(&Ray::new(start + e * beam, d)))
}

/// Smallest cosine between a sample direction and the face normal: steeper
/// directions are drawn again. A ray leaving a face at least this steeply
/// moves away from the triangle's own plane (and from coplanar duplicates),
/// so it cannot meet them and an any-hit query answers the question.
pub const MIN_FACE_COSINE: f32 = 1e-3;

/// Sample points on triangle `tri`: the centroid, then uniform points; each
/// calls `f(point, unit normal)` until it returns `Some`. `None` for a
/// triangle of zero area.
pub fn on_surface<T>(
    mesh: &TriangleMesh,
    tri: usize,
    points: u32,
    rng: &mut Pcg32,
    mut f: impl FnMut(Vec3, Vec3, &mut Pcg32) -> Option<T>,
) -> Option<T> {
    let [a, b, c] = mesh.triangle(tri);
    let n = (b - a).cross(c - a).normalize_or_zero();
    if n == Vec3::ZERO {
        return None;
    }
    for k in 0..points {
        let (mut u, mut v) = if k == 0 {
            (1.0 / 3.0, 1.0 / 3.0)
        } else {
            (rng.next_f32(), rng.next_f32())
        };
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        if let Some(x) = f(a + u * (b - a) + v * (c - a), n, rng) {
            return Some(x);
        }
    }
    None
}

/// The origin of escape rays from surface point `p` of triangle `tri` on
/// the side of `face`: a hair off the surface, so the triangle does not hit
/// itself.
pub fn off_surface(mesh: &TriangleMesh, tri: usize, p: Vec3, face: Vec3) -> Vec3 {
    let [a, b, c] = mesh.triangle(tri);
    let scale = a.abs().max(b.abs()).max(c.abs()).max_element().max(1e-30);
    p + face * (scale * 1e-5)
}

/// A direction in which a ray from triangle `tri` escapes the model, found by
/// `c.points` sample points (the centroid first) × both faces ×
/// `c.directions` uniform directions of that face's hemisphere, or `None`.
pub fn escape_direction(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    tri: usize,
    c: &RayConfirm,
) -> Option<Vec3> {
    let mut rng = Pcg32::with_stream(c.seed, tri as u64);
    on_surface(mesh, tri, c.points, &mut rng, |p, n, rng| {
        for face in [n, -n] {
            let origin = off_surface(mesh, tri, p, face);
            for _ in 0..c.directions {
                let d = loop {
                    let d = rng.unit_vector();
                    let cos = d.dot(face);
                    if cos.abs() >= MIN_FACE_COSINE {
                        break if cos < 0.0 { -d } else { d };
                    }
                };
                if beam_escapes(accel, origin, d, c.beam) {
                    return Some(d);
                }
            }
        }
        None
    })
}

/// True when triangle `t` of `mesh` has no area (no face to sample or see).
pub fn is_degenerate(mesh: &TriangleMesh, t: usize) -> bool {
    mesh.face_normal(t).normalize_or_zero() == Vec3::ZERO
}

/// Point `i` of the `n`-point Fibonacci sphere (unit vectors, evenly spread).
pub fn fibonacci(i: usize, n: usize) -> Vec3 {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let z = 1.0 - (2.0 * i as f64 + 1.0) / n.max(1) as f64;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = golden * i as f64;
    Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
}
