//! `_raykit.InstancedScene`: several geometries, each stored once with its
//! own BVH, placed by instances (an affine transform each) under a top-level
//! BVH — the core's two-level scene (Wald et al. 2014's instancing, as in
//! Embree and pbrt-v4) — and its ray queries.

use crate::arrays::{c_order, rows};
use crate::errors::value_error;
use crate::hit_arrays::{column, laid_out, matrix, HitColumns};
use crate::image_order::{banded, moved_per_ray, nearest_by_bands, occlusion_by_bands, HitRow};
use crate::threads::{detached, Stop};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use raykit_core::accel::BuildOptions;
use raykit_core::glam::{Affine3A, Vec3A};
use raykit_core::instancing::{InstancedScene as CoreScene, SceneBuilder};
use raykit_core::{Ray, TriangleMesh, Vec3};
use rayon::prelude::*;

/// Rays per rayon task when converting rays and answers.
const GRAIN: usize = 4096;

/// A geometry as Python passes it: vertices `(n, 3)` float32, triangles
/// `(m, 3)` uint32 and its ray mask.
type GeometryIn<'py> = (PyReadonlyArray2<'py, f32>, PyReadonlyArray2<'py, u32>, u32);

/// An instance as Python passes it: geometry id, a `(3, 4)` float64
/// object-to-world matrix `[R | t]` and its ray mask.
type InstanceIn<'py> = (u32, PyReadonlyArray2<'py, f64>, u32);

/// The rays of the rows of `[ox, oy, oz, dx, dy, dz]` over `[tnear, tfar]`.
fn make_rays(r: &[f32], tnear: f32, tfar: f32) -> Vec<Ray> {
    r.par_chunks_exact(6)
        .with_min_len(GRAIN)
        .map(|r| {
            Ray::segment(
                Vec3::from_slice(&r[..3]),
                Vec3::from_slice(&r[3..]),
                tnear,
                tfar,
            )
        })
        .collect()
}

/// The affine map of a row-major `(3, 4)` matrix `[R | t]`.
fn affine(m: &[f64]) -> Affine3A {
    let col = |j: usize| Vec3A::new(m[j] as f32, m[4 + j] as f32, m[8 + j] as f32);
    Affine3A::from_cols(col(0), col(1), col(2), col(3))
}

/// Several triangle meshes placed by instances, with the two-level BVH
/// over them.
#[pyclass(module = "raykit._raykit", frozen)]
pub struct InstancedScene {
    scene: CoreScene,
}

impl InstancedScene {
    /// Nearest hits of the `n` rows of `rays` as result columns, traced
    /// band by band (in image blocks when the rays form rows of `width`;
    /// [`nearest_by_bands`]).
    fn nearest(&self, rays: &[f32], n: usize, mask: u32, width: usize, stop: &Stop) -> HitColumns {
        nearest_by_bands(rays, n, width, stop, |traced| {
            let mut hits = vec![None; traced.len()];
            self.scene.intersect_batch(traced, mask, &mut hits);
            hits.iter()
                .map(|h| {
                    h.map(|h| HitRow {
                        t: h.t,
                        geometry: h.geometry,
                        instance: h.instance,
                        prim: h.prim,
                        uv: [h.u, h.v],
                        normal: h.normal.to_array(),
                    })
                })
                .collect()
        })
    }
}

#[pymethods]
impl InstancedScene {
    /// Build the scene: `geometries` is a list of `(vertices, triangles,
    /// mask)`, `instances` a list of `(geometry_id, matrix, mask)` with a
    /// `(3, 4)` float64 object-to-world matrix. A bad mesh, an unknown
    /// geometry and a transform that is not finite or not invertible are
    /// refused with `ValueError`, naming the geometry or instance.
    #[new]
    #[pyo3(signature = (geometries, instances, threads=0))]
    fn new(
        py: Python<'_>,
        geometries: Vec<GeometryIn<'_>>,
        instances: Vec<InstanceIn<'_>>,
        threads: i64,
    ) -> PyResult<InstancedScene> {
        let mut builder = SceneBuilder::new();
        for (i, (vertices, triangles, mask)) in geometries.iter().enumerate() {
            let (v, _) = rows(vertices, 3, &format!("geometry {i}'s vertices"))?;
            let (t, _) = rows(triangles, 3, &format!("geometry {i}'s triangles"))?;
            let mesh = TriangleMesh::new(
                v.chunks_exact(3).map(Vec3::from_slice).collect(),
                t.chunks_exact(3).map(|i| [i[0], i[1], i[2]]).collect(),
            );
            let id = builder
                .add_geometry(mesh)
                .map_err(|e| value_error(e.to_string()))?;
            builder
                .set_geometry_mask(id, *mask)
                .map_err(|e| value_error(e.to_string()))?;
        }
        for (i, (geometry, matrix, mask)) in instances.iter().enumerate() {
            if matrix.shape() != [3, 4] {
                return Err(value_error(format!(
                    "instance {i}: the transform must have shape (3, 4), got {:?}",
                    matrix.shape()
                )));
            }
            let m = c_order(matrix, &format!("instance {i}: the transform"))?;
            let id = builder
                .add_instance(*geometry, affine(m))
                .map_err(|e| value_error(e.to_string()))?;
            builder
                .set_instance_mask(id, *mask)
                .map_err(|e| value_error(e.to_string()))?;
        }
        let scene = detached(py, threads, move || builder.build(&BuildOptions::default()))?;
        Ok(InstancedScene { scene })
    }

    /// Nearest hits of `(n, 6)` float32 rays seen by `mask`: `(t_hit,
    /// geometry_ids, instance_ids, primitive_ids, primitive_uvs,
    /// primitive_normals)`, the normal in world space; a miss has `t_hit`
    /// inf, `INVALID_ID` ids and zero uvs and normal. `width`: the rays are
    /// the rows of an image this wide (traced in pixel blocks; 0: any).
    #[pyo3(signature = (rays, mask=u32::MAX, threads=0, width=0))]
    #[allow(clippy::type_complexity)]
    fn cast_rays<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        mask: u32,
        threads: i64,
        width: usize,
    ) -> PyResult<(
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray2<f32>>,
    )> {
        let (r, n) = rows(&rays, 6, "rays")?;
        // The structures are built with the scene.
        let c = banded(py, threads, (n, width), true, |stop| {
            self.nearest(r, n, mask, width, stop)
        })?;
        Ok((
            c.t.into_pyarray(py),
            c.geometry.into_pyarray(py),
            c.instance.into_pyarray(py),
            c.prim.into_pyarray(py),
            matrix(py, c.uv, 2),
            matrix(py, c.normal, 3),
        ))
    }

    /// Whether each `(n, 6)` float32 ray meets a triangle seen by `mask`
    /// with `t` in `[tnear, tfar]`; `width` as for `cast_rays`; `moved` as
    /// for the plain scene's.
    #[pyo3(signature = (rays, tnear=0.0, tfar=f32::INFINITY, mask=u32::MAX, threads=0, width=0, moved=None))]
    #[allow(clippy::too_many_arguments)]
    fn test_occlusions<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        tnear: f32,
        tfar: f32,
        mask: u32,
        threads: i64,
        width: usize,
        moved: Option<PyReadonlyArray1<'py, f64>>,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let (r, n) = rows(&rays, 6, "rays")?;
        let moved = moved_per_ray(&moved, n)?;
        let occluded = banded(py, threads, (n, width), true, |stop| {
            occlusion_by_bands(r, n, width, (tnear, tfar), moved, stop, |rays, out| {
                self.scene.occluded_batch(rays, mask, out)
            })
        })?;
        Ok(occluded.into_pyarray(py))
    }

    /// Number of triangles seen by `mask` that each `(n, 6)` float32 ray
    /// crosses for `t >= 0` (int32, as Open3D).
    #[pyo3(signature = (rays, mask=u32::MAX, threads=0))]
    fn count_intersections<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        mask: u32,
        threads: i64,
    ) -> PyResult<Bound<'py, PyArray1<i32>>> {
        let (r, n) = rows(&rays, 6, "rays")?;
        let counts = detached(py, threads, || {
            let mut counts = vec![0u32; n];
            self.scene
                .count_hits_batch(&make_rays(r, 0.0, f32::INFINITY), mask, &mut counts);
            counts
                .into_par_iter()
                .with_min_len(GRAIN)
                .map(|c| c.min(i32::MAX as u32) as i32)
                .collect::<Vec<i32>>()
        })?;
        Ok(counts.into_pyarray(py))
    }

    /// Every hit seen by `mask` of each `(n, 6)` float32 ray for `t >= 0`,
    /// sorted by `t`, at most `max_hits` per ray: `(ray_splits, ray_ids,
    /// t_hit, geometry_ids, instance_ids, primitive_ids, primitive_uvs)` in
    /// Open3D's layout.
    #[pyo3(signature = (rays, max_hits=usize::MAX, mask=u32::MAX, threads=0))]
    #[allow(clippy::type_complexity)]
    fn list_intersections<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        max_hits: usize,
        mask: u32,
        threads: i64,
    ) -> PyResult<(
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray2<f32>>,
    )> {
        let (r, _) = rows(&rays, 6, "rays")?;
        let lists = detached(py, threads, || {
            self.scene
                .ray_hits_batch(&make_rays(r, 0.0, f32::INFINITY), mask, max_hits)
        })?;
        let (splits, ray_ids, hits) = laid_out(&lists);
        Ok((
            splits.into_pyarray(py),
            ray_ids.into_pyarray(py),
            column(py, &hits, |h| h.t),
            column(py, &hits, |h| h.geometry),
            column(py, &hits, |h| h.instance),
            column(py, &hits, |h| h.prim),
            matrix(py, hits.iter().flat_map(|h| [h.u, h.v]).collect(), 2),
        ))
    }

    /// Triangles stored (each geometry once, however many instances).
    #[getter]
    fn stored_triangles(&self) -> usize {
        self.scene.stats().stored_triangles
    }

    /// Triangles the instances place in the world.
    #[getter]
    fn placed_triangles(&self) -> usize {
        self.scene.stats().instanced_triangles
    }
}
