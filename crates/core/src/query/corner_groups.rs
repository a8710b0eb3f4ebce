//! The point tree's leaf triangles in structure of arrays: each leaf's
//! corners in groups of [`LANES`] triangles, one array per corner and axis,
//! so that the closest-point kernel (`super::closest`) loads a group's
//! coordinates as whole vectors instead of gathering them from the
//! triangles' corners on every visit.

use super::surface_node::{SurfaceNode, WIDTH};
use crate::accel::bvh::huge_pages;
use glam::Vec3;

/// Triangles per group: the lanes of the closest-point kernel.
pub(crate) const LANES: usize = 4;

/// The corners of [`LANES`] triangles: `[corner][axis][lane]`.
pub(crate) type Group = [[[f32; LANES]; 3]; 3];

/// The groups of a leaf triangle order: a leaf of `n` triangles takes
/// `ceil(n / LANES)` consecutive groups; lanes past a leaf's last triangle
/// repeat it.
#[derive(Default)]
pub(crate) struct CornerGroups {
    /// The groups' corners.
    pub(crate) corners: Vec<Group>,
    /// The leaf-order index of each group's first triangle (lane `k` is
    /// triangle `first[g] + k`).
    pub(crate) first: Vec<u32>,
}

impl CornerGroups {
    /// The groups of every leaf of `nodes`, whose triangles in leaf order
    /// are `tris`; each leaf slot's `child` is set to its first group.
    pub(crate) fn build(nodes: &mut [SurfaceNode], tris: &[[Vec3; 3]]) -> Self {
        let n: usize = nodes
            .iter()
            .flat_map(|node| node.count)
            .map(|c| (c as usize).div_ceil(LANES))
            .sum();
        // Allocated once, in huge pages where the system offers them: the
        // search reads groups all over the array.
        let mut groups = CornerGroups {
            corners: huge_pages::with_capacity(n),
            first: Vec::with_capacity(n),
        };
        for node in nodes.iter_mut() {
            for k in 0..WIDTH {
                if node.count[k] == 0 {
                    continue;
                }
                let (start, end) = (
                    node.first[k] as usize,
                    (node.first[k] + node.count[k]) as usize,
                );
                node.child[k] = groups.corners.len() as u32;
                for at in (start..end).step_by(LANES) {
                    groups
                        .corners
                        .push(group_of(&tris[at..end.min(at + LANES)]));
                    groups.first.push(at as u32);
                }
            }
        }
        groups
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        std::mem::size_of_val(&self.corners[..]) + std::mem::size_of_val(&self.first[..])
    }
}

/// The group of one to [`LANES`] triangles, the last repeated in the lanes
/// past them.
pub(crate) fn group_of(tris: &[[Vec3; 3]]) -> Group {
    let mut g = [[[0f32; LANES]; 3]; 3];
    for k in 0..LANES {
        let t = &tris[k.min(tris.len() - 1)];
        for (corner, out) in t.iter().zip(g.iter_mut()) {
            out[0][k] = corner.x;
            out[1][k] = corner.y;
            out[2][k] = corner.z;
        }
    }
    g
}
