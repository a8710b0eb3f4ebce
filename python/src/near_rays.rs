//! Float64 rays made float32 without losing their origins' precision: a
//! ray whose origin lies far from the scene is first moved along itself,
//! in float64, to just outside the scene's bounding sphere, where float32
//! keeps it to a fraction of the scene's size (rounded first, an origin at
//! 10⁷ moves by up to half a unit). The same move as the core's far-ray
//! wrapper for Möller's test, done here before the rounding, for every
//! test.

use crate::arrays::rows;
use crate::threads::inline_or_interruptible;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use raykit_core::accel::{approach_start, FAR_RADII};
use raykit_core::glam::DVec3;
use rayon::prelude::*;

/// Rays per rayon task.
const GRAIN: usize = 4096;

/// `(n, 6)` float64 rays `[ox, oy, oz, dx, dy, dz]` as float32, origins
/// moved by `-shift`; a ray whose origin then lies more than
/// [`FAR_RADII`] radii from `centre` is moved along itself to twice
/// `radius` before its closest approach to `centre`, as the core's
/// [`raykit_core::accel::FarRays`] moves it ([`approach_start`]). Returns
/// the rays and, when any ray moved, the distance `t0` each moved in its
/// direction's length (a hit's `t` on the moved ray plus `t0` is its `t`
/// on the ray given).
#[pyfunction]
#[pyo3(signature = (rays, shift, centre, radius, threads=0))]
#[allow(clippy::type_complexity)]
pub fn near_rays<'py>(
    py: Python<'py>,
    rays: PyReadonlyArray2<'py, f64>,
    shift: [f64; 3],
    centre: [f64; 3],
    radius: f64,
    threads: i64,
) -> PyResult<(Bound<'py, PyArray2<f32>>, Option<Bound<'py, PyArray1<f64>>>)> {
    let (r, n) = rows(&rays, 6, "rays")?;
    let (shift, centre) = (DVec3::from_array(shift), DVec3::from_array(centre));
    let far = (FAR_RADII as f64 * radius).powi(2);
    let mut out = vec![0.0f32; 6 * n];
    let mut moved = vec![0.0f64; n];
    // Up to one task's rays on the caller's thread, more on the pool
    // `threads` names (a forked child's own).
    let any = inline_or_interruptible(py, threads, n, n <= GRAIN, |_| {
        out.par_chunks_exact_mut(6)
            .zip(moved.par_iter_mut())
            .zip(r.par_chunks_exact(6))
            .with_min_len(GRAIN)
            .map(|((out, t0), r)| {
                let mut o = DVec3::new(r[0], r[1], r[2]) - shift;
                let d = DVec3::new(r[3], r[4], r[5]);
                if (o - centre).length_squared() > far {
                    let t = approach_start(o, d, centre, radius);
                    if t.is_finite() && t > 0.0 {
                        *t0 = t;
                        o += t * d;
                    }
                }
                out[..3].copy_from_slice(&o.as_vec3().to_array());
                out[3..].copy_from_slice(&d.as_vec3().to_array());
                *t0 > 0.0
            })
            .reduce(|| false, |a, b| a || b)
    })?;
    let rays = Array2::from_shape_vec((n, 6), out)
        .expect("six per ray")
        .into_pyarray(py);
    Ok((rays, any.then(|| moved.into_pyarray(py))))
}
