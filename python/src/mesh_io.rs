//! `load_mesh`: any mesh file raykit reads, as numpy arrays.

use crate::errors::load_error;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use std::path::PathBuf;

/// Load OBJ, PLY (also `.ply.gz`), STL, OFF, glTF or GLB (chosen by the
/// extension, as `raykit_io::load_keeping_precision`): `(vertices (n, 3)
/// float32, triangles (m, 3) uint32, parts (m,) uint32, origin (x, y, z))`,
/// `parts` giving each triangle's part (glTF node, OBJ object or group; 0
/// when the file has none), and the vertices relative to `origin` (zero
/// unless the mesh lies far from the coordinates' origin).
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn load_mesh(
    py: Python<'_>,
    path: PathBuf,
) -> PyResult<(
    Bound<'_, PyArray2<f32>>,
    Bound<'_, PyArray2<u32>>,
    Bound<'_, PyArray1<u32>>,
    [f64; 3],
)> {
    let loaded = py
        .detach(|| raykit_io::load_keeping_precision(&path))
        .map_err(load_error)?;
    let mesh = loaded.mesh;
    let n = mesh.positions.len();
    let m = mesh.num_triangles();
    let parts: Vec<u32> = (0..m).map(|i| mesh.part_of(i)).collect();
    let v: Vec<f32> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
    let t: Vec<u32> = mesh.indices.iter().flatten().copied().collect();
    let v = Array2::from_shape_vec((n, 3), v).expect("three per vertex");
    let t = Array2::from_shape_vec((m, 3), t).expect("three per triangle");
    Ok((
        v.into_pyarray(py),
        t.into_pyarray(py),
        parts.into_pyarray(py),
        loaded.origin,
    ))
}
