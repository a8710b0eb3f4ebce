//! Embree 4 (Wald et al. 2014), loaded at run time ([`Embree4::load`]): a
//! device, and a scene over one triangle mesh, built like the Embree 3
//! one, answering rays through every query API Embree 4 offers on the CPU:
//! single rays (`rtcIntersect1` / `rtcOccluded1`) and packets of 4, 8 and
//! 16 (`rtcIntersectN` / `rtcOccludedN`).

use crate::ffi4 as ffi;
use crate::library4::Embree4;
use crate::mesh_scene::{self, MeshExtent};
use crate::rtcore::{RTCDevice, RTCRay, RTCScene, RTC_INVALID_GEOMETRY_ID};
use crate::Quality;
use anyhow::Result;
use raykit_core::accel::AccelStats;
use raykit_core::{Aabb, Accel, Hit, Ray, TriangleMesh, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

/// The library's name in errors.
const VERSION: &str = "Embree 4";

/// Rays handed to one rayon task by the packet traces (a multiple of 16).
const TASK_RAYS: usize = 1024;

/// A query API of Embree 4: single rays or packets of 4, 8 or 16.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QueryApi {
    /// `rtcIntersect1` / `rtcOccluded1`, one call per ray.
    Single,
    /// `rtcIntersect4` / `rtcOccluded4`.
    Packet4,
    /// `rtcIntersect8` / `rtcOccluded8`.
    Packet8,
    /// `rtcIntersect16` / `rtcOccluded16`.
    Packet16,
}

impl QueryApi {
    /// Every API, single rays first.
    pub const ALL: [QueryApi; 4] = [
        QueryApi::Single,
        QueryApi::Packet4,
        QueryApi::Packet8,
        QueryApi::Packet16,
    ];

    /// The suffix of the Embree call: `1`, `4`, `8` or `16`.
    pub fn width(self) -> usize {
        match self {
            QueryApi::Single => 1,
            QueryApi::Packet4 => 4,
            QueryApi::Packet8 => 8,
            QueryApi::Packet16 => 16,
        }
    }
}

/// An Embree 4 device: its thread pool and allocator.
pub struct Embree4Device {
    lib: Arc<Embree4>,
    raw: RTCDevice,
}

// SAFETY: an Embree device may be used from any thread.
unsafe impl Send for Embree4Device {}
// SAFETY: as above.
unsafe impl Sync for Embree4Device {}

impl Embree4Device {
    /// A device of `lib` with `threads` build threads (0: all cores);
    /// `$RAYKIT_EMBREE_CONFIG` ([`crate::CONFIG_ENV`]) adds to its
    /// configuration string, as for Embree 3.
    pub fn new(lib: &Arc<Embree4>, threads: usize) -> Result<Arc<Embree4Device>> {
        let raw = mesh_scene::new_device(&lib.api.calls, threads, VERSION)?;
        Ok(Arc::new(Embree4Device {
            lib: Arc::clone(lib),
            raw,
        }))
    }
}

impl Drop for Embree4Device {
    fn drop(&mut self) {
        // SAFETY: created by `new`, released once.
        unsafe { (self.lib.api.calls.rtcReleaseDevice)(self.raw) };
    }
}

/// A committed Embree 4 scene holding one triangle mesh.
pub struct Embree4Scene {
    device: Arc<Embree4Device>,
    scene: RTCScene,
    extent: MeshExtent,
}

// SAFETY: Embree documents its query calls on a committed scene as
// thread-safe; the scene is not modified after `build`.
unsafe impl Send for Embree4Scene {}
// SAFETY: as above; `&Embree4Scene` only issues queries.
unsafe impl Sync for Embree4Scene {}

impl Embree4Scene {
    /// Build Embree 4's BVH over `mesh` with `quality` on `device`.
    pub fn build(
        device: &Arc<Embree4Device>,
        mesh: &TriangleMesh,
        quality: Quality,
    ) -> Result<Embree4Scene> {
        Self::build_triangles(device, &mesh.positions, &mesh.indices, quality)
    }

    /// Build Embree 4's BVH over the triangles `indices` into `positions`;
    /// an index past the vertices is an error naming the triangle.
    pub fn build_triangles(
        device: &Arc<Embree4Device>,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        quality: Quality,
    ) -> Result<Embree4Scene> {
        let calls = &device.lib.api.calls;
        // SAFETY: `device` is a live device of the library `calls` is from.
        let (scene, extent) =
            unsafe { mesh_scene::build(calls, device.raw, positions, indices, quality, VERSION)? };
        Ok(Embree4Scene {
            device: Arc::clone(device),
            scene,
            extent,
        })
    }

    fn api(&self) -> &ffi::Api {
        &self.device.lib.api
    }

    /// Nearest hits of `rays` through `api`, in parallel over the rayon
    /// pool; `coherent` is the hint passed in the query arguments.
    pub fn intersect_with(
        &self,
        api: QueryApi,
        rays: &[Ray],
        hits: &mut [Option<Hit>],
        coherent: bool,
    ) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        let flags = query_flags(coherent);
        rays.par_chunks(TASK_RAYS)
            .zip(hits.par_chunks_mut(TASK_RAYS))
            .for_each(|(r, h)| match api {
                QueryApi::Single => {
                    for (ray, hit) in r.iter().zip(h) {
                        *hit = self.intersect1(ray, flags);
                    }
                }
                QueryApi::Packet4 => self.intersect_packets::<4>(r, h, flags),
                QueryApi::Packet8 => self.intersect_packets::<8>(r, h, flags),
                QueryApi::Packet16 => self.intersect_packets::<16>(r, h, flags),
            });
    }

    /// Occlusion of `rays` through `api`, in parallel over the rayon pool.
    pub fn occluded_with(
        &self,
        api: QueryApi,
        rays: &[Ray],
        occluded: &mut [bool],
        coherent: bool,
    ) {
        assert_eq!(rays.len(), occluded.len(), "one result per ray");
        let flags = query_flags(coherent);
        rays.par_chunks(TASK_RAYS)
            .zip(occluded.par_chunks_mut(TASK_RAYS))
            .for_each(|(r, o)| match api {
                QueryApi::Single => {
                    for (ray, o) in r.iter().zip(o) {
                        *o = self.occluded1(ray, flags);
                    }
                }
                QueryApi::Packet4 => self.occluded_packets::<4>(r, o, flags),
                QueryApi::Packet8 => self.occluded_packets::<8>(r, o, flags),
                QueryApi::Packet16 => self.occluded_packets::<16>(r, o, flags),
            });
    }

    fn intersect1(&self, ray: &Ray, flags: u32) -> Option<Hit> {
        let mut rh = ffi::RTCRayHit::of(ray);
        let mut args = ffi::RTCQueryArguments::new(flags);
        // SAFETY: valid scene, ray/hit record and arguments.
        unsafe { (self.api().rtcIntersect1)(self.scene, &mut rh, &mut args) };
        rh.hit()
    }

    fn occluded1(&self, ray: &Ray, flags: u32) -> bool {
        let mut r = RTCRay::of(ray);
        let mut args = ffi::RTCQueryArguments::new(flags);
        // SAFETY: valid scene, ray record and arguments.
        unsafe { (self.api().rtcOccluded1)(self.scene, &mut r, &mut args) };
        r.occluded()
    }

    fn intersect_packets<const N: usize>(&self, rays: &[Ray], hits: &mut [Option<Hit>], flags: u32)
    where
        Self: PacketCalls<N>,
    {
        let mut args = ffi::RTCQueryArguments::new(flags);
        for (rs, hs) in rays.chunks(N).zip(hits.chunks_mut(N)) {
            let (valid, mut p) = packet::<N>(rs);
            self.intersect_n(&valid, &mut p, &mut args);
            for (i, h) in hs.iter_mut().enumerate() {
                *h = (p.geom_id[i] != RTC_INVALID_GEOMETRY_ID).then_some(Hit {
                    t: p.tfar[i],
                    u: p.u[i],
                    v: p.v[i],
                    prim: p.prim_id[i],
                });
            }
        }
    }

    fn occluded_packets<const N: usize>(&self, rays: &[Ray], occluded: &mut [bool], flags: u32)
    where
        Self: PacketCalls<N>,
    {
        let mut args = ffi::RTCQueryArguments::new(flags);
        for (rs, os) in rays.chunks(N).zip(occluded.chunks_mut(N)) {
            let (valid, mut p) = packet::<N>(rs);
            self.occluded_n(&valid, &mut p, &mut args);
            for (i, o) in os.iter_mut().enumerate() {
                *o = p.tfar[i] == f32::NEG_INFINITY;
            }
        }
    }
}

/// The packet calls of one width.
trait PacketCalls<const N: usize> {
    /// `rtcIntersectN`.
    fn intersect_n(
        &self,
        valid: &ffi::Valid<N>,
        p: &mut ffi::RTCRayHitN<N>,
        args: &mut ffi::RTCQueryArguments,
    );
    /// `rtcOccludedN`.
    fn occluded_n(
        &self,
        valid: &ffi::Valid<N>,
        p: &mut ffi::RTCRayHitN<N>,
        args: &mut ffi::RTCQueryArguments,
    );
}

macro_rules! packet_calls {
    ($n:literal, $isect:ident, $occl:ident) => {
        impl PacketCalls<$n> for Embree4Scene {
            fn intersect_n(
                &self,
                valid: &ffi::Valid<$n>,
                p: &mut ffi::RTCRayHitN<$n>,
                args: &mut ffi::RTCQueryArguments,
            ) {
                // SAFETY: an aligned valid mask and packet record of width
                // $n, valid arguments, a committed scene.
                unsafe { (self.api().$isect)(valid.0.as_ptr(), self.scene, p, args) };
            }
            fn occluded_n(
                &self,
                valid: &ffi::Valid<$n>,
                p: &mut ffi::RTCRayHitN<$n>,
                args: &mut ffi::RTCQueryArguments,
            ) {
                // SAFETY: as above; the ray part leads the record.
                unsafe { (self.api().$occl)(valid.0.as_ptr(), self.scene, p, args) };
            }
        }
    };
}
packet_calls!(4, rtcIntersect4, rtcOccluded4);
packet_calls!(8, rtcIntersect8, rtcOccluded8);
packet_calls!(16, rtcIntersect16, rtcOccluded16);

fn query_flags(coherent: bool) -> u32 {
    if coherent {
        ffi::RTC_RAY_QUERY_FLAG_COHERENT
    } else {
        ffi::RTC_RAY_QUERY_FLAG_INCOHERENT
    }
}

/// A packet of up to N rays and its valid mask (idle lanes: 0).
fn packet<const N: usize>(rays: &[Ray]) -> (ffi::Valid<N>, ffi::RTCRayHitN<N>) {
    let mut valid = ffi::Valid([0; N]);
    let mut p = ffi::RTCRayHitN::<N>::default();
    for (i, r) in rays.iter().enumerate().take(N) {
        valid.0[i] = -1;
        [p.org_x[i], p.org_y[i], p.org_z[i]] = r.origin.to_array();
        [p.dir_x[i], p.dir_y[i], p.dir_z[i]] = r.dir().to_array();
        p.tnear[i] = r.tnear;
        p.tfar[i] = r.tfar;
    }
    (valid, p)
}

/// The single-ray API (`rtcIntersect1` / `rtcOccluded1`, incoherent hint),
/// so the scene can stand wherever an [`Accel`] does.
impl Accel for Embree4Scene {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.intersect1(ray, ffi::RTC_RAY_QUERY_FLAG_INCOHERENT)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.occluded1(ray, ffi::RTC_RAY_QUERY_FLAG_INCOHERENT)
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

impl Drop for Embree4Scene {
    fn drop(&mut self) {
        // SAFETY: the scene came from `build` and is released once, before
        // the device (which `self.device` keeps alive until after this).
        unsafe { (self.api().calls.rtcReleaseScene)(self.scene) };
    }
}
