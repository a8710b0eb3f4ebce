//! `load_mesh`: any mesh file raykit reads, as numpy arrays.

use crate::errors::load_error;
use crate::threads::detached;
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
    let loaded =
        detached(py, 0, || raykit_io::load_keeping_precision(&path))?.map_err(load_error)?;
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

/// A glTF file's meshes, each once, and the nodes placing them: one
/// geometry per glTF mesh as `(vertices (n, 3) float32, triangles (m, 3)
/// uint32)` in the mesh's own coordinates, one instance per node with a
/// mesh (each copy of an `EXT_mesh_gpu_instancing` node) as `(geometry,
/// (3, 4) float64 object-to-world matrix composed in float64 from the
/// file's values, node index, name)` in the
/// flattened load's part order, and the loader's warnings.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn load_gltf_instances(
    py: Python<'_>,
    path: PathBuf,
) -> PyResult<(
    Vec<(Bound<'_, PyArray2<f32>>, Bound<'_, PyArray2<u32>>)>,
    Vec<(u32, Bound<'_, PyArray2<f64>>, u32, String)>,
    Vec<String>,
)> {
    let loaded = detached(py, 0, || raykit_io::load_gltf_instances(&path))?.map_err(load_error)?;
    let geometries = loaded
        .geometries
        .iter()
        .map(|g| {
            let v: Vec<f32> = g.positions.iter().flat_map(|p| p.to_array()).collect();
            let t: Vec<u32> = g.indices.iter().flatten().copied().collect();
            let v = Array2::from_shape_vec((g.positions.len(), 3), v).expect("three per vertex");
            let t = Array2::from_shape_vec((g.num_triangles(), 3), t).expect("three per triangle");
            (v.into_pyarray(py), t.into_pyarray(py))
        })
        .collect();
    let instances = loaded
        .instances
        .iter()
        .map(|i| {
            let m = i.to_world_f64.matrix3;
            let c = i.to_world_f64.translation;
            let rows: Vec<f64> = (0..3)
                .flat_map(|r| [m.x_axis[r], m.y_axis[r], m.z_axis[r], c[r]])
                .collect();
            let matrix = Array2::from_shape_vec((3, 4), rows).expect("a 3 × 4 matrix");
            (i.geometry, matrix.into_pyarray(py), i.node, i.name.clone())
        })
        .collect();
    Ok((geometries, instances, loaded.warnings))
}
