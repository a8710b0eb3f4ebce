//! One triangle mesh committed into an Embree scene: the device and the
//! build steps, the same for Embree 3 and 4 through their [`Calls`] tables,
//! and what a scene keeps of the mesh to answer the [`Accel`] trait's
//! statistics and regions (Embree's own nodes are not visible).
//!
//! [`Accel`]: raykit_core::Accel

use crate::rtcore::{self, Calls, RTCDevice, RTCScene};
use crate::{Quality, CONFIG_ENV};
use anyhow::{bail, Result};
use raykit_core::accel::AccelStats;
use raykit_core::{Aabb, Vec3};
use std::ffi::CString;

/// Embree's device configuration string for `threads` threads (0: all
/// cores), with [`CONFIG_ENV`]'s extra settings appended.
fn device_config(threads: usize) -> String {
    let mut config = if threads == 0 {
        String::new()
    } else {
        format!("threads={threads}")
    };
    if let Ok(extra) = std::env::var(CONFIG_ENV) {
        if !extra.trim().is_empty() {
            if !config.is_empty() {
                config.push(',');
            }
            config.push_str(extra.trim());
        }
    }
    config
}

/// A new device with `threads` build threads (0: all cores); `version`
/// names the library in the error.
pub fn new_device(calls: &Calls, threads: usize, version: &str) -> Result<RTCDevice> {
    let config = CString::new(device_config(threads))?;
    // SAFETY: a valid NUL-terminated configuration string.
    let raw = unsafe { (calls.rtcNewDevice)(config.as_ptr()) };
    if raw.is_null() {
        bail!("{version} could not create a device (configuration '{config:?}')");
    }
    Ok(raw)
}

/// The bounds and triangle count of a scene's mesh.
pub struct MeshExtent {
    bounds: Aabb,
    triangles: usize,
}

impl MeshExtent {
    /// Statistics of a structure whose nodes are not visible: only the
    /// triangles it references.
    pub fn stats(&self) -> AccelStats {
        AccelStats {
            triangle_refs: self.triangles,
            ..AccelStats::default()
        }
    }

    /// One region, the mesh bounds, holding every triangle (conservative,
    /// as the [`Accel`](raykit_core::Accel) trait asks).
    pub fn visit_regions(
        &self,
        enter: &mut dyn FnMut(&Aabb) -> bool,
        leaf: &mut dyn FnMut(&[u32]),
    ) {
        if enter(&self.bounds) {
            let all: Vec<u32> = (0..self.triangles as u32).collect();
            leaf(&all);
        }
    }
}

/// Commit the triangles `indices` over `positions` into a new scene on
/// `device`, with `quality` for the scene and the geometry. An index past
/// the vertices is an error naming the triangle; `version` names the
/// library in errors.
///
/// # Safety
/// `device` must be a live device of the library `calls` comes from.
pub unsafe fn build(
    calls: &Calls,
    device: RTCDevice,
    positions: &[Vec3],
    indices: &[[u32; 3]],
    quality: Quality,
    version: &str,
) -> Result<(RTCScene, MeshExtent)> {
    let mut bounds = Aabb::EMPTY;
    for (t, tri) in indices.iter().enumerate() {
        for &i in tri {
            match positions.get(i as usize) {
                Some(&p) => bounds = bounds.grow(p),
                None => bail!(
                    "triangle {t}: vertex index {i} is past the {} vertices",
                    positions.len()
                ),
            }
        }
    }
    let q = rtcore::build_quality(quality);
    // SAFETY: plain FFI calls with valid arguments; every buffer Embree
    // returns is written within the size asked for.
    unsafe {
        let scene = (calls.rtcNewScene)(device);
        (calls.rtcSetSceneBuildQuality)(scene, q);
        let geom = (calls.rtcNewGeometry)(device, rtcore::RTC_GEOMETRY_TYPE_TRIANGLE);
        (calls.rtcSetGeometryBuildQuality)(geom, q);
        let vb = (calls.rtcSetNewGeometryBuffer)(
            geom,
            rtcore::RTC_BUFFER_TYPE_VERTEX,
            0,
            rtcore::RTC_FORMAT_FLOAT3,
            12,
            positions.len(),
        ) as *mut f32;
        let ib = (calls.rtcSetNewGeometryBuffer)(
            geom,
            rtcore::RTC_BUFFER_TYPE_INDEX,
            0,
            rtcore::RTC_FORMAT_UINT3,
            12,
            indices.len(),
        ) as *mut u32;
        if vb.is_null() || ib.is_null() {
            (calls.rtcReleaseGeometry)(geom);
            (calls.rtcReleaseScene)(scene);
            bail!("{version} could not allocate the mesh buffers");
        }
        let verts = std::slice::from_raw_parts_mut(vb, positions.len() * 3);
        for (dst, p) in verts.chunks_exact_mut(3).zip(positions) {
            dst.copy_from_slice(&p.to_array());
        }
        let idx = std::slice::from_raw_parts_mut(ib, indices.len() * 3);
        for (dst, t) in idx.chunks_exact_mut(3).zip(indices) {
            dst.copy_from_slice(t);
        }
        (calls.rtcCommitGeometry)(geom);
        (calls.rtcAttachGeometry)(scene, geom);
        (calls.rtcReleaseGeometry)(geom);
        (calls.rtcCommitScene)(scene);
        let err = (calls.rtcGetDeviceError)(device);
        if err != rtcore::RTC_ERROR_NONE {
            (calls.rtcReleaseScene)(scene);
            bail!("{version} reported error {err} while building the scene");
        }
        let extent = MeshExtent {
            bounds,
            triangles: indices.len(),
        };
        Ok((scene, extent))
    }
}
