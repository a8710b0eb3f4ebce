//! Front propagation from the grid's outer boundary (Min 2008, second stage).

use crate::grid::Grid;

/// Min's (2008) fast-marching tags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Tag {
    /// Not reached: inside the model (or in a cavity closed off from outside).
    Far = 0,
    /// On the front: reached, neighbours not yet examined.
    Trial = 1,
    /// Outside: reached and its neighbours examined.
    Known = 2,
}

/// The result of front propagation: a tag per grid point; `Known` points are
/// outside, `Far` points inside.
#[derive(Clone, Debug)]
pub struct Classification {
    /// Tag per grid point (linear index of [`Grid::index`]).
    pub tags: Vec<Tag>,
    /// Number of outside (`Known`) points.
    pub outside: usize,
}

impl Classification {
    /// True when the point with linear index `idx` is outside.
    #[inline]
    pub fn is_outside(&self, idx: usize) -> bool {
        self.tags[idx] == Tag::Known
    }
}

/// Classify every grid point as outside or inside (Min 2008, second stage).
///
/// The front starts at the grid's boundary points (outside by construction)
/// and moves inwards: a neighbour `q` of a `Known` point `p` becomes `Trial`
/// when the step between them is free — `p`'s directed distance towards `q`
/// exceeds `|pq|`, bit `axis` of `free[min(p, q)]` from
/// [`crate::DirectedDistanceField::free_steps`]. The front is processed in
/// first-in first-out order, which on a grid of equal spacings is fast
/// marching's arrival order for unit speed (the arrival time is the number
/// of steps), so no heap is needed. Every point reached is `Known` at the end.
pub fn propagate(grid: &Grid, free: &[u8]) -> Classification {
    assert_eq!(free.len(), grid.len(), "one free-step byte per grid point");
    let mut tags = vec![Tag::Far; grid.len()];
    let mut front: Vec<u32> = Vec::new();
    for (idx, tag) in tags.iter_mut().enumerate() {
        if grid.is_boundary(grid.coords(idx)) {
            *tag = Tag::Trial;
            front.push(idx as u32);
        }
    }
    let strides = [0, 1, 2].map(|a| grid.stride(a));
    let mut head = 0;
    while head < front.len() {
        let idx = front[head] as usize;
        head += 1;
        tags[idx] = Tag::Known;
        let c = grid.coords(idx);
        for axis in 0..3 {
            let s = strides[axis];
            if c[axis] + 1 < grid.dims[axis] && free[idx] & (1 << axis) != 0 {
                let q = idx + s;
                if tags[q] == Tag::Far {
                    tags[q] = Tag::Trial;
                    front.push(q as u32);
                }
            }
            if c[axis] > 0 && free[idx - s] & (1 << axis) != 0 {
                let q = idx - s;
                if tags[q] == Tag::Far {
                    tags[q] = Tag::Trial;
                    front.push(q as u32);
                }
            }
        }
    }
    Classification {
        outside: front.len(),
        tags,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::{Aabb, Vec3};

    #[test]
    fn a_closed_wall_of_blocked_steps_keeps_the_middle_inside() {
        let g = Grid::around(&Aabb::new(Vec3::ZERO, Vec3::ONE), 9);
        let mut free = vec![7u8; g.len()];
        // Block every step into or out of the centre point.
        let centre = g.index([4, 4, 4]);
        for a in 0..3 {
            free[centre] &= !(1 << a);
            free[centre - g.stride(a)] &= !(1 << a);
        }
        let c = propagate(&g, &free);
        assert_eq!(c.outside, g.len() - 1);
        assert_eq!(c.tags[centre], Tag::Far);
        // With nothing blocked, everything is outside.
        let c = propagate(&g, &vec![7u8; g.len()]);
        assert_eq!(c.outside, g.len());
    }
}
