//! Point and multi-hit ray queries on a `_raykit.Scene`: closest points,
//! unsigned and signed distance, occupancy and winding numbers, hit counts
//! and hit lists, all through the scene's [`raykit_core::query::SurfaceBvh`]
//! (built at the first of these queries).

use crate::arrays::rows;
use crate::errors::value_error;
use crate::hit_arrays::{column, laid_out, matrix, INVALID_ID};
use crate::scene::Scene;
use crate::threads::inline_or_interruptible;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use raykit_core::query::{ClosestPoint, QueryKind};
use raykit_core::{Hit, Ray, Vec3};
use rayon::prelude::*;

/// Points per rayon task.
const GRAIN: usize = 1024;

/// Rays or points handed to the engine at a time: a call stops between
/// pieces when interrupted ([`crate::threads::interruptible`]). Large enough that each
/// piece keeps the engine's own order (Morton order of points) effective.
const PIECE: usize = 1 << 20;

/// The points of the rows of an `(n, 3)` array.
fn points(p: &[f32]) -> Vec<Vec3> {
    p.par_chunks_exact(3)
        .with_min_len(GRAIN)
        .map(Vec3::from_slice)
        .collect()
}

/// The rays of the rows of an `(n, 6)` array, over `[0, inf)`.
fn rays(r: &[f32]) -> Vec<Ray> {
    r.par_chunks_exact(6)
        .with_min_len(GRAIN)
        .map(|r| Ray::new(Vec3::from_slice(&r[..3]), Vec3::from_slice(&r[3..])))
        .collect()
}

/// Closest surface point of each `(n, 3)` float32 point within
/// `max_distance`: `(points, geometry_ids, primitive_ids, primitive_uvs,
/// primitive_normals, distances)`. A point with no answer (not finite, an
/// empty scene, nothing within `max_distance`) gets NaN coordinates,
/// `INVALID_ID`, zero uvs and normal, and an infinite distance (NaN for a
/// point that is not finite).
#[pyfunction]
#[pyo3(signature = (scene, query_points, max_distance=f32::INFINITY, threads=0))]
#[allow(clippy::type_complexity)]
pub fn closest_points<'py>(
    py: Python<'py>,
    scene: &Scene,
    query_points: PyReadonlyArray2<'py, f32>,
    max_distance: f32,
    threads: i64,
) -> PyResult<(
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<f32>>,
)> {
    let (q, n) = rows(&query_points, 3, "query_points")?;
    if max_distance.is_nan() || max_distance < 0.0 {
        return Err(value_error(format!(
            "max_distance must be >= 0, got {max_distance}"
        )));
    }
    let single = scene.read().single_task(QueryKind::Closest, n);
    let (pts, g, p, uv, nrm, dist) = inline_or_interruptible(py, threads, n, single, |stop| {
        let built = scene.read();
        let bvh = built.surface();
        let qp = points(q);
        let mut found: Vec<Option<ClosestPoint>> = vec![None; n];
        for (qp, found) in qp.chunks(PIECE).zip(found.chunks_mut(PIECE)) {
            if !stop.raised() {
                bvh.closest_points(qp, max_distance, found);
            }
        }
        let mut pts = vec![f32::NAN; 3 * n];
        let mut g = vec![INVALID_ID; n];
        let mut p = vec![INVALID_ID; n];
        let mut uv = vec![0.0f32; 2 * n];
        let mut nrm = vec![0.0f32; 3 * n];
        let mut dist = vec![f32::INFINITY; n];
        found
            .par_iter()
            .zip(&qp)
            .zip(pts.par_chunks_exact_mut(3))
            .zip(g.par_iter_mut())
            .zip(p.par_iter_mut())
            .zip(uv.par_chunks_exact_mut(2))
            .zip(nrm.par_chunks_exact_mut(3))
            .zip(dist.par_iter_mut())
            .with_min_len(GRAIN)
            .for_each(|(((((((c, q), pt), g), p), uv), nrm), d)| match c {
                Some(c) => {
                    pt.copy_from_slice(&c.point.to_array());
                    (*g, *p) = scene.split(c.prim);
                    uv.copy_from_slice(&[c.u, c.v]);
                    nrm.copy_from_slice(&built.normals[c.prim as usize].to_array());
                    *d = c.distance;
                }
                None if !q.is_finite() => *d = f32::NAN,
                None => {}
            });
        (pts, g, p, uv, nrm, dist)
    })?;
    Ok((
        Array2::from_shape_vec((n, 3), pts)
            .expect("three per point")
            .into_pyarray(py),
        g.into_pyarray(py),
        p.into_pyarray(py),
        Array2::from_shape_vec((n, 2), uv)
            .expect("two per point")
            .into_pyarray(py),
        Array2::from_shape_vec((n, 3), nrm)
            .expect("three per point")
            .into_pyarray(py),
        dist.into_pyarray(py),
    ))
}

/// What [`point_values`] computes per point.
#[derive(Clone, Copy)]
enum PointValue {
    Distance,
    SignedDistance,
    Occupancy,
    Winding(f32),
}

/// One float32 per point of `(n, 3)` float32 `query_points`.
fn point_values<'py>(
    py: Python<'py>,
    scene: &Scene,
    query_points: PyReadonlyArray2<'py, f32>,
    threads: i64,
    what: PointValue,
) -> PyResult<Bound<'py, PyArray1<f32>>> {
    let (q, n) = rows(&query_points, 3, "query_points")?;
    let kind = match what {
        PointValue::Distance => Some(QueryKind::Distance),
        PointValue::SignedDistance => Some(QueryKind::SignedDistance),
        PointValue::Occupancy => Some(QueryKind::Inside),
        PointValue::Winding(_) => None,
    };
    let single = kind.is_some_and(|k| scene.read().single_task(k, n));
    let out = inline_or_interruptible(py, threads, n, single, |stop| {
        let built = scene.read();
        let bvh = built.surface();
        let qp = points(q);
        let mut out = vec![0.0f32; n];
        for (qp, out) in qp.chunks(PIECE).zip(out.chunks_mut(PIECE)) {
            if stop.raised() {
                break;
            }
            match what {
                PointValue::Distance => bvh.distances(qp, out),
                PointValue::SignedDistance => bvh.signed_distances(qp, out),
                PointValue::Occupancy => {
                    let mut inside = vec![false; qp.len()];
                    bvh.inside_batch(qp, &mut inside);
                    out.par_iter_mut()
                        .zip(&inside)
                        .with_min_len(GRAIN)
                        .for_each(|(o, &i)| *o = f32::from(u8::from(i)));
                }
                PointValue::Winding(beta) => bvh.winding_numbers_with(qp, beta, out),
            }
        }
        out
    })?;
    Ok(out.into_pyarray(py))
}

/// Unsigned distance from each `(n, 3)` float32 point to the surface
/// (inf for an empty scene, NaN for a point that is not finite).
#[pyfunction]
#[pyo3(signature = (scene, query_points, threads=0))]
pub fn distance<'py>(
    py: Python<'py>,
    scene: &Scene,
    query_points: PyReadonlyArray2<'py, f32>,
    threads: i64,
) -> PyResult<Bound<'py, PyArray1<f32>>> {
    point_values(py, scene, query_points, threads, PointValue::Distance)
}

/// Signed distance (negative inside, by the generalized winding number).
#[pyfunction]
#[pyo3(signature = (scene, query_points, threads=0))]
pub fn signed_distance<'py>(
    py: Python<'py>,
    scene: &Scene,
    query_points: PyReadonlyArray2<'py, f32>,
    threads: i64,
) -> PyResult<Bound<'py, PyArray1<f32>>> {
    point_values(py, scene, query_points, threads, PointValue::SignedDistance)
}

/// Occupancy: 1.0 where the generalized winding number is at least ½,
/// else 0.0 (also for points that are not finite).
#[pyfunction]
#[pyo3(signature = (scene, query_points, threads=0))]
pub fn occupancy<'py>(
    py: Python<'py>,
    scene: &Scene,
    query_points: PyReadonlyArray2<'py, f32>,
    threads: i64,
) -> PyResult<Bound<'py, PyArray1<f32>>> {
    point_values(py, scene, query_points, threads, PointValue::Occupancy)
}

/// Generalized winding number of each point (Jacobson et al. 2013) with
/// Barill et al.'s 2018 far-field approximation at accuracy `beta`
/// (`inf`: exact).
#[pyfunction]
#[pyo3(signature = (scene, query_points, beta=2.0, threads=0))]
pub fn winding_number<'py>(
    py: Python<'py>,
    scene: &Scene,
    query_points: PyReadonlyArray2<'py, f32>,
    beta: f32,
    threads: i64,
) -> PyResult<Bound<'py, PyArray1<f32>>> {
    if beta.is_nan() || beta <= 0.0 {
        return Err(value_error(format!("beta must be > 0, got {beta}")));
    }
    point_values(py, scene, query_points, threads, PointValue::Winding(beta))
}

/// Number of triangles each `(n, 6)` float32 ray crosses for `t >= 0`
/// (int32, as Open3D).
#[pyfunction]
#[pyo3(signature = (scene, rays, threads=0))]
pub fn count_intersections<'py>(
    py: Python<'py>,
    scene: &Scene,
    rays: PyReadonlyArray2<'py, f32>,
    threads: i64,
) -> PyResult<Bound<'py, PyArray1<i32>>> {
    let (r, n) = rows(&rays, 6, "rays")?;
    let single = scene.read().single_task(QueryKind::Count, n);
    let out = inline_or_interruptible(py, threads, n, single, |stop| {
        let built = scene.read();
        let bvh = built.surface();
        let mut counts = vec![0u32; n];
        let rays = self::rays(r);
        for (rays, counts) in rays.chunks(PIECE).zip(counts.chunks_mut(PIECE)) {
            if !stop.raised() {
                bvh.count_hits_batch(rays, counts);
            }
        }
        counts
            .into_par_iter()
            .with_min_len(GRAIN)
            .map(|c| c.min(i32::MAX as u32) as i32)
            .collect::<Vec<i32>>()
    })?;
    Ok(out.into_pyarray(py))
}

/// Every hit of each `(n, 6)` float32 ray for `t >= 0`, sorted by `t`, at
/// most `max_hits` per ray: `(ray_splits, ray_ids, t_hit, geometry_ids,
/// primitive_ids, primitive_uvs)` in Open3D's layout (the hits of ray `i`
/// are `ray_splits[i]..ray_splits[i+1]`).
#[pyfunction]
#[pyo3(signature = (scene, rays, max_hits=usize::MAX, threads=0))]
#[allow(clippy::type_complexity)]
pub fn list_intersections<'py>(
    py: Python<'py>,
    scene: &Scene,
    rays: PyReadonlyArray2<'py, f32>,
    max_hits: usize,
    threads: i64,
) -> PyResult<(
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<f32>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray1<u32>>,
    Bound<'py, PyArray2<f32>>,
)> {
    let (r, n) = rows(&rays, 6, "rays")?;
    let single = scene.read().single_task(QueryKind::AllHits, n);
    let lists: Vec<Vec<Hit>> = inline_or_interruptible(py, threads, n, single, |stop| {
        let built = scene.read();
        let mut lists = Vec::with_capacity(n);
        for rays in self::rays(r).chunks(PIECE) {
            if stop.raised() {
                break;
            }
            lists.extend(built.surface().ray_hits_batch(rays, max_hits));
        }
        lists
    })?;
    let (splits, ray_ids, hits) = laid_out(&lists);
    let (g, p): (Vec<u32>, Vec<u32>) = hits.iter().map(|h| scene.split(h.prim)).unzip();
    Ok((
        splits.into_pyarray(py),
        ray_ids.into_pyarray(py),
        column(py, &hits, |h| h.t),
        g.into_pyarray(py),
        p.into_pyarray(py),
        matrix(py, hits.iter().flat_map(|h| [h.u, h.v]).collect(), 2),
    ))
}
