//! `_raykit.Scene`: one triangle mesh made of the geometries added to a
//! `RaycastingScene`, its acceleration structure, and the ray queries.
//!
//! Geometries are concatenated into one mesh; `offsets[g]` is the first
//! triangle of geometry `g`, so a hit's triangle maps back to the geometry
//! and its own triangle index by a binary search.

use crate::arrays::{flat, rows};
use crate::errors::persist_error;
use crate::errors::value_error;
use crate::hit_arrays::{matrix, HitColumns, INVALID_ID};
use crate::image_order::{banded, moved_per_ray, nearest_by_bands, occlusion_by_bands, HitRow};
use crate::threads::{detached, Stop};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use raykit_core::accel::bvh::DEFAULT_MAX_DEGRADATION;
use raykit_core::accel::{
    build_accel, load_accel, refit_keeps_precision, AccelKind, BuildOptions, RefitError,
};
use raykit_core::query::{QueryKind, SurfaceBvh};
use raykit_core::tri::TestKind;
use raykit_core::{Accel, MeshError, TriangleMesh, Vec3};
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::{OnceLock, RwLock, RwLockReadGuard};

/// Rays per rayon task when converting rays and answers.
const GRAIN: usize = 4096;

/// A triangle mesh with its acceleration structure, built (or loaded)
/// once and refit when the vertices move.
#[pyclass(module = "raykit._raykit", frozen)]
pub struct Scene {
    offsets: Vec<u32>,
    /// The mesh and its structures; queries read it, a refit
    /// ([`Scene::refit`]) writes it.
    built: RwLock<Built>,
}

/// The mesh of a [`Scene`] and the structures made over it.
pub(crate) struct Built {
    pub(crate) mesh: TriangleMesh,
    /// Unit normal of each triangle by its winding (zero for degenerate
    /// ones), made once so a hit costs one load instead of an index and
    /// three vertices.
    pub(crate) normals: Vec<Vec3>,
    /// The ray structure's kind and triangle test (`--accel`, `--test`).
    kind: AccelKind,
    test: TestKind,
    /// The ray structure: loaded with the scene, or built at the first
    /// query that traces through it, so that a scene asked only point and
    /// multi-hit queries never builds it; `None` inside for a scene without
    /// triangles.
    ray_structure: OnceLock<Option<Box<dyn Accel>>>,
    /// The 8-wide BVH of the point and multi-hit queries, built at the
    /// first such query.
    surface: OnceLock<SurfaceBvh>,
}

impl Built {
    /// The ray structure (built on first use); `None` for a scene without
    /// triangles.
    pub(crate) fn accel(&self) -> Option<&dyn Accel> {
        self.ray_structure
            .get_or_init(|| {
                (self.mesh.num_triangles() > 0).then(|| {
                    build_accel(self.kind, self.test, &self.mesh, &BuildOptions::default())
                })
            })
            .as_deref()
    }

    /// Whether the ray structure has been built (or loaded), or the scene
    /// needs none.
    pub(crate) fn is_built(&self) -> bool {
        self.ray_structure.get().is_some() || self.mesh.num_triangles() == 0
    }

    /// Whether the point and multi-hit query `kind` on `n` points or rays
    /// is a single task over trees already made
    /// ([`SurfaceBvh::single_task`]), which may run on the caller's thread.
    pub(crate) fn single_task(&self, kind: QueryKind, n: usize) -> bool {
        self.surface.get().is_some_and(|s| s.single_task(kind, n))
    }

    /// The BVH of the point and multi-hit queries (built on first use).
    pub(crate) fn surface(&self) -> &SurfaceBvh {
        self.surface.get_or_init(|| SurfaceBvh::build(&self.mesh))
    }
}

/// Unit normal of each triangle of `mesh` ([`TriangleMesh::unit_normal`]).
fn face_normals(mesh: &TriangleMesh) -> Vec<Vec3> {
    (0..mesh.num_triangles())
        .into_par_iter()
        .with_min_len(GRAIN)
        .map(|i| mesh.unit_normal(i))
        .collect()
}

impl Scene {
    /// The mesh and its structures, for reading (waits while a refit
    /// writes them).
    pub(crate) fn read(&self) -> RwLockReadGuard<'_, Built> {
        self.built.read().unwrap_or_else(|e| e.into_inner())
    }

    /// Geometry id and the triangle's index within it.
    pub(crate) fn split(&self, prim: u32) -> (u32, u32) {
        let g = self.offsets.partition_point(|&o| o <= prim) - 1;
        (g as u32, prim - self.offsets[g])
    }

    /// Nearest hits of the rows of `rays` as result columns, traced band
    /// by band in image blocks when the rays form rows of `width` (0: any
    /// order; [`nearest_by_bands`]).
    fn nearest(&self, built: &Built, rays: &[f32], width: usize, stop: &Stop) -> HitColumns {
        let n = rays.len() / 6;
        let Some(a) = built.accel() else {
            return HitColumns::misses(n);
        };
        nearest_by_bands(rays, n, width, stop, |traced| {
            let mut hits = vec![None; traced.len()];
            a.intersect_batch(traced, &mut hits);
            hits.iter()
                .map(|h| {
                    h.map(|h| {
                        let (geometry, prim) = self.split(h.prim);
                        HitRow {
                            t: h.t,
                            geometry,
                            instance: INVALID_ID,
                            prim,
                            uv: [h.u, h.v],
                            normal: built.normals[h.prim as usize].to_array(),
                        }
                    })
                })
                .collect()
        })
    }
}

#[pymethods]
impl Scene {
    /// Build the structure `accel` with triangle test `test` over the
    /// triangles (`(m, 3)` uint32) of the vertices (`(n, 3)` float32);
    /// `offsets` (uint32) holds the first triangle of each geometry. With
    /// `structure`, the path of a file written by [`Scene::save`] for this
    /// mesh, the structure is loaded from it instead (its own structure and
    /// test replace `accel` and `test`), refused when it is damaged or was
    /// saved for another mesh.
    #[new]
    #[pyo3(signature = (vertices, triangles, offsets, accel="bvh8", test="moller", threads=0, structure=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f32>,
        triangles: PyReadonlyArray2<'_, u32>,
        offsets: PyReadonlyArray1<'_, u32>,
        accel: &str,
        test: &str,
        threads: i64,
        structure: Option<PathBuf>,
    ) -> PyResult<Scene> {
        let kind = AccelKind::from_name(accel).ok_or_else(|| {
            let names: Vec<_> = AccelKind::ALL.iter().map(|k| k.name()).collect();
            value_error(format!(
                "unknown accel '{accel}'; expected one of {}",
                names.join(", ")
            ))
        })?;
        let test_kind = TestKind::from_name(test).ok_or_else(|| {
            let names: Vec<_> = TestKind::ALL.iter().map(|k| k.name()).collect();
            value_error(format!(
                "unknown test '{test}'; expected one of {}",
                names.join(", ")
            ))
        })?;
        let (v, _) = rows(&vertices, 3, "vertices")?;
        let (t, m) = rows(&triangles, 3, "triangles")?;
        let offsets = flat(&offsets, "offsets")?.to_vec();
        if offsets.first() != Some(&0)
            || offsets.windows(2).any(|w| w[0] > w[1])
            || *offsets.last().unwrap_or(&0) as usize != m
        {
            return Err(value_error(
                "offsets must rise from 0 to the number of triangles",
            ));
        }
        let mesh = TriangleMesh::new(
            v.chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect(),
            t.chunks_exact(3).map(|i| [i[0], i[1], i[2]]).collect(),
        );
        checked(&mesh)?;
        if structure.is_some() && mesh.num_triangles() == 0 {
            return Err(value_error(
                "the scene has no triangles to load a structure for",
            ));
        }
        let (mesh, normals, ray_structure, kind, test_kind) = detached(py, threads, move || {
            let (kind, test_kind, loaded) = match &structure {
                Some(path) => {
                    let (k, t, a) = load_accel(path, &mesh).map_err(persist_error)?;
                    (k, t, OnceLock::from(Some(a)))
                }
                None => (kind, test_kind, OnceLock::new()),
            };
            let normals = face_normals(&mesh);
            Ok::<_, PyErr>((mesh, normals, loaded, kind, test_kind))
        })??;
        Ok(Scene {
            offsets,
            built: RwLock::new(Built {
                mesh,
                normals,
                kind,
                test: test_kind,
                ray_structure,
                surface: OnceLock::new(),
            }),
        })
    }

    /// Save the ray structure to `path` (bvh4 and bvh8 have a saved form),
    /// with the mesh's checksum, for `Scene(..., structure=path)`.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        // On all cores: saving checks the tree against the mesh in parallel.
        detached(py, 0, || {
            let built = self.read();
            let Some(accel) = built.accel() else {
                return Err(value_error("the scene has no triangles to save"));
            };
            accel.save(&path, &built.mesh).map_err(persist_error)
        })?
    }

    /// Move the vertices to `vertices` (`(n, 3)` float32, as many as the
    /// mesh has, same triangles) and refit the ray structure to them in
    /// O(n) (Wald, Boulos and Shirley 2007), rebuilding it when the refit
    /// tree's SAH cost passes `max_degradation` times the built tree's, or
    /// when the structure has no refit; the point-query BVH is rebuilt at
    /// its next use. Returns `{"rebuilt": bool, "degradation": float}`
    /// (degradation NaN when the structure has no refit), or `None` when
    /// no query has built the ray structure yet (it is built from the new
    /// vertices at its first use).
    #[pyo3(signature = (vertices, threads=0, max_degradation=DEFAULT_MAX_DEGRADATION))]
    fn refit<'py>(
        &self,
        py: Python<'py>,
        vertices: PyReadonlyArray2<'py, f32>,
        threads: i64,
        max_degradation: f64,
    ) -> PyResult<Option<Bound<'py, PyDict>>> {
        let (v, n) = rows(&vertices, 3, "vertices")?;
        if max_degradation.is_nan() || max_degradation < 1.0 {
            return Err(value_error(format!(
                "max_degradation must be >= 1, got {max_degradation}"
            )));
        }
        let outcome = detached(py, threads, || {
            let mut built = self.built.write().unwrap_or_else(|e| e.into_inner());
            let have = built.mesh.positions.len();
            if n != have {
                return Err(value_error(format!(
                    "vertices: the scene has {have} vertices, got {n}"
                )));
            }
            let mesh = TriangleMesh::new(
                v.chunks_exact(3)
                    .map(|p| Vec3::new(p[0], p[1], p[2]))
                    .collect(),
                built.mesh.indices.clone(),
            );
            checked(&mesh)?;
            // A structure not built yet is built from the new vertices at
            // its first use: nothing to refit.
            // A model moved too far for the scaling and placement it was
            // built with is rebuilt, as a refit would lose precision.
            let keeps = refit_keeps_precision(built.test, &built.mesh, &mesh);
            let outcome = match built.ray_structure.get_mut().and_then(|a| a.as_mut()) {
                None => None,
                Some(_) if !keeps => Some((true, f64::NAN)),
                Some(a) => Some(match a.refit(&mesh) {
                    Ok(report) => {
                        let d = report.degradation();
                        (d > max_degradation, d)
                    }
                    Err(RefitError::Unsupported) => (true, f64::NAN),
                    Err(e) => return Err(value_error(e.to_string())),
                }),
            };
            if let Some((true, _)) = outcome {
                let rebuilt = build_accel(built.kind, built.test, &mesh, &BuildOptions::default());
                built.ray_structure = OnceLock::from(Some(rebuilt));
            }
            built.normals = face_normals(&mesh);
            built.mesh = mesh;
            built.surface = OnceLock::new();
            Ok(outcome)
        })??;
        let Some((rebuilt, degradation)) = outcome else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("rebuilt", rebuilt)?;
        d.set_item("degradation", degradation)?;
        Ok(Some(d))
    }

    /// Nearest hits of `(n, 6)` float32 rays: `(t_hit, geometry_ids,
    /// primitive_ids, primitive_uvs, primitive_normals)`. `width`: the rays
    /// are the rows of an image this wide (traced in pixel blocks; 0: any).
    #[pyo3(signature = (rays, threads=0, width=0))]
    #[allow(clippy::type_complexity)]
    fn cast_rays<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        threads: i64,
        width: usize,
    ) -> PyResult<(
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray1<u32>>,
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray2<f32>>,
    )> {
        let (r, n) = rows(&rays, 6, "rays")?;
        // Read apart: a guard in the call's arguments would be held while
        // the work takes the lock again.
        let built = self.read().is_built();
        let c = banded(py, threads, (n, width), built, |stop| {
            self.nearest(&self.read(), r, width, stop)
        })?;
        Ok((
            c.t.into_pyarray(py),
            c.geometry.into_pyarray(py),
            c.prim.into_pyarray(py),
            matrix(py, c.uv, 2),
            matrix(py, c.normal, 3),
        ))
    }

    /// Whether each `(n, 6)` float32 ray meets a triangle with `t` in
    /// `[tnear, tfar]`; `width` as for `cast_rays`; `moved` (float64, one
    /// per ray): how far each ray was moved along itself, taken off its
    /// interval.
    #[pyo3(signature = (rays, tnear=0.0, tfar=f32::INFINITY, threads=0, width=0, moved=None))]
    #[allow(clippy::too_many_arguments)]
    fn test_occlusions<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        tnear: f32,
        tfar: f32,
        threads: i64,
        width: usize,
        moved: Option<PyReadonlyArray1<'py, f64>>,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let (r, n) = rows(&rays, 6, "rays")?;
        let moved = moved_per_ray(&moved, n)?;
        let built = self.read().is_built();
        let occluded = banded(py, threads, (n, width), built, |stop| {
            match self.read().accel() {
                Some(a) => {
                    occlusion_by_bands(r, n, width, (tnear, tfar), moved, stop, |rays, out| {
                        a.occluded_batch(rays, out)
                    })
                }
                None => vec![false; n],
            }
        })?;
        Ok(occluded.into_pyarray(py))
    }

    /// Triangles in the scene.
    #[getter]
    fn num_triangles(&self) -> usize {
        self.read().mesh.num_triangles()
    }

    /// The structure's name (`--accel`).
    #[getter]
    fn accel(&self) -> &'static str {
        self.read().kind.name()
    }

    /// The triangle test's name (`--test`).
    #[getter]
    fn test(&self) -> &'static str {
        self.read().test.name()
    }

    /// Size and quality figures of the structure (`raykit bench`'s
    /// columns); empty for a scene without triangles.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        if let Some(a) = self.read().accel() {
            let s = a.stats();
            d.set_item("nodes", s.nodes)?;
            d.set_item("leaves", s.leaves)?;
            d.set_item("bytes", s.bytes)?;
            d.set_item("node_bytes", s.node_bytes)?;
            d.set_item("depth", s.depth)?;
            d.set_item("sah_cost", s.sah_cost)?;
            d.set_item("triangle_refs", s.triangle_refs)?;
        }
        Ok(d)
    }
}

/// `mesh` checked as [`TriangleMesh::validate`] checks it (indices in
/// range, coordinates finite and within reach); a mesh of no triangles is
/// accepted, every ray missing it.
fn checked(mesh: &TriangleMesh) -> PyResult<()> {
    match mesh.validate() {
        Ok(()) | Err(MeshError::Empty) => Ok(()),
        Err(e) => Err(value_error(e.to_string())),
    }
}
