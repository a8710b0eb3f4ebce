//! What the scene builder refuses, each error naming the geometry or
//! instance at fault.

use super::transform::TransformError;
use crate::mesh::MeshError;
use std::fmt;

/// An error of [`super::SceneBuilder`]: a bad mesh, a reference to a
/// geometry or instance that does not exist, or a transform that cannot be
/// inverted.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneError {
    /// Geometry `geometry`'s mesh breaks an invariant of
    /// [`crate::TriangleMesh::validate`] (an empty mesh is accepted).
    BadMesh {
        /// The id the geometry would have had.
        geometry: u32,
        /// What is wrong with the mesh.
        error: MeshError,
    },
    /// An instance refers to a geometry that does not exist.
    UnknownGeometry {
        /// The instance (the id it would have had).
        instance: u32,
        /// The instance's name, if it has one.
        name: Option<String>,
        /// The geometry asked for.
        geometry: u32,
        /// Geometries in the scene.
        count: usize,
    },
    /// An instance's transform is not finite or not invertible.
    BadTransform {
        /// The instance (the id it would have had).
        instance: u32,
        /// The instance's name, if it has one.
        name: Option<String>,
        /// What is wrong with the transform.
        problem: TransformError,
    },
    /// A mask was set on a geometry or instance that does not exist.
    UnknownId {
        /// `"geometry"` or `"instance"`.
        what: &'static str,
        /// The id asked for.
        id: u32,
        /// How many there are.
        count: usize,
    },
}

/// `instance 3` or `instance 3 ("wheel")`.
fn instance_label(f: &mut fmt::Formatter<'_>, instance: u32, name: &Option<String>) -> fmt::Result {
    match name {
        Some(n) => write!(f, "instance {instance} ({n:?})"),
        None => write!(f, "instance {instance}"),
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SceneError::BadMesh { geometry, error } => write!(f, "geometry {geometry}: {error}"),
            SceneError::UnknownGeometry {
                instance,
                name,
                geometry,
                count,
            } => {
                instance_label(f, *instance, name)?;
                write!(
                    f,
                    ": geometry {geometry} does not exist (the scene has {count})"
                )
            }
            SceneError::BadTransform {
                instance,
                name,
                problem,
            } => {
                instance_label(f, *instance, name)?;
                write!(f, ": {problem}")
            }
            SceneError::UnknownId { what, id, count } => {
                write!(f, "{what} {id} does not exist (the scene has {count})")
            }
        }
    }
}

impl std::error::Error for SceneError {}
