//! Ray answers as the columns of Open3D's result dicts: the nearest hit of
//! each ray (`t_hit`, ids, uvs, normals), and the hits of many rays laid
//! out one ray after another with `ray_splits`.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;

/// The value of `geometry_ids` and `primitive_ids` for a ray that hits
/// nothing (Open3D's `RaycastingScene.INVALID_ID`).
pub const INVALID_ID: u32 = u32::MAX;

/// The nearest hits of `n` rays, one column per field; a miss has `t`
/// inf, [`INVALID_ID`] ids and zero uvs and normal.
pub(crate) struct HitColumns {
    pub(crate) t: Vec<f32>,
    pub(crate) geometry: Vec<u32>,
    pub(crate) instance: Vec<u32>,
    pub(crate) prim: Vec<u32>,
    pub(crate) uv: Vec<f32>,
    pub(crate) normal: Vec<f32>,
}

impl HitColumns {
    /// Columns of `n` rows of zeros, for a caller that writes every row
    /// (the memory is mapped as it is written).
    pub(crate) fn zeroed(n: usize) -> Self {
        HitColumns {
            t: vec![0.0; n],
            geometry: vec![0; n],
            instance: vec![0; n],
            prim: vec![0; n],
            uv: vec![0.0; 2 * n],
            normal: vec![0.0; 3 * n],
        }
    }

    /// The columns of `n` misses.
    pub(crate) fn misses(n: usize) -> Self {
        HitColumns {
            t: vec![f32::INFINITY; n],
            geometry: vec![INVALID_ID; n],
            instance: vec![INVALID_ID; n],
            prim: vec![INVALID_ID; n],
            uv: vec![0.0; 2 * n],
            normal: vec![0.0; 3 * n],
        }
    }
}

/// A row-major `(len / width, width)` array.
pub(crate) fn matrix<'py>(
    py: Python<'py>,
    values: Vec<f32>,
    width: usize,
) -> Bound<'py, PyArray2<f32>> {
    Array2::from_shape_vec((values.len() / width, width), values)
        .expect("a whole number of rows")
        .into_pyarray(py)
}

/// One field of every row, as a numpy array.
pub(crate) fn column<'py, R, T: numpy::Element>(
    py: Python<'py>,
    rows: &[R],
    field: impl Fn(&R) -> T,
) -> Bound<'py, numpy::PyArray1<T>> {
    rows.iter().map(field).collect::<Vec<T>>().into_pyarray(py)
}

/// The hits of many rays one ray after another: `ray_splits` (the hits of
/// ray `i` are `splits[i]..splits[i + 1]`), the ray of each hit, and the
/// hits.
pub(crate) fn laid_out<H>(lists: &[Vec<H>]) -> (Vec<u32>, Vec<u32>, Vec<&H>) {
    let mut splits = Vec::with_capacity(lists.len() + 1);
    splits.push(0u32);
    let mut total = 0u32;
    for l in lists {
        total = total.saturating_add(l.len() as u32);
        splits.push(total);
    }
    let (ray_ids, hits) = lists
        .iter()
        .enumerate()
        .flat_map(|(i, l)| l.iter().map(move |h| (i as u32, h)))
        .unzip();
    (splits, ray_ids, hits)
}
