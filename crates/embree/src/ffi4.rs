//! The few Embree 4 calls the Embree 4 backend needs, declared by hand
//! from `embree4/rtcore*.h` (Embree 4.4.0) and looked up at run time in a
//! `libembree4.so.4` (the one the PyPI wheel `embreex` ships has no
//! headers, and a build machine need not have it at all); those shared
//! with Embree 3 are in [`crate::rtcore`].
//!
//! Two settings of Embree's own build change these layouts:
//! `RTC_MAX_INSTANCE_LEVEL_COUNT` (default 1) and
//! `RTC_GEOMETRY_INSTANCE_ARRAY` (adds `instPrimID` after `instID`), and
//! `RTC_MIN_WIDTH` adds a float to the argument structs. Each changes only
//! the tail of a structure, so the records here reserve room for the
//! largest tail (instance levels up to [`INSTANCE_LEVELS`], with instance
//! primitive ids, and the minimum-width factor): Embree reads and writes
//! the fields before the tail at the offsets declared, whatever its build.

#![allow(non_camel_case_types)]

use crate::rtcore::{self, Calls, RTCDevice, RTCRay, RTCScene, RTC_INVALID_GEOMETRY_ID};
use std::ffi::{c_int, c_uint, c_void};

pub const RTC_RAY_QUERY_FLAG_INCOHERENT: c_uint = 0;
pub const RTC_RAY_QUERY_FLAG_COHERENT: c_uint = 1 << 16;
pub const RTC_FEATURE_FLAG_ALL: c_uint = 0xffff_ffff;
/// `RTC_DEVICE_PROPERTY_VERSION`: the version as MAJOR·10000 + MINOR·100 +
/// PATCH.
pub const RTC_DEVICE_PROPERTY_VERSION: c_uint = 0;

/// Instance levels the hit records leave room for (Embree's default build
/// has 1).
pub const INSTANCE_LEVELS: usize = 4;

/// `struct RTCRayHit` with room for the largest instance tail.
pub type RTCRayHit = rtcore::RTCRayHit<{ 2 * INSTANCE_LEVELS }>;

/// `struct RTCRayHitN` for N = 4, 8, 16: `RTCRayN` then `RTCHitN`, each
/// field an array of N (structure of arrays). Aligned to 64 bytes, the
/// strictest of `RTCRayHit4` (16), `RTCRayHit8` (32) and `RTCRayHit16`
/// (64); `RTCRayN` is 48·N bytes, a multiple of 64 for every N, so the hit
/// part starts at 48·N as in the headers. Used for `rtcOccludedN` too,
/// whose `RTCRayN` is the first part.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct RTCRayHitN<const N: usize> {
    pub org_x: [f32; N],
    pub org_y: [f32; N],
    pub org_z: [f32; N],
    pub tnear: [f32; N],
    pub dir_x: [f32; N],
    pub dir_y: [f32; N],
    pub dir_z: [f32; N],
    pub time: [f32; N],
    pub tfar: [f32; N],
    pub mask: [c_uint; N],
    pub id: [c_uint; N],
    pub flags: [c_uint; N],
    pub ng_x: [f32; N],
    pub ng_y: [f32; N],
    pub ng_z: [f32; N],
    pub u: [f32; N],
    pub v: [f32; N],
    pub prim_id: [c_uint; N],
    pub geom_id: [c_uint; N],
    /// `instID[levels][N]` and `instPrimID[levels][N]`.
    pub instance_tail: [[c_uint; N]; 2 * INSTANCE_LEVELS],
}

impl<const N: usize> Default for RTCRayHitN<N> {
    fn default() -> Self {
        RTCRayHitN {
            org_x: [0.0; N],
            org_y: [0.0; N],
            org_z: [0.0; N],
            tnear: [0.0; N],
            dir_x: [0.0; N],
            dir_y: [0.0; N],
            dir_z: [0.0; N],
            time: [0.0; N],
            tfar: [0.0; N],
            mask: [u32::MAX; N],
            id: [0; N],
            flags: [0; N],
            ng_x: [0.0; N],
            ng_y: [0.0; N],
            ng_z: [0.0; N],
            u: [0.0; N],
            v: [0.0; N],
            prim_id: [0; N],
            geom_id: [RTC_INVALID_GEOMETRY_ID; N],
            instance_tail: [[RTC_INVALID_GEOMETRY_ID; N]; 2 * INSTANCE_LEVELS],
        }
    }
}

/// The `valid` mask of a packet call: −1 for an active lane, 0 for an idle
/// one. Embree loads it as one SIMD vector, hence the alignment.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct Valid<const N: usize>(pub [c_int; N]);

/// `struct RTCIntersectArguments` and `struct RTCOccludedArguments` (the
/// same layout: flags, feature mask, context, filter, user-geometry
/// callback, then the minimum-width factor where `RTC_MIN_WIDTH` is on).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCQueryArguments {
    pub flags: c_uint,
    pub feature_mask: c_uint,
    /// `RTCRayQueryContext*`; null: Embree uses a fresh default context.
    pub context: *mut c_void,
    pub filter: *const c_void,
    pub user_geometry: *const c_void,
    pub min_width_distance_factor: f32,
}

impl RTCQueryArguments {
    /// What `rtcInitIntersectArguments` / `rtcInitOccludedArguments` set,
    /// with the coherence hint `flags`.
    pub fn new(flags: c_uint) -> Self {
        RTCQueryArguments {
            flags,
            feature_mask: RTC_FEATURE_FLAG_ALL,
            context: std::ptr::null_mut(),
            filter: std::ptr::null(),
            user_geometry: std::ptr::null(),
            min_width_distance_factor: 0.0,
        }
    }
}

pub type RtcIntersectN<const N: usize> = unsafe extern "C" fn(
    valid: *const c_int,
    scene: RTCScene,
    rayhit: *mut RTCRayHitN<N>,
    args: *mut RTCQueryArguments,
);

/// The functions looked up in the library (names as in the headers).
#[allow(non_snake_case)]
pub struct Api {
    /// The device and scene-building calls.
    pub calls: Calls,
    pub rtcGetDeviceProperty: unsafe extern "C" fn(device: RTCDevice, prop: c_uint) -> isize,
    pub rtcIntersect1:
        unsafe extern "C" fn(scene: RTCScene, rayhit: *mut RTCRayHit, args: *mut RTCQueryArguments),
    pub rtcOccluded1:
        unsafe extern "C" fn(scene: RTCScene, ray: *mut RTCRay, args: *mut RTCQueryArguments),
    pub rtcIntersect4: RtcIntersectN<4>,
    pub rtcIntersect8: RtcIntersectN<8>,
    pub rtcIntersect16: RtcIntersectN<16>,
    /// `rtcOccludedN` takes an `RTCRayN*`, the first part of the record.
    pub rtcOccluded4: RtcIntersectN<4>,
    pub rtcOccluded8: RtcIntersectN<8>,
    pub rtcOccluded16: RtcIntersectN<16>,
}

impl Api {
    /// Look every function up in `lib`.
    ///
    /// # Safety
    /// `lib` must be an Embree 4 library, whose functions have the
    /// signatures declared here; the returned table must not outlive it.
    pub unsafe fn load(lib: &libloading::Library) -> Result<Api, libloading::Error> {
        macro_rules! sym {
            ($name:ident) => {
                *lib.get(concat!(stringify!($name), "\0").as_bytes())?
            };
        }
        Ok(Api {
            calls: Calls {
                rtcNewDevice: sym!(rtcNewDevice),
                rtcGetDeviceError: sym!(rtcGetDeviceError),
                rtcReleaseDevice: sym!(rtcReleaseDevice),
                rtcNewScene: sym!(rtcNewScene),
                rtcSetSceneBuildQuality: sym!(rtcSetSceneBuildQuality),
                rtcCommitScene: sym!(rtcCommitScene),
                rtcReleaseScene: sym!(rtcReleaseScene),
                rtcNewGeometry: sym!(rtcNewGeometry),
                rtcSetNewGeometryBuffer: sym!(rtcSetNewGeometryBuffer),
                rtcSetGeometryBuildQuality: sym!(rtcSetGeometryBuildQuality),
                rtcCommitGeometry: sym!(rtcCommitGeometry),
                rtcAttachGeometry: sym!(rtcAttachGeometry),
                rtcReleaseGeometry: sym!(rtcReleaseGeometry),
            },
            rtcGetDeviceProperty: sym!(rtcGetDeviceProperty),
            rtcIntersect1: sym!(rtcIntersect1),
            rtcOccluded1: sym!(rtcOccluded1),
            rtcIntersect4: sym!(rtcIntersect4),
            rtcIntersect8: sym!(rtcIntersect8),
            rtcIntersect16: sym!(rtcIntersect16),
            rtcOccluded4: sym!(rtcOccluded4),
            rtcOccluded8: sym!(rtcOccluded8),
            rtcOccluded16: sym!(rtcOccluded16),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{align_of, offset_of};

    #[test]
    fn struct_layouts_match_the_embree_4_headers() {
        // Offsets from embree4/rtcore_ray.h and rtcore_scene.h (4.4.0) on
        // x86-64; the tails only add room after the declared fields.
        assert_eq!(offset_of!(RTCRayHit, hit), 48);
        type RTCHit = rtcore::RTCHit<{ 2 * INSTANCE_LEVELS }>;
        assert_eq!(offset_of!(RTCHit, prim_id), 20);
        assert_eq!(offset_of!(RTCHit, geom_id), 24);
        assert_eq!(offset_of!(RTCHit, instance_tail), 28);
        // RTCRayHitN: RTCRayN is 12 arrays of N, the hit follows at 48·N.
        fn packet<const N: usize>() {
            let w = 4 * N;
            assert_eq!(offset_of!(RTCRayHitN<N>, tnear), 3 * w);
            assert_eq!(offset_of!(RTCRayHitN<N>, tfar), 8 * w);
            assert_eq!(offset_of!(RTCRayHitN<N>, ng_x), 12 * w);
            assert_eq!(offset_of!(RTCRayHitN<N>, u), 15 * w);
            assert_eq!(offset_of!(RTCRayHitN<N>, prim_id), 17 * w);
            assert_eq!(offset_of!(RTCRayHitN<N>, geom_id), 18 * w);
            assert_eq!(offset_of!(RTCRayHitN<N>, instance_tail), 19 * w);
            assert!(align_of::<RTCRayHitN<N>>() >= w.min(64));
            assert!(align_of::<Valid<N>>() >= w);
        }
        packet::<4>();
        packet::<8>();
        packet::<16>();
        // flags, feature mask, three pointers, then the min-width float.
        assert_eq!(offset_of!(RTCQueryArguments, context), 8);
        assert_eq!(offset_of!(RTCQueryArguments, user_geometry), 24);
        assert_eq!(offset_of!(RTCQueryArguments, min_width_distance_factor), 32);
    }
}
