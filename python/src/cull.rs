//! `cull`: global visibility culling of CAD models (raykit-cull: directed distance field and front propagation) on numpy arrays.

use crate::arrays::{flat, rows};
use crate::errors::value_error;
use crate::threads::detached;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use raykit_core::{Part, TriangleMesh, Vec3};
use raykit_cull::CullOptions;

/// Part ids below this many are accepted whatever the triangle count
/// (ids may skip numbers, as a file's parts without triangles do); above
/// it, only ids below the number of triangles, so that a stray large id
/// does not make the cull allocate a part record for every id up to it.
const MAX_PARTS: usize = 1 << 20;

/// Which triangles (and parts) of the mesh can be seen from outside it:
/// `(keep (m,) bool, part_keep (p,) bool, stats dict)`. `parts` (uint32,
/// one per triangle) groups triangles into parts; `conservative` keeps
/// what the evidence does not clearly hide (the command line's default),
/// off is the distance-field rule alone.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, parts=None, resolution=128, conservative=true, threads=0))]
#[allow(clippy::type_complexity)]
pub fn cull<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f32>,
    triangles: PyReadonlyArray2<'py, u32>,
    parts: Option<PyReadonlyArray1<'py, u32>>,
    resolution: i64,
    conservative: bool,
    threads: i64,
) -> PyResult<(
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyDict>,
)> {
    if !(4..=2048).contains(&resolution) {
        return Err(value_error(format!(
            "resolution must be between 4 and 2048 grid points, got {resolution}"
        )));
    }
    let resolution = resolution as usize;
    let (v, _) = rows(&vertices, 3, "vertices")?;
    let (t, m) = rows(&triangles, 3, "triangles")?;
    let mut mesh = TriangleMesh::new(
        v.chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect(),
        t.chunks_exact(3).map(|i| [i[0], i[1], i[2]]).collect(),
    );
    if let Some(parts) = &parts {
        let p = flat(parts, "parts")?;
        if p.len() != m {
            return Err(value_error(format!(
                "parts has {} entries, expected one per triangle ({m})",
                p.len()
            )));
        }
        let count = p.iter().max().map_or(0, |&x| x as usize + 1);
        if count > m.max(MAX_PARTS) {
            return Err(value_error(format!(
                "parts: the largest part id is {}, but ids must be below the number of \
                 triangles ({m}) or {MAX_PARTS}, whichever is larger",
                count - 1
            )));
        }
        mesh.parts = (0..count)
            .map(|i| Part {
                name: format!("part {i}"),
                node: None,
            })
            .collect();
        mesh.tri_part = p.to_vec();
    }
    let options = if conservative {
        CullOptions::conservative(resolution)
    } else {
        CullOptions::paper(resolution)
    };
    let result = detached(py, threads, || raykit_cull::cull(&mesh, &options))?
        .map_err(|e| value_error(e.to_string()))?;
    let s = &result.stats;
    let stats = PyDict::new(py);
    stats.set_item("grid", s.grid.to_vec())?;
    stats.set_item("spacing", s.spacing)?;
    stats.set_item("outside_points", s.outside_points)?;
    stats.set_item("triangles", s.triangles)?;
    stats.set_item("triangles_removed", s.triangles_removed)?;
    stats.set_item("parts", s.parts)?;
    stats.set_item("parts_removed", s.parts_removed)?;
    stats.set_item("distance_field_seconds", s.distance_field_seconds)?;
    stats.set_item("propagation_seconds", s.propagation_seconds)?;
    stats.set_item("visible_seconds", s.visible_seconds)?;
    Ok((
        result.visible.into_pyarray(py),
        result.part_visible.into_pyarray(py),
        stats,
    ))
}
