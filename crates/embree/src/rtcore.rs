//! What Embree 3's and Embree 4's headers declare alike
//! (`rtcore_common.h`, `rtcore_ray.h`, `rtcore_device.h`,
//! `rtcore_scene.h`, `rtcore_geometry.h`): the handle types, the
//! constants, the single-ray records and the device and scene-building
//! calls, whose signatures did not change between the versions. Each
//! version fills a [`Calls`] table with its own functions (linked for
//! Embree 3, looked up at run time for Embree 4), so one scene builder
//! serves both.

#![allow(non_camel_case_types, non_snake_case)]

use crate::Quality;
use raykit_core::{Hit, Ray};
use std::ffi::{c_char, c_uint, c_void};

pub type RTCDevice = *mut c_void;
pub type RTCScene = *mut c_void;
pub type RTCGeometry = *mut c_void;

pub const RTC_GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
pub const RTC_BUFFER_TYPE_INDEX: c_uint = 0;
pub const RTC_BUFFER_TYPE_VERTEX: c_uint = 1;
pub const RTC_FORMAT_UINT3: c_uint = 0x5003;
pub const RTC_FORMAT_FLOAT3: c_uint = 0x9003;
pub const RTC_BUILD_QUALITY_MEDIUM: c_uint = 1;
pub const RTC_BUILD_QUALITY_HIGH: c_uint = 2;
pub const RTC_INVALID_GEOMETRY_ID: c_uint = u32::MAX;
pub const RTC_ERROR_NONE: c_uint = 0;

/// `enum RTCBuildQuality` of `quality`.
pub fn build_quality(quality: Quality) -> c_uint {
    match quality {
        Quality::Medium => RTC_BUILD_QUALITY_MEDIUM,
        Quality::High => RTC_BUILD_QUALITY_HIGH,
    }
}

/// `struct RTCRay` (16-byte aligned).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCRay {
    pub org: [f32; 3],
    pub tnear: f32,
    pub dir: [f32; 3],
    pub time: f32,
    pub tfar: f32,
    pub mask: c_uint,
    pub id: c_uint,
    pub flags: c_uint,
}

impl RTCRay {
    /// Embree's record of `r`: every mask bit set, time 0.
    pub fn of(r: &Ray) -> RTCRay {
        RTCRay {
            org: r.origin.to_array(),
            tnear: r.tnear,
            dir: r.dir().to_array(),
            time: 0.0,
            tfar: r.tfar,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }

    /// Whether an occlusion query found a blocker: Embree marks it by
    /// setting `tfar` to −inf.
    pub fn occluded(&self) -> bool {
        self.tfar == f32::NEG_INFINITY
    }
}

/// `struct RTCHit` (16-byte aligned). Its tail, `instID[…]` and, where
/// the library has instance arrays, `instPrimID[…]`, is as long as the
/// library's build makes it: `TAIL` words.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct RTCHit<const TAIL: usize> {
    pub ng: [f32; 3],
    pub u: f32,
    pub v: f32,
    pub prim_id: c_uint,
    pub geom_id: c_uint,
    pub instance_tail: [c_uint; TAIL],
}

/// `struct RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCRayHit<const TAIL: usize> {
    pub ray: RTCRay,
    pub hit: RTCHit<TAIL>,
}

impl<const TAIL: usize> RTCRayHit<TAIL> {
    /// The record of `r` before a query, as `rtcInitRayHit` leaves it:
    /// geometry and instance ids invalid.
    pub fn of(r: &Ray) -> Self {
        RTCRayHit {
            ray: RTCRay::of(r),
            hit: RTCHit {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: 0,
                geom_id: RTC_INVALID_GEOMETRY_ID,
                instance_tail: [RTC_INVALID_GEOMETRY_ID; TAIL],
            },
        }
    }

    /// The nearest hit Embree left in the record, if any.
    pub fn hit(&self) -> Option<Hit> {
        (self.hit.geom_id != RTC_INVALID_GEOMETRY_ID).then_some(Hit {
            t: self.ray.tfar,
            u: self.hit.u,
            v: self.hit.v,
            prim: self.hit.prim_id,
        })
    }
}

/// The device and scene-building calls of one Embree library (names as in
/// the headers).
pub struct Calls {
    pub rtcNewDevice: unsafe extern "C" fn(config: *const c_char) -> RTCDevice,
    pub rtcGetDeviceError: unsafe extern "C" fn(device: RTCDevice) -> c_uint,
    pub rtcReleaseDevice: unsafe extern "C" fn(device: RTCDevice),
    pub rtcNewScene: unsafe extern "C" fn(device: RTCDevice) -> RTCScene,
    pub rtcSetSceneBuildQuality: unsafe extern "C" fn(scene: RTCScene, quality: c_uint),
    pub rtcCommitScene: unsafe extern "C" fn(scene: RTCScene),
    pub rtcReleaseScene: unsafe extern "C" fn(scene: RTCScene),
    pub rtcNewGeometry: unsafe extern "C" fn(device: RTCDevice, kind: c_uint) -> RTCGeometry,
    pub rtcSetNewGeometryBuffer: unsafe extern "C" fn(
        geometry: RTCGeometry,
        kind: c_uint,
        slot: c_uint,
        format: c_uint,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void,
    pub rtcSetGeometryBuildQuality: unsafe extern "C" fn(geometry: RTCGeometry, quality: c_uint),
    pub rtcCommitGeometry: unsafe extern "C" fn(geometry: RTCGeometry),
    pub rtcAttachGeometry: unsafe extern "C" fn(scene: RTCScene, geometry: RTCGeometry) -> c_uint,
    pub rtcReleaseGeometry: unsafe extern "C" fn(geometry: RTCGeometry),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ray_record_matches_the_headers() {
        // rtcore_ray.h on x86-64, the same in Embree 3 and 4.
        assert_eq!(std::mem::size_of::<RTCRay>(), 48);
        assert_eq!(std::mem::align_of::<RTCRay>(), 16);
        assert_eq!(std::mem::offset_of!(RTCRay, tfar), 32);
        assert_eq!(std::mem::offset_of!(RTCRay, flags), 44);
    }
}
