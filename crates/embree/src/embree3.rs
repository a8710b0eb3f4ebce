//! Embree 3 (Wald et al. 2014) linked from Debian's `libembree-dev`: a
//! device, and a scene over one triangle mesh answering single rays
//! (`rtcIntersect1` / `rtcOccluded1`, through the [`Accel`] trait) and
//! streams (`rtcIntersect1M` / `rtcOccluded1M`).

use crate::ffi3::{self as ffi, CALLS};
use crate::mesh_scene::{self, MeshExtent};
use crate::rtcore::{RTCDevice, RTCRay, RTCScene};
use crate::Quality;
use anyhow::Result;
use raykit_core::accel::AccelStats;
use raykit_core::{Aabb, Accel, Hit, Ray, TriangleMesh, Vec3};
use std::sync::Arc;

/// The library's name in errors.
const VERSION: &str = "Embree 3";

/// An Embree 3 device: its thread pool and allocator, created once so that
/// build timings measure the build alone.
pub struct Embree3Device {
    raw: RTCDevice,
}

// SAFETY: an Embree device may be used from any thread.
unsafe impl Send for Embree3Device {}
// SAFETY: as above.
unsafe impl Sync for Embree3Device {}

impl Embree3Device {
    /// A device with `threads` build threads (0: Embree's default, all
    /// cores); `$RAYKIT_EMBREE_CONFIG` ([`crate::CONFIG_ENV`]) adds to its
    /// configuration string.
    pub fn new(threads: usize) -> Result<Arc<Embree3Device>> {
        let raw = mesh_scene::new_device(&CALLS, threads, VERSION)?;
        Ok(Arc::new(Embree3Device { raw }))
    }
}

impl Drop for Embree3Device {
    fn drop(&mut self) {
        // SAFETY: created by `new`, released once.
        unsafe { (CALLS.rtcReleaseDevice)(self.raw) };
    }
}

/// A committed Embree 3 scene holding one triangle mesh.
pub struct Embree3Scene {
    /// Kept so the device outlives the scene.
    _device: Arc<Embree3Device>,
    scene: RTCScene,
    extent: MeshExtent,
}

// SAFETY: Embree documents its query calls on a committed scene as
// thread-safe; the scene is not modified after `build`.
unsafe impl Send for Embree3Scene {}
// SAFETY: as above; `&Embree3Scene` only issues queries.
unsafe impl Sync for Embree3Scene {}

impl Embree3Scene {
    /// Build Embree's BVH over `mesh` with `quality` on `device`.
    pub fn build(
        device: &Arc<Embree3Device>,
        mesh: &TriangleMesh,
        quality: Quality,
    ) -> Result<Embree3Scene> {
        Self::build_triangles(device, &mesh.positions, &mesh.indices, quality)
    }

    /// Build Embree's BVH over the triangles `indices` into `positions`;
    /// an index past the vertices is an error naming the triangle.
    pub fn build_triangles(
        device: &Arc<Embree3Device>,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        quality: Quality,
    ) -> Result<Embree3Scene> {
        // SAFETY: `device` is a live Embree 3 device.
        let (scene, extent) =
            unsafe { mesh_scene::build(&CALLS, device.raw, positions, indices, quality, VERSION)? };
        Ok(Embree3Scene {
            _device: Arc::clone(device),
            scene,
            extent,
        })
    }

    /// Nearest hits of `rays` through Embree's stream API
    /// (`rtcIntersect1M`), in streams of `stream` rays marked coherent, on
    /// the calling thread.
    pub fn intersect_stream(&self, rays: &[Ray], hits: &mut [Option<Hit>], stream: usize) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        let mut buf: Vec<ffi::RTCRayHit> = Vec::with_capacity(stream);
        for (rs, hs) in rays
            .chunks(stream.max(1))
            .zip(hits.chunks_mut(stream.max(1)))
        {
            buf.clear();
            buf.extend(rs.iter().map(ffi::RTCRayHit::of));
            let mut ctx = ffi::RTCIntersectContext::new(ffi::RTC_INTERSECT_CONTEXT_FLAG_COHERENT);
            // SAFETY: `buf` holds `buf.len()` initialised RTCRayHit records
            // with the stride Embree is told.
            unsafe {
                ffi::rtcIntersect1M(
                    self.scene,
                    &mut ctx,
                    buf.as_mut_ptr(),
                    buf.len() as u32,
                    std::mem::size_of::<ffi::RTCRayHit>(),
                );
            }
            for (h, rh) in hs.iter_mut().zip(&buf) {
                *h = rh.hit();
            }
        }
    }

    /// Occlusion of `rays` through Embree's stream API (`rtcOccluded1M`),
    /// in streams of `stream` rays marked coherent, on the calling thread.
    pub fn occluded_stream(&self, rays: &[Ray], occluded: &mut [bool], stream: usize) {
        assert_eq!(rays.len(), occluded.len(), "one result per ray");
        let mut buf: Vec<RTCRay> = Vec::with_capacity(stream);
        for (rs, os) in rays
            .chunks(stream.max(1))
            .zip(occluded.chunks_mut(stream.max(1)))
        {
            buf.clear();
            buf.extend(rs.iter().map(RTCRay::of));
            let mut ctx = ffi::RTCIntersectContext::new(ffi::RTC_INTERSECT_CONTEXT_FLAG_COHERENT);
            // SAFETY: `buf` holds `buf.len()` initialised RTCRay records
            // with the stride Embree is told.
            unsafe {
                ffi::rtcOccluded1M(
                    self.scene,
                    &mut ctx,
                    buf.as_mut_ptr(),
                    buf.len() as u32,
                    std::mem::size_of::<RTCRay>(),
                );
            }
            for (o, r) in os.iter_mut().zip(&buf) {
                *o = r.occluded();
            }
        }
    }
}

/// The single-ray API (`rtcIntersect1` / `rtcOccluded1`, incoherent hint),
/// so the scene can stand wherever an [`Accel`] does; the batch calls are
/// the trait's, single rays in parallel over the rayon pool.
impl Accel for Embree3Scene {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut rh = ffi::RTCRayHit::of(ray);
        let mut ctx = ffi::RTCIntersectContext::new(ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        // SAFETY: valid scene, context and ray/hit record.
        unsafe { ffi::rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        rh.hit()
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let mut r = RTCRay::of(ray);
        let mut ctx = ffi::RTCIntersectContext::new(ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        // SAFETY: valid scene, context and ray record.
        unsafe { ffi::rtcOccluded1(self.scene, &mut ctx, &mut r) };
        r.occluded()
    }

    fn stats(&self) -> AccelStats {
        self.extent.stats()
    }

    /// Embree's nodes are not visible: one region, the mesh bounds,
    /// holding every triangle.
    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        self.extent.visit_regions(enter, leaf)
    }
}

impl Drop for Embree3Scene {
    fn drop(&mut self) {
        // SAFETY: the scene came from `build` and is released once, before
        // the device (which `_device` keeps alive until after this).
        unsafe { (CALLS.rtcReleaseScene)(self.scene) };
    }
}
