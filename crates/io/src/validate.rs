//! The last step of every loader: an empty mesh or a mesh that breaks the
//! [`TriangleMesh`] invariants becomes a [`LoadError`].

use crate::error::{ErrorKind, LoadError, Location};
use raykit_core::TriangleMesh;
use std::path::Path;

/// Check `mesh` from `path`; `end` is the location of the end of the file,
/// reported when there are no triangles.
pub(crate) fn finish(
    path: &Path,
    mesh: TriangleMesh,
    end: Location,
) -> Result<TriangleMesh, LoadError> {
    if mesh.indices.is_empty() {
        return Err(LoadError::new(
            path,
            ErrorKind::Empty,
            end,
            "the file has no triangles (reached the end of the file)",
        ));
    }
    match mesh.validate() {
        Ok(()) => Ok(mesh),
        Err(e) => Err(LoadError::new(
            path,
            ErrorKind::Malformed,
            Location::File,
            format!("the loaded mesh is invalid: {e}"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::Vec3;

    #[test]
    fn an_empty_mesh_is_an_error() {
        let e = finish(
            Path::new("a.obj"),
            TriangleMesh::default(),
            Location::Line(3),
        )
        .unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Empty);
        assert!(e.to_string().starts_with("a.obj:3: "));
        let m = TriangleMesh::new(vec![Vec3::ZERO; 3], vec![[0, 1, 2]]);
        assert!(finish(Path::new("a"), m, Location::File).is_ok());
    }
}
