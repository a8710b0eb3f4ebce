//! Bounding volume hierarchies (placeholder until the real build lands).

use super::{Accel, AccelStats, BruteForce};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// Options of the BVH builds.
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Most triangles per leaf.
    pub max_leaf_size: usize,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions { max_leaf_size: 4 }
    }
}

/// Placeholder.
pub struct Bvh2<T: TriangleTest>(BruteForce<T>);
/// Placeholder.
pub struct ThreadedBvh<T: TriangleTest>(BruteForce<T>);

impl<T: TriangleTest> Bvh2<T> {
    /// Build.
    pub fn build(mesh: &TriangleMesh, _o: &BuildOptions) -> Self {
        Bvh2(BruteForce::new(mesh))
    }
}
impl<T: TriangleTest> ThreadedBvh<T> {
    /// Build.
    pub fn build(mesh: &TriangleMesh, _o: &BuildOptions) -> Self {
        ThreadedBvh(BruteForce::new(mesh))
    }
}
impl<T: TriangleTest> Accel for Bvh2<T> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
    fn stats(&self) -> AccelStats {
        self.0.stats()
    }
}
impl<T: TriangleTest> Accel for ThreadedBvh<T> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
    fn stats(&self) -> AccelStats {
        self.0.stats()
    }
}
