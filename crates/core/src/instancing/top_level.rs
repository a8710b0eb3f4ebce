//! The top level of the two-level BVH: an 8-wide BVH over the instances'
//! world boxes (Wald et al. 2014, "Embree: a kernel framework for efficient
//! CPU ray tracing": a BVH over instances whose leaves hold the instances'
//! own BVHs; pbrt-v4's `BVHAggregate` over `TransformedPrimitive`s).
//!
//! It is made by the binned-SAH build of the triangle BVHs run over boxes
//! ([`crate::accel::bvh::build::build_over_boxes`], one instance per leaf)
//! and collapsed to nodes of up to eight children the way the wide BVHs
//! are (the largest-area inner child's two children pulled up first).
//! A node holds its children's boxes in structure-of-arrays layout, so one
//! ray is tested against all eight in loops that compile to SIMD.

use crate::aabb::Aabb;
use crate::accel::bvh::build::{build_over_boxes, BuildNode};
use crate::accel::BuildOptions;
use crate::query::all_hits::slab8;
use crate::query::point_tree::{root_slots, set_slot_box, stack_need, widen};
use crate::ray::Ray;
use glam::Vec3;

/// Children per node.
const WIDTH: usize = 8;
/// A slot with no child.
const EMPTY: u32 = u32::MAX;
/// Stack entries kept on the machine stack; deeper trees use the heap.
const SMALL_STACK: usize = 128;

/// An inner node: up to eight children's boxes, and per child an inner
/// node (`count == 0`, `child` its index), a leaf (`count > 0`, `child` its
/// first entry of the instance order) or nothing (`child == EMPTY`, empty
/// box).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct TopNode {
    min: [[f32; WIDTH]; 3],
    max: [[f32; WIDTH]; 3],
    child: [u32; WIDTH],
    count: [u32; WIDTH],
}

impl Default for TopNode {
    fn default() -> Self {
        TopNode {
            min: [[f32::INFINITY; WIDTH]; 3],
            max: [[f32::NEG_INFINITY; WIDTH]; 3],
            child: [EMPTY; WIDTH],
            count: [0; WIDTH],
        }
    }
}

/// The 8-wide BVH over instance boxes. The root is node 0; a scene without
/// (non-empty) instances has no nodes.
pub(crate) struct TopLevelBvh {
    nodes: Vec<TopNode>,
    /// Instance ids in leaf order.
    order: Vec<u32>,
    /// Most stack entries a walk can need.
    stack_need: usize,
}

impl TopLevelBvh {
    /// Build over `boxes[i]` for the instances `ids[i]` (finite, non-empty
    /// boxes only).
    pub(crate) fn build(boxes: &[Aabb], ids: &[u32]) -> Self {
        let mut top = TopLevelBvh {
            nodes: Vec::new(),
            order: Vec::new(),
            stack_need: 1,
        };
        if boxes.is_empty() {
            return top;
        }
        let options = BuildOptions {
            max_leaf_size: 1,
            ..BuildOptions::default()
        };
        let tree = build_over_boxes(boxes, &options);
        top.order = tree.order.iter().map(|&i| ids[i as usize]).collect();
        top.nodes.push(TopNode::default());
        let depth = top.fill(0, &root_slots(&tree.root));
        top.stack_need = stack_need(depth);
        top
    }

    /// Fill node `at` with `slots`; returns the inner levels from `at` down.
    fn fill(&mut self, at: usize, slots: &[&BuildNode]) -> usize {
        let mut node = TopNode::default();
        let mut inner = Vec::new();
        for (k, s) in slots.iter().enumerate() {
            set_slot_box(&mut node.min, &mut node.max, k, &s.bounds());
            match s {
                BuildNode::Leaf { first, count, .. } => {
                    node.child[k] = *first;
                    node.count[k] = *count;
                }
                BuildNode::Inner { .. } => {
                    node.child[k] = self.nodes.len() as u32;
                    self.nodes.push(TopNode::default());
                    inner.push((self.nodes.len() - 1, *s));
                }
            }
        }
        self.nodes[at] = node;
        let mut depth = 1;
        for (idx, s) in inner {
            depth = depth.max(1 + self.fill(idx, &widen(s)));
        }
        depth
    }

    /// Number of nodes.
    pub(crate) fn num_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes held by the nodes and the instance order.
    pub(crate) fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<TopNode>() + self.order.len() * 4
    }

    /// Walk the instances whose boxes `ray` enters within `reach()`, nearest
    /// box first: `visit(instance)` returns false to stop. `reach` is read
    /// again before each node, so a query that shortens the ray prunes the
    /// boxes behind its nearest hit. A ray that is not valid
    /// ([`Ray::is_valid`]: NaN, infinite, zero direction) visits nothing.
    #[inline]
    pub(crate) fn walk(
        &self,
        ray: &Ray,
        reach: impl FnMut() -> f32,
        visit: impl FnMut(u32) -> bool,
    ) {
        let mut small = [(0u32, 0u32, 0f32); SMALL_STACK];
        let mut big = Vec::new();
        let stack: &mut [(u32, u32, f32)] = if self.stack_need <= SMALL_STACK {
            &mut small
        } else {
            big.resize(self.stack_need, (0, 0, 0.0));
            &mut big
        };
        self.walk_on(stack, ray, reach, visit);
    }

    /// Every instance in a leaf whose box and whose ancestors' boxes all
    /// pass `keep(min, max)`, in no particular order: a walk for a
    /// bounding volume of many rays (a cone, a frustum) instead of one ray.
    pub(crate) fn each_kept(&self, keep: impl Fn(Vec3, Vec3) -> bool, mut visit: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            for k in 0..WIDTH {
                if node.child[k] == EMPTY {
                    continue;
                }
                let min = Vec3::new(node.min[0][k], node.min[1][k], node.min[2][k]);
                let max = Vec3::new(node.max[0][k], node.max[1][k], node.max[2][k]);
                if !keep(min, max) {
                    continue;
                }
                let (child, count) = (node.child[k], node.count[k]);
                if count > 0 {
                    for &inst in &self.order[child as usize..(child + count) as usize] {
                        visit(inst);
                    }
                } else {
                    stack.push(child);
                }
            }
        }
    }

    /// A stack that [`TopLevelBvh::walk_on`] can use, for a caller that
    /// walks many rays.
    pub(crate) fn stack(&self) -> Vec<(u32, u32, f32)> {
        vec![(0, 0, 0.0); self.stack_need.max(1)]
    }

    /// [`TopLevelBvh::walk`] on `stack` (from [`TopLevelBvh::stack`]).
    #[inline]
    pub(crate) fn walk_on(
        &self,
        stack: &mut [(u32, u32, f32)],
        ray: &Ray,
        mut reach: impl FnMut() -> f32,
        mut visit: impl FnMut(u32) -> bool,
    ) {
        if self.nodes.is_empty() || !ray.is_valid() {
            return;
        }
        stack[0] = (0, 0, ray.tnear);
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (child, count, entry) = stack[sp];
            let tfar = reach();
            if entry > tfar {
                continue;
            }
            if count > 0 {
                for &inst in &self.order[child as usize..(child + count) as usize] {
                    if !visit(inst) {
                        return;
                    }
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let entry = slab8(&node.min, &node.max, &node.child, ray, tfar);
            // Far children pushed first, so that the nearest is popped first.
            let mut order = [(0f32, 0usize); WIDTH];
            let mut n = 0;
            for (k, &e) in entry.iter().enumerate() {
                if e <= tfar {
                    let mut i = n;
                    while i > 0 && order[i - 1].0 < e {
                        order[i] = order[i - 1];
                        i -= 1;
                    }
                    order[i] = (e, k);
                    n += 1;
                }
            }
            for &(e, k) in &order[..n] {
                stack[sp] = (node.child[k], node.count[k], e);
                sp += 1;
            }
        }
    }
}
