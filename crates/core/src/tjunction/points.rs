//! Welding by exact position: the distinct points a T-junction search tests
//! against the edges (Kim 2013 tests "every other vertex"; vertices at one
//! position are one vertex for this purpose).

use crate::mesh::TriangleMesh;
use glam::Vec3;
use rayon::prelude::*;

/// The distinct positions used by a set of triangles, each named by the
/// smallest vertex index at that position, in ascending order of that index.
pub(crate) struct Points {
    /// Representative vertex index of each point, ascending.
    pub rep: Vec<u32>,
    /// Position of each point.
    pub pos: Vec<Vec3>,
}

impl Points {
    /// Number of distinct points.
    pub fn len(&self) -> usize {
        self.rep.len()
    }
}

/// Bit pattern of a position with `-0.0` turned into `0.0`, so that two
/// positions have the same key exactly when they are equal as f32 values
/// (NaN cannot occur: the mesh was validated).
#[inline]
pub(crate) fn position_key(p: Vec3) -> [u32; 3] {
    p.to_array().map(|c| (c + 0.0).to_bits())
}

/// The distinct points of triangles `tris` of `mesh`.
pub(crate) fn distinct_points(mesh: &TriangleMesh, tris: &[u32]) -> Points {
    let mut used = vec![false; mesh.positions.len()];
    for &t in tris {
        for &v in &mesh.indices[t as usize] {
            used[v as usize] = true;
        }
    }
    let mut order: Vec<([u32; 3], u32)> = used
        .iter()
        .enumerate()
        .filter(|(_, &u)| u)
        .map(|(i, _)| (position_key(mesh.positions[i]), i as u32))
        .collect();
    order.par_sort_unstable();
    let mut rep: Vec<u32> = order
        .chunk_by(|x, y| x.0 == y.0)
        .map(|group| group[0].1)
        .collect();
    rep.par_sort_unstable();
    let pos = rep.iter().map(|&i| mesh.positions[i as usize]).collect();
    Points { rep, pos }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_positions_are_one_point_named_by_the_smallest_index() {
        let m = TriangleMesh::new(
            vec![
                Vec3::new(5.0, 5.0, 5.0), // unused
                Vec3::X,
                Vec3::Y,
                Vec3::new(-0.0, 0.0, 0.0),
                Vec3::ZERO,
                Vec3::X,
            ],
            vec![[4, 1, 2], [3, 5, 2]],
        );
        let p = distinct_points(&m, &[0, 1]);
        assert_eq!(p.rep, vec![1, 2, 3]);
        assert_eq!(p.pos, vec![Vec3::X, Vec3::Y, Vec3::ZERO]);
        let p = distinct_points(&m, &[1]);
        assert_eq!(p.rep, vec![2, 3, 5]);
    }
}
