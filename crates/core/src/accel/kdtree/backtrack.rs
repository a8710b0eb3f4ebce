//! kd-backtrack (Foley & Sugerman 2005): stackless, climbing parent links
//! to the lowest ancestor the rest of the ray still passes through.

use super::base::KdTree;
use super::restart::descend;
use super::KdOptions;
use crate::aabb::Aabb;
use crate::accel::{Accel, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// kd-backtrack (Foley & Sugerman 2005): every node also stores its cell and
/// its parent; after a leaf without a hit inside its segment the traversal
/// climbs to the first ancestor whose cell the ray leaves beyond the
/// current point and descends from there, instead of from the root as
/// kd-restart does. Costs 28 extra bytes per node.
pub struct KdBacktrack<T: TriangleTest> {
    tree: KdTree<T>,
    cells: Vec<Aabb>,
    parents: Vec<u32>,
}

/// Where the ray leaves `cell` (the nearest far face), ignoring axes the
/// ray does not move along.
#[inline(always)]
fn cell_exit(cell: &Aabb, ray: &Ray) -> f32 {
    let mut exit = f32::INFINITY;
    for a in 0..3 {
        let d = ray.dir[a];
        if d != 0.0 {
            let face = if d > 0.0 { cell.max[a] } else { cell.min[a] };
            exit = exit.min((face - ray.origin[a]) * ray.inv_dir[a]);
        }
    }
    exit
}

impl<T: TriangleTest> KdBacktrack<T> {
    /// Build over all triangles of `mesh`.
    pub fn build(mesh: &TriangleMesh, opts: &KdOptions) -> Self {
        Self::from_tree(KdTree::build(mesh, opts))
    }

    /// Traverse an already built tree.
    pub fn from_tree(tree: KdTree<T>) -> Self {
        let (cells, parents) = tree.cells_and_parents();
        KdBacktrack {
            tree,
            cells,
            parents,
        }
    }

    fn visit(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        self.tree.visit(enter, leaf)
    }

    #[inline(always)]
    fn traverse<const ANY: bool>(&self, ray: &Ray) -> (Option<Hit>, bool) {
        let t = &self.tree;
        let Some((mut tmin, scene_exit)) = t.clip_root(ray) else {
            return (None, false);
        };
        let rd = T::prepare(ray);
        let mut tfar = ray.tfar;
        let mut best = None;
        let mut start = 0u32;
        let mut start_exit = scene_exit;
        loop {
            let (leaf_index, tmax) = descend(t, start, ray, tmin, start_exit);
            let leaf = t.nodes[leaf_index as usize];
            if t.test_leaf::<ANY>(leaf, ray, &rd, &mut tfar, &mut best) {
                return (None, true);
            }
            if tfar <= tmax || tmax >= scene_exit {
                return (best, false);
            }
            tmin = tmax;
            // Climb to the lowest ancestor the ray leaves after `tmin`.
            let mut node = leaf_index;
            loop {
                node = self.parents[node as usize];
                if node == 0 {
                    start_exit = scene_exit;
                    break;
                }
                let exit = cell_exit(&self.cells[node as usize], ray);
                if exit > tmin {
                    start_exit = exit.min(scene_exit);
                    break;
                }
            }
            start = node;
        }
    }
}

kd_accel!(KdBacktrack, self => std::mem::size_of_val(&self.cells[..]) + std::mem::size_of_val(&self.parents[..]));
