//! [`Bvh8`] handed over as plain nodes ([`FlatBvh8`]) for devices with a
//! node layout of their own.

use super::wide_bvh::Bvh8;
use super::wide_leaf::Leaves;
use super::wide_node::Child4;
use crate::accel::flat::{FlatBvh8, FlatChild, FlatNode8};
use crate::tri::TriangleTest;

impl<T: TriangleTest> Bvh8<T> {
    /// The tree as plain nodes: each slot's padded box and reference, with
    /// leaves as ranges of mesh triangle indices in leaf order (the order
    /// the CPU traversal tests them in; packs of four are unpacked).
    pub fn flat(&self) -> FlatBvh8 {
        let mut prims = Vec::with_capacity(self.stats.triangle_refs);
        let mut leaf = |c: Child4| -> FlatChild {
            if c.count == 0 {
                return if c.index == Child4::EMPTY.index {
                    FlatChild::Empty
                } else {
                    FlatChild::Inner(c.index)
                };
            }
            let first = prims.len() as u32;
            match &self.leaves {
                Leaves::Single(t) => {
                    prims.extend_from_slice(t.prims(c.index as usize, c.count as usize))
                }
                Leaves::Packed(p) => p.prims(c, &mut prims),
            }
            FlatChild::Leaf {
                first,
                count: c.count,
            }
        };
        let root = if self.stats.triangle_refs == 0 {
            FlatChild::Empty
        } else {
            leaf(self.root)
        };
        let nodes = self
            .nodes
            .iter()
            .map(|n| {
                let mut f = FlatNode8 {
                    min: [[f32::INFINITY; 3]; 8],
                    max: [[f32::NEG_INFINITY; 3]; 8],
                    child: [FlatChild::Empty; 8],
                };
                for s in 0..8 {
                    let b = n.boxes.get(s);
                    f.min[s] = b.min.to_array();
                    f.max[s] = b.max.to_array();
                    f.child[s] = leaf(n.child[s]);
                }
                f
            })
            .collect();
        FlatBvh8 {
            nodes,
            root,
            root_box: (self.root_box.min, self.root_box.max),
            prims,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{Accel, BuildOptions};
    use crate::mesh::TriangleMesh;
    use crate::tri::{Moller, Plucker};
    use glam::Vec3;

    fn soup(n: usize) -> TriangleMesh {
        let mut s = 0x9e3779b9u32;
        let mut r = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32
        };
        let mut v = Vec::new();
        for _ in 0..n {
            let c = Vec3::new(r(), r(), r()) * 10.0;
            for _ in 0..3 {
                v.push(c + Vec3::new(r(), r(), r()) - 0.5);
            }
        }
        let idx = (0..n as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        TriangleMesh::new(v, idx)
    }

    /// Every triangle appears in exactly one leaf, and every slot's box
    /// contains its subtree's triangles, for both kinds of leaves.
    fn check<T: TriangleTest>(mesh: &TriangleMesh) {
        let bvh = Bvh8::<T>::build(mesh, &BuildOptions::default());
        let f = bvh.flat();
        let mut seen = vec![0u32; mesh.num_triangles()];
        for &p in &f.prims {
            seen[p as usize] += 1;
        }
        assert!(seen.iter().all(|&c| c == 1), "each triangle in one leaf");
        assert_eq!(bvh.stats().triangle_refs, f.prims.len());
        // The corners under each slot lie inside its box.
        fn corners(f: &FlatBvh8, mesh: &TriangleMesh, c: FlatChild, out: &mut Vec<Vec3>) {
            match c {
                FlatChild::Empty => {}
                FlatChild::Leaf { first, count } => {
                    for &p in &f.prims[first as usize..(first + count) as usize] {
                        out.extend(mesh.triangle(p as usize));
                    }
                }
                FlatChild::Inner(i) => {
                    for &k in &f.nodes[i as usize].child {
                        corners(f, mesh, k, out);
                    }
                }
            }
        }
        for n in &f.nodes {
            for s in 0..8 {
                let mut pts = Vec::new();
                corners(&f, mesh, n.child[s], &mut pts);
                let (lo, hi) = (Vec3::from(n.min[s]), Vec3::from(n.max[s]));
                assert!(pts.iter().all(|p| p.cmpge(lo).all() && p.cmple(hi).all()));
            }
        }
    }

    #[test]
    fn flat_nodes_hold_every_triangle_inside_their_boxes() {
        let mesh = soup(3000);
        check::<Moller>(&mesh);
        check::<Plucker>(&mesh);
        check::<Plucker>(&soup(2));
        let empty = TriangleMesh::new(Vec::new(), Vec::new());
        let f = Bvh8::<Plucker>::build(&empty, &BuildOptions::default()).flat();
        assert_eq!(f.root, FlatChild::Empty);
    }
}
