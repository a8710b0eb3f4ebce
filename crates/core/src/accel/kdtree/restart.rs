//! kd-restart (Foley & Sugerman 2005): stackless, every leaf found by a new
//! descent from the root.

use super::base::KdTree;
use super::KdOptions;
use crate::aabb::Aabb;
use crate::accel::{Accel, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// kd-restart (Foley & Sugerman 2005, "KD-tree acceleration structures for
/// a GPU raytracer"): no stack; after a leaf without a hit inside its
/// segment, the segment start moves to the leaf's exit and the descent
/// restarts at the root. Needs no memory beyond the tree but re-traverses
/// the upper levels once per leaf visited.
pub struct KdRestart<T: TriangleTest> {
    tree: KdTree<T>,
}

/// Descend from `node` to the leaf the segment `[tmin, tmax]` enters
/// first; returns the leaf's index and the segment's end inside it. A plane at
/// exactly `tmin` sends the ray to the far side, so a leaf is never entered
/// again at its own exit.
#[inline(always)]
pub(crate) fn descend<T: TriangleTest>(
    tree: &KdTree<T>,
    mut node: u32,
    ray: &Ray,
    tmin: f32,
    mut tmax: f32,
) -> (u32, f32) {
    loop {
        let n = tree.nodes[node as usize];
        if n.is_leaf() {
            return (node, tmax);
        }
        let a = n.axis();
        let split = n.split();
        let (o, d) = (ray.origin[a], ray.dir[a]);
        let ts = (split - o) * ray.inv_dir[a];
        let below_first = o < split || (o == split && d <= 0.0);
        let c = n.first_child();
        let (first, second) = if below_first { (c, c + 1) } else { (c + 1, c) };
        // A plane at or behind the origin is crossed, in order of `t`,
        // from the far side to the near one (a segment that starts behind
        // the origin, negative tnear).
        if ts.is_nan() {
            node = first;
        } else if ts > 0.0 {
            if ts > tmax {
                node = first;
            } else if ts <= tmin {
                node = second;
            } else {
                node = first;
                tmax = ts;
            }
        } else if ts <= tmin {
            node = first;
        } else if ts >= tmax {
            node = second;
        } else {
            node = second;
            tmax = ts;
        }
    }
}

impl<T: TriangleTest> KdRestart<T> {
    /// Build over all triangles of `mesh`.
    pub fn build(mesh: &TriangleMesh, opts: &KdOptions) -> Self {
        Self::from_tree(KdTree::build(mesh, opts))
    }

    /// Traverse an already built tree.
    pub fn from_tree(tree: KdTree<T>) -> Self {
        KdRestart { tree }
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
        loop {
            let (leaf, tmax) = descend(t, 0, ray, tmin, scene_exit);
            let leaf = t.nodes[leaf as usize];
            if t.test_leaf::<ANY>(leaf, ray, &rd, &mut tfar, &mut best) {
                return (None, true);
            }
            if tfar <= tmax || tmax >= scene_exit {
                return (best, false);
            }
            tmin = tmax;
        }
    }
}

kd_accel!(KdRestart, self => 0);
