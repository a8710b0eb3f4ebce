//! Ray/triangle intersection tests, each with its own precomputed
//! per-triangle data, behind one trait so that every acceleration structure is
//! generic over the test (`Bvh<Moller>`, `Bvh<Plucker>`, ...).
//!
//! | test | per triangle | per ray | shipped: slips on closed meshes | paper's/textbook form |
//! |---|---|---|---|---|
//! | [`Moller`]: Möller–Trumbore 1997 | 44 bytes | 4 bytes | 0 | 2.8% of edge rays, 9.4% of corner rays |
//! | [`Plucker`]: Plücker sign test, Jones 2000 | 112 bytes | 32 bytes | 0 up to 10^2 sizes from the origin; 6 of ~90,000 at 10^3-10^4 | 0 inside shared edges, 0.25% of corner rays |
//! | [`Projection`]: Wald 2004 | 48 bytes | 0 | 0 up to 10^3 sizes from the origin; 3 of ~90,000 at 10^4 | 6.9% of edge rays, 6.2% of corner rays |
//!
//! (Rays aimed exactly at shared-edge points and shared corners of closed
//! meshes placed 0 to 10^4 mesh sizes from the origin, see
//! `tests/triangle_tests.rs` and each module's documentation.)
//!
//! All three accept hits on both faces (no back-face culling) with
//! `t` in `[ray.tnear, tfar]`, report barycentrics `(u, v)` relative to the
//! corners in the order they were given to `precompute`, and never report a
//! hit on a degenerate (zero-area) triangle, for a direction parallel to the
//! triangle's plane (within the rounding error of the test's denominator), or
//! for NaN or infinite input; a reported hit never holds a NaN.
//!
//! All three are *conservative*: each widens its edge tests by a bound on its
//! own rounding error, so it hits whenever exact arithmetic on the `f32`
//! corners and ray says the ray meets the closed triangle (except for rays
//! within rounding of parallel to it, or whose `t` is within rounding of the
//! interval's ends), as long as that bound stays below
//! [`MAX_EDGE_TOLERANCE`] (2^-8 of the triangle). Exact arithmetic leaves no
//! gap between the triangles of a closed mesh, so no ray slips through an
//! edge or a corner where the bound is within the cap; beyond it (grazing
//! rays, geometry 10^3-10^4 of its size away from the origin) a few rays
//! can, as the table shows. The price is a thin band (at most 2^-8 of the
//! triangle) outside each triangle that also counts as a hit, so two
//! neighbours may both report a ray near their shared edge; the accelerators
//! keep the nearest. The textbook forms without the tolerance stay available
//! as `intersect_strict`, and the uncapped tolerance as `intersect_uncapped`,
//! for comparison. The [`reference`](mod@reference) module holds the `f64`
//! reference they are all tested against.
use crate::aabb::Aabb;
use crate::ray::Ray;
use glam::Vec3;
use std::fmt::Debug;

pub mod crossing_once;
pub mod moller;
pub mod plucker;
pub mod projection;
pub mod reach;
pub mod reference;

pub use crossing_once::crossing_once;
pub use moller::Moller;
pub use plucker::Plucker;
pub use projection::Projection;

/// Largest tolerance, in barycentric units, that any test adds outside a
/// triangle's edges (2^-8 of the triangle).
///
/// The tests widen their edge checks by a bound on their own rounding error
/// so that no ray slips between two triangles sharing an edge or a vertex.
/// For rays nearly parallel to a triangle, or far from it relative to its
/// size, that bound grows without limit; capping it keeps every false hit
/// within this thin band around the triangle (twice it beyond the edge
/// opposite the first corner in Möller's test, which checks `u + v` against
/// the sum of the two coordinates' allowances), and lets the BVHs pad their
/// boxes by the same fraction so that box culling never disagrees with the
/// triangle test (see `accel::bvh`).
pub const MAX_EDGE_TOLERANCE: f32 = 1.0 / 256.0;

/// Distance and barycentric coordinates of a ray/triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    /// Distance along the ray.
    pub t: f32,
    /// Weight of the second corner.
    pub u: f32,
    /// Weight of the third corner.
    pub v: f32,
}

/// A ray/triangle test with precomputed per-triangle and per-ray data.
pub trait TriangleTest: Send + Sync + 'static {
    /// The test's name: how saved structures, reports and front ends
    /// (`--test`, `test=`) identify it.
    const NAME: &'static str;
    /// Whether the wide BVHs keep this test's triangles in SIMD packs of
    /// four (`accel/bvh/tri4/`, Embree's `triangle4`; Wald et al. 2014),
    /// which also opens their packet path. True for Möller–Trumbore, whose
    /// pack kernel gives the scalar test's answers bit for bit; the other
    /// tests keep one triangle at a time.
    const PACKS_OF_FOUR: bool = false;
    /// Data precomputed once per triangle when an accel is built.
    type Tri: Copy + Send + Sync + Debug + 'static;
    /// Data precomputed once per ray before traversal.
    type RayData: Copy;

    /// Precompute the data for the triangle with corners `a`, `b`, `c`.
    fn precompute(a: Vec3, b: Vec3, c: Vec3) -> Self::Tri;

    /// Precompute the per-ray data.
    fn prepare(ray: &Ray) -> Self::RayData;

    /// A box holding every point at which this test may report a hit on
    /// the triangle `a`, `b`, `c`, its tolerance band included
    /// ([`reach`]): the tube [`reach::around`] unless the test reports hits
    /// only in the triangle's plane.
    fn reach(a: Vec3, b: Vec3, c: Vec3) -> Aabb {
        reach::around(a, b, c)
    }

    /// Nearest-hit test: the hit if the ray meets the triangle at a distance
    /// `t` with `ray.tnear <= t <= tfar`.
    fn intersect(tri: &Self::Tri, ray: &Ray, rd: &Self::RayData, tfar: f32) -> Option<TriHit>;

    /// Any-hit test for shadow rays: true if the ray meets the triangle with
    /// `ray.tnear <= t <= tfar`. May skip the barycentrics.
    fn occluded(tri: &Self::Tri, ray: &Ray, rd: &Self::RayData, tfar: f32) -> bool {
        Self::intersect(tri, ray, rd, tfar).is_some()
    }

    /// Number of 32-bit words [`TriangleTest::write_words`] appends per
    /// triangle.
    const WORDS: usize;

    /// Append the precomputed triangle as its flat record: 32-bit words
    /// (`f32` bits, or a `u32` where the record holds an integer). Saved
    /// structures store these records (`accel/bvh/persist.rs`), and the
    /// GPU kernels of `raykit-gpu` read the same layout, so a loaded
    /// structure and a device test exactly the data the CPU precomputed.
    fn write_words(tri: &Self::Tri, out: &mut Vec<u32>);
}

/// The triangle tests by name, for run-time selection.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TestKind {
    /// [`Moller`].
    Moller,
    /// [`Plucker`].
    Plucker,
    /// [`Projection`].
    Projection,
}

impl TestKind {
    /// Every test, in a fixed order.
    pub const ALL: [TestKind; 3] = [TestKind::Moller, TestKind::Plucker, TestKind::Projection];

    /// The test's name (its [`TriangleTest::NAME`]), as `Display` writes it.
    pub fn name(self) -> &'static str {
        match self {
            TestKind::Moller => Moller::NAME,
            TestKind::Plucker => Plucker::NAME,
            TestKind::Projection => Projection::NAME,
        }
    }

    /// The test with this name, if any (`str::parse` gives an error
    /// listing the names instead).
    pub fn from_name(name: &str) -> Option<TestKind> {
        name.parse().ok()
    }
}

crate::names::named_choice!(TestKind, "triangle test");

/// Call `$body` with the type alias `$T` bound to the triangle test named by
/// a [`TestKind`] value, so that generic code can be chosen at run time.
#[macro_export]
macro_rules! with_test {
    ($kind:expr, $T:ident => $body:expr) => {
        match $kind {
            $crate::tri::TestKind::Moller => {
                type $T = $crate::tri::Moller;
                $body
            }
            $crate::tri::TestKind::Plucker => {
                type $T = $crate::tri::Plucker;
                $body
            }
            $crate::tri::TestKind::Projection => {
                type $T = $crate::tri::Projection;
                $body
            }
        }
    };
}
