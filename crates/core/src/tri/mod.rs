//! Ray/triangle intersection tests, each with its own precomputed
//! per-triangle data, behind one trait so that every acceleration structure is
//! generic over the test (`Bvh<Moller>`, `Bvh<Plucker>`, ...).
//!
//! - [`Moller`]: Möller–Trumbore 1997, used by paper 001.
//! - [`Plucker`]: Plücker-coordinate sign test of paper 000: a sign test on
//!   precomputed edge lines first, distance and barycentrics second; shadow
//!   rays stop after the sign test.
//! - [`Projection`]: Wald's projection test (Wald 2004), the comparison of
//!   paper 000.
//!
//! All three accept hits on both faces (no back-face culling) with
//! `t` in `[ray.tnear, tfar]`, report barycentrics `(u, v)` relative to the
//! corners in the order they were given to `precompute`, and never report a hit
//! on a degenerate (zero-area) triangle. See each module for its watertightness
//! behaviour on shared edges and vertices.

use crate::ray::Ray;
use glam::Vec3;
use std::fmt::Debug;

mod moller;
mod plucker;
mod projection;
pub mod reference;

pub use moller::Moller;
pub use plucker::Plucker;
pub use projection::Projection;

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
    /// Name used on the command line (`--test NAME`).
    const NAME: &'static str;
    /// Data precomputed once per triangle when an accel is built.
    type Tri: Copy + Send + Sync + Debug + 'static;
    /// Data precomputed once per ray before traversal.
    type RayData: Copy;

    /// Precompute the data for the triangle with corners `a`, `b`, `c`.
    fn precompute(a: Vec3, b: Vec3, c: Vec3) -> Self::Tri;

    /// Precompute the per-ray data.
    fn prepare(ray: &Ray) -> Self::RayData;

    /// Nearest-hit test: the hit if the ray meets the triangle at a distance
    /// `t` with `ray.tnear <= t <= tfar`.
    fn intersect(tri: &Self::Tri, ray: &Ray, rd: &Self::RayData, tfar: f32) -> Option<TriHit>;

    /// Any-hit test for shadow rays: true if the ray meets the triangle with
    /// `ray.tnear <= t <= tfar`. May skip the barycentrics.
    fn occluded(tri: &Self::Tri, ray: &Ray, rd: &Self::RayData, tfar: f32) -> bool {
        Self::intersect(tri, ray, rd, tfar).is_some()
    }
}

/// The triangle tests by name, for run-time selection (`--test NAME`).
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

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            TestKind::Moller => Moller::NAME,
            TestKind::Plucker => Plucker::NAME,
            TestKind::Projection => Projection::NAME,
        }
    }

    /// One-line description for `raykit info tests`.
    pub fn description(self) -> &'static str {
        match self {
            TestKind::Moller => "Möller–Trumbore 1997 (paper 001): edge vectors, determinant and barycentrics per ray",
            TestKind::Plucker => "Plücker coordinates (paper 000): sign test on precomputed edge lines, then distance; watertight on shared edges",
            TestKind::Projection => "Wald's projection test (2004): precomputed projection onto the dominant axis plane",
        }
    }

    /// Parse a command-line name.
    pub fn from_name(name: &str) -> Option<TestKind> {
        TestKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

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
