//! kd-tree traversal with a fixed-size per-ray stack.

use super::base::KdTree;
use super::{KdOptions, MAX_KD_DEPTH};
use crate::aabb::Aabb;
use crate::accel::{Accel, AccelStats};
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// kd-tree traversal with a per-ray stack (after Havran's TA_B^rec): clip the
/// ray to the scene cell; at an inner node compare the distance to the split
/// plane with the segment `[tmin, tmax]`; visit the near child and push the far
/// one with its segment when the ray crosses the plane inside the segment. At a
/// leaf, stop when the nearest hit lies within the leaf's segment, else pop.
/// The stack is a fixed array of [`MAX_KD_DEPTH`] entries (the builds never
/// exceed that depth), no node is visited twice.
pub struct KdStack<T: TriangleTest> {
    tree: KdTree<T>,
}

impl<T: TriangleTest> KdStack<T> {
    /// Build over all triangles of `mesh`.
    pub fn build(mesh: &TriangleMesh, opts: &KdOptions) -> Self {
        Self::from_tree(KdTree::build(mesh, opts))
    }

    /// Traverse an already built tree.
    pub fn from_tree(tree: KdTree<T>) -> Self {
        KdStack { tree }
    }

    /// The underlying tree.
    pub fn tree(&self) -> &KdTree<T> {
        &self.tree
    }

    fn visit(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        self.tree.visit(enter, leaf)
    }

    #[inline(always)]
    fn traverse<const ANY: bool>(&self, ray: &Ray) -> (Option<Hit>, bool) {
        let t = &self.tree;
        let Some((mut tmin, mut tmax)) = t.clip_root(ray) else {
            return (None, false);
        };
        let rd = T::prepare(ray);
        let mut tfar = ray.tfar;
        let mut best = None;
        let o = ray.origin.to_array();
        let d = ray.dir.to_array();
        let inv = ray.inv_dir.to_array();
        let mut stack = [(0u32, 0f32, 0f32); MAX_KD_DEPTH];
        let mut sp = 0usize;
        let mut node = 0u32;
        loop {
            let n = t.nodes[node as usize];
            if !n.is_leaf() {
                let a = n.axis();
                let split = n.split();
                let ts = (split - o[a]) * inv[a];
                let below_first = o[a] < split || (o[a] == split && d[a] <= 0.0);
                let c = n.first_child();
                let (first, second) = if below_first { (c, c + 1) } else { (c + 1, c) };
                // A NaN (ray lying in the plane) goes to the near side only.
                // A plane at or behind the origin is crossed, in order of
                // `t`, from the far side to the near one: it matters for a
                // segment that starts behind the origin (negative tnear).
                let behind = ts <= 0.0;
                let (enter, leave) = if behind {
                    (second, first)
                } else {
                    (first, second)
                };
                if ts.is_nan() || (!behind && ts > tmax) || (behind && ts <= tmin) {
                    node = first;
                } else if (!behind && ts < tmin) || (behind && ts >= tmax) {
                    node = second;
                } else {
                    stack[sp] = (leave, ts, tmax);
                    sp += 1;
                    node = enter;
                    tmax = ts;
                }
                continue;
            }
            if t.test_leaf::<ANY>(n, ray, &rd, &mut tfar, &mut best) {
                return (None, true);
            }
            if tfar <= tmax {
                return (best, false);
            }
            loop {
                if sp == 0 {
                    return (best, false);
                }
                sp -= 1;
                let (nd, t0, t1) = stack[sp];
                if t0 <= tfar {
                    (node, tmin, tmax) = (nd, t0, t1);
                    break;
                }
            }
        }
    }
}

kd_accel!(KdStack, self => 0);
