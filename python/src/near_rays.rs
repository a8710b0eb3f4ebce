//! Float64 rays made float32 without losing their origins' precision: a
//! ray whose origin lies far from the scene is first moved along itself,
//! in float64, to just outside the scene's bounding sphere, where float32
//! keeps it to a fraction of the scene's size (rounded first, an origin at
//! 10⁷ moves by up to half a unit). The same move as the core's far-ray
//! wrapper for Möller's test, done here before the rounding, for every
//! test.

use crate::arrays::rows;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use rayon::prelude::*;

/// Rays per rayon task.
const GRAIN: usize = 4096;

/// `(n, 6)` float64 rays `[ox, oy, oz, dx, dy, dz]` as float32, origins
/// moved by `-shift`; a ray whose origin then lies more than `far_radii`
/// radii from `centre` is moved along itself to twice `radius` before its
/// closest approach to `centre`. Returns the rays and, when any ray moved,
/// the distance `t0` each moved in its direction's length (a hit's `t` on
/// the moved ray plus `t0` is its `t` on the ray given).
#[pyfunction]
#[pyo3(signature = (rays, shift, centre, radius, far_radii))]
#[allow(clippy::type_complexity)]
pub fn near_rays<'py>(
    py: Python<'py>,
    rays: PyReadonlyArray2<'py, f64>,
    shift: [f64; 3],
    centre: [f64; 3],
    radius: f64,
    far_radii: f64,
) -> PyResult<(Bound<'py, PyArray2<f32>>, Option<Bound<'py, PyArray1<f64>>>)> {
    let (r, n) = rows(&rays, 6, "rays")?;
    let far = (far_radii * radius).powi(2);
    let mut out = vec![0.0f32; 6 * n];
    let mut moved = vec![0.0f64; n];
    let any = py.detach(|| {
        out.par_chunks_exact_mut(6)
            .zip(moved.par_iter_mut())
            .zip(r.par_chunks_exact(6))
            .with_min_len(GRAIN)
            .map(|((out, t0), r)| {
                let mut o = [r[0] - shift[0], r[1] - shift[1], r[2] - shift[2]];
                let d = [r[3], r[4], r[5]];
                let w = [o[0] - centre[0], o[1] - centre[1], o[2] - centre[2]];
                let ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
                if ww > far {
                    let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    let closest = -(w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / dd;
                    let t = closest - 2.0 * radius / dd.sqrt();
                    if t.is_finite() && t > 0.0 {
                        *t0 = t;
                        for k in 0..3 {
                            o[k] += t * d[k];
                        }
                    }
                }
                for k in 0..3 {
                    out[k] = o[k] as f32;
                    out[3 + k] = d[k] as f32;
                }
                *t0 > 0.0
            })
            .reduce(|| false, |a, b| a || b)
    });
    let rays = Array2::from_shape_vec((n, 6), out)
        .expect("six per ray")
        .into_pyarray(py);
    Ok((rays, any.then(|| moved.into_pyarray(py))))
}
