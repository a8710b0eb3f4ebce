//! The mesh a depth map is rendered from: without repeated triangles. A
//! depth map keeps only the distance to the nearest surface, which a copy
//! of a triangle (the same three corners, in any order) cannot change; but
//! every copy covers the whole of its triangle's texels again, so a file
//! holding one triangle 20,000 times made the rasterizer test each texel
//! 20,000 times (Williams 1978's maps depend on the surface, not on how
//! often it is listed).

use raykit_core::TriangleMesh;
use std::borrow::Cow;
use std::collections::HashSet;

/// `mesh` without the triangles whose three corners (by position, in any
/// order) an earlier triangle already has; `mesh` itself when none repeat.
pub(crate) fn distinct_triangles(mesh: &TriangleMesh) -> Cow<'_, TriangleMesh> {
    let mut seen = HashSet::with_capacity(mesh.num_triangles());
    let keep: Vec<bool> = (0..mesh.num_triangles())
        .map(|t| {
            let mut key = mesh.triangle(t).map(|p| p.to_array().map(f32::to_bits));
            key.sort_unstable();
            seen.insert(key)
        })
        .collect();
    if keep.iter().all(|&k| k) {
        return Cow::Borrowed(mesh);
    }
    let indices = mesh
        .indices
        .iter()
        .zip(&keep)
        .filter(|(_, &k)| k)
        .map(|(i, _)| *i)
        .collect();
    Cow::Owned(TriangleMesh::new(mesh.positions.clone(), indices))
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::Vec3;

    #[test]
    fn copies_in_any_corner_order_are_dropped_and_distinct_triangles_kept() {
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let positions = vec![
            p(0.0, 0.0, 0.0),
            p(1.0, 0.0, 0.0),
            p(0.0, 1.0, 0.0),
            p(1.0, 0.0, 0.0), // a second vertex at corner 1's position
            p(0.0, 0.0, 1.0),
        ];
        let indices = vec![[0, 1, 2], [2, 0, 3], [1, 2, 0], [0, 1, 4], [0, 4, 1]];
        let mesh = TriangleMesh::new(positions, indices);
        let d = distinct_triangles(&mesh);
        assert_eq!(d.indices, vec![[0, 1, 2], [0, 1, 4]]);
        let once = TriangleMesh::new(mesh.positions.clone(), vec![[0, 1, 2], [0, 1, 4]]);
        assert!(matches!(distinct_triangles(&once), Cow::Borrowed(_)));
    }
}
