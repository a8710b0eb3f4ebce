//! The "linear BVH" of Kim et al.'s GPU stream ray tracer: the triangles in
//! mesh order cut into runs of eight, one box per run, the boxes scanned in
//! order.

use super::leaf::LeafTriangles;
use super::node_box::NodeBox;
use super::{Accel, AccelStats};
use crate::aabb::Aabb;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// Triangles per box.
pub const LINEAR_BOX_SIZE: usize = 8;

/// One level of boxes over runs of [`LINEAR_BOX_SIZE`] consecutive
/// triangles (the last run may be shorter), the acceleration the GPU stream
/// ray tracer of Kim et al. (after Purcell et al. 2002) compares with no
/// acceleration and with its complete BVH: every ray tests every box, and
/// the triangles of the boxes it enters. Nothing is sorted, so the boxes
/// are only as tight as the mesh's own triangle order is coherent.
pub struct LinearBoxes<T: TriangleTest> {
    boxes: Vec<NodeBox>,
    tris: LeafTriangles<T>,
    bounds: Aabb,
}

impl<T: TriangleTest> LinearBoxes<T> {
    /// Boxes over the triangles of `mesh` in index order.
    pub fn new(mesh: &TriangleMesh) -> Self {
        let n = mesh.num_triangles();
        let boxes = (0..n)
            .step_by(LINEAR_BOX_SIZE)
            .map(|first| {
                let mut b = Aabb::EMPTY;
                for i in first..(first + LINEAR_BOX_SIZE).min(n) {
                    b = b.union(mesh.triangle_bounds(i));
                }
                NodeBox::from(b)
            })
            .collect();
        LinearBoxes {
            boxes,
            tris: LeafTriangles::new(mesh, (0..n as u32).collect()),
            bounds: mesh.bounds(),
        }
    }

    /// Number of boxes.
    pub fn num_boxes(&self) -> usize {
        self.boxes.len()
    }

    fn scan<const ANY: bool>(&self, ray: &Ray) -> (Option<Hit>, bool) {
        let rd = T::prepare(ray);
        let mut best = None;
        let mut tfar = ray.tfar;
        let n = self.tris.len();
        for (i, b) in self.boxes.iter().enumerate() {
            if b.entry(ray, ray.tnear, tfar) == f32::INFINITY {
                continue;
            }
            let first = i * LINEAR_BOX_SIZE;
            let count = LINEAR_BOX_SIZE.min(n - first);
            if self
                .tris
                .test::<ANY>(first, count, ray, &rd, &mut tfar, &mut best)
            {
                return (None, true);
            }
        }
        (best, false)
    }
}

impl<T: TriangleTest> Accel for LinearBoxes<T> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.scan::<false>(ray).0
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.scan::<true>(ray).1
    }

    /// The mesh bounds, then each box with its run of triangles.
    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        let n = self.tris.len();
        if n == 0 || !enter(&self.bounds) {
            return;
        }
        for (i, b) in self.boxes.iter().enumerate() {
            let region = Aabb::new(b.min.into(), b.max.into());
            if enter(&region) {
                let first = i * LINEAR_BOX_SIZE;
                leaf(self.tris.prims(first, LINEAR_BOX_SIZE.min(n - first)));
            }
        }
    }

    fn stats(&self) -> AccelStats {
        let node_bytes = std::mem::size_of_val(&self.boxes[..]);
        let root = self.bounds.surface_area().max(f32::MIN_POSITIVE) as f64;
        let n = self.tris.len();
        // Every box is tested; a box's triangles with the chance of entering it.
        let leaf_cost: f64 = (self.boxes.iter().enumerate())
            .map(|(i, b)| {
                let area = Aabb::new(b.min.into(), b.max.into()).surface_area() as f64;
                area / root * LINEAR_BOX_SIZE.min(n - i * LINEAR_BOX_SIZE) as f64
            })
            .sum();
        AccelStats {
            nodes: self.boxes.len() + 1,
            leaves: self.boxes.len(),
            bytes: node_bytes + self.tris.bytes(),
            node_bytes,
            depth: 1,
            sah_cost: self.boxes.len() as f64 + leaf_cost,
            triangle_refs: self.tris.len(),
        }
    }
}
