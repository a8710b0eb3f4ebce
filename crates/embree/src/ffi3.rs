//! The few Embree 3 calls the Embree 3 backend needs beyond those shared
//! with Embree 4 ([`crate::rtcore`]), declared by hand from
//! `embree3/rtcore*.h` (Embree 3.13, `RTC_MAX_INSTANCE_LEVEL_COUNT` 1,
//! `RTC_MIN_WIDTH` 0, as Debian's `libembree-dev` builds it). Linked as
//! `-lembree3`, so compiled only with the `embree3` feature.

#![allow(non_camel_case_types)]

use crate::rtcore::{
    self, Calls, RTCDevice, RTCGeometry, RTCRay, RTCScene, RTC_INVALID_GEOMETRY_ID,
};
use std::ffi::{c_char, c_uint, c_void};

pub const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: c_uint = 0;
pub const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: c_uint = 1;

/// `struct RTCRayHit` of Debian's build: one instance level, no instance
/// arrays.
pub type RTCRayHit = rtcore::RTCRayHit<1>;

/// `struct RTCIntersectContext` as `rtcInitIntersectContext` fills it.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCIntersectContext {
    pub flags: c_uint,
    pub filter: *const c_void,
    pub inst_id: [c_uint; 1],
}

impl RTCIntersectContext {
    /// What the header's inline `rtcInitIntersectContext` sets, with the
    /// coherence hint `flags`.
    pub fn new(flags: c_uint) -> Self {
        RTCIntersectContext {
            flags,
            filter: std::ptr::null(),
            inst_id: [RTC_INVALID_GEOMETRY_ID],
        }
    }
}

#[link(name = "embree3")]
extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    pub fn rtcGetDeviceError(device: RTCDevice) -> c_uint;
    pub fn rtcReleaseDevice(device: RTCDevice);
    pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
    pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: c_uint);
    pub fn rtcCommitScene(scene: RTCScene);
    pub fn rtcReleaseScene(scene: RTCScene);
    pub fn rtcNewGeometry(device: RTCDevice, kind: c_uint) -> RTCGeometry;
    pub fn rtcSetNewGeometryBuffer(
        geometry: RTCGeometry,
        kind: c_uint,
        slot: c_uint,
        format: c_uint,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    pub fn rtcSetGeometryBuildQuality(geometry: RTCGeometry, quality: c_uint);
    pub fn rtcCommitGeometry(geometry: RTCGeometry);
    pub fn rtcAttachGeometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
    pub fn rtcReleaseGeometry(geometry: RTCGeometry);
    pub fn rtcIntersect1(
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit,
    );
    pub fn rtcOccluded1(scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay);
    pub fn rtcIntersect1M(
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit,
        m: c_uint,
        byte_stride: usize,
    );
    pub fn rtcOccluded1M(
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        ray: *mut RTCRay,
        m: c_uint,
        byte_stride: usize,
    );
}

/// The device and scene-building calls, linked.
pub const CALLS: Calls = Calls {
    rtcNewDevice,
    rtcGetDeviceError,
    rtcReleaseDevice,
    rtcNewScene,
    rtcSetSceneBuildQuality,
    rtcCommitScene,
    rtcReleaseScene,
    rtcNewGeometry,
    rtcSetNewGeometryBuffer,
    rtcSetGeometryBuildQuality,
    rtcCommitGeometry,
    rtcAttachGeometry,
    rtcReleaseGeometry,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn struct_layouts_match_the_embree_3_headers() {
        // Sizes and offsets from rtcore_ray.h / rtcore_common.h on x86-64.
        assert_eq!(std::mem::size_of::<rtcore::RTCHit<1>>(), 32);
        assert_eq!(std::mem::size_of::<RTCRayHit>(), 80);
        assert_eq!(std::mem::offset_of!(RTCRayHit, hit), 48);
        assert_eq!(std::mem::offset_of!(rtcore::RTCHit<1>, prim_id), 20);
        assert_eq!(std::mem::size_of::<RTCIntersectContext>(), 24);
        assert_eq!(std::mem::offset_of!(RTCIntersectContext, inst_id), 16);
    }
}
