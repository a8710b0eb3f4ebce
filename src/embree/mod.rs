//! Embree as a comparison backend for `raykit bench --compare embree`
//! (cargo feature `embree`): Embree 3 linked from Debian's
//! `libembree-dev`, and Embree 4 loaded at run time ([`embree4`]). Never the
//! engine itself: it answers the same rays as our structures so the
//! benchmark can check the answers agree and print the speed ratio.

pub mod embree4;
mod ffi;
mod ffi4;

use anyhow::{bail, Result};
use raykit_core::accel::AccelStats;
use raykit_core::{Aabb, Accel, Hit, Ray, TriangleMesh};
use std::ffi::CString;
use std::sync::Arc;

/// Embree's build quality.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// `RTC_BUILD_QUALITY_MEDIUM`: the default fast build.
    Medium,
    /// `RTC_BUILD_QUALITY_HIGH`: with spatial splits.
    High,
}

/// Embree's device configuration string for `threads` threads (0: all
/// cores), with RAYKIT_EMBREE_CONFIG's extra settings for experiments, e.g.
/// `isa=avx2` or `verbose=1`. The same for Embree 3 and 4.
fn device_config(threads: usize) -> String {
    let mut config = if threads == 0 {
        String::new()
    } else {
        format!("threads={threads}")
    };
    if let Ok(extra) = std::env::var("RAYKIT_EMBREE_CONFIG") {
        if !extra.trim().is_empty() {
            if !config.is_empty() {
                config.push(',');
            }
            config.push_str(extra.trim());
        }
    }
    config
}

/// An Embree device: its thread pool and allocator, created once so that
/// build timings measure the build alone.
pub struct EmbreeDevice {
    raw: ffi::RTCDevice,
}

// SAFETY: an Embree device may be used from any thread.
unsafe impl Send for EmbreeDevice {}
// SAFETY: as above.
unsafe impl Sync for EmbreeDevice {}

impl EmbreeDevice {
    /// A device with `threads` build threads (0: Embree's default, all cores).
    pub fn new(threads: usize) -> Result<Arc<EmbreeDevice>> {
        let config = CString::new(device_config(threads))?;
        // SAFETY: a valid NUL-terminated configuration string.
        let raw = unsafe { ffi::rtcNewDevice(config.as_ptr()) };
        if raw.is_null() {
            bail!("Embree could not create a device");
        }
        Ok(Arc::new(EmbreeDevice { raw }))
    }
}

impl Drop for EmbreeDevice {
    fn drop(&mut self) {
        // SAFETY: created by `new`, released once.
        unsafe { ffi::rtcReleaseDevice(self.raw) };
    }
}

/// A committed Embree scene holding one triangle mesh.
pub struct EmbreeScene {
    /// Kept so the device outlives the scene.
    _device: Arc<EmbreeDevice>,
    scene: ffi::RTCScene,
    bounds: Aabb,
    triangles: usize,
}

// SAFETY: Embree documents rtcIntersect1/rtcOccluded1/rtcIntersect1M on a
// committed scene as thread-safe; the scene is not modified after `build`.
unsafe impl Send for EmbreeScene {}
// SAFETY: as above; `&EmbreeScene` only issues queries.
unsafe impl Sync for EmbreeScene {}

impl EmbreeScene {
    /// Build Embree's BVH over `mesh` with `quality` on `device`.
    pub fn build(
        dev: &Arc<EmbreeDevice>,
        mesh: &TriangleMesh,
        quality: Quality,
    ) -> Result<EmbreeScene> {
        let raw = dev.raw;
        // SAFETY: plain FFI calls with valid arguments; every buffer Embree
        // returns is written within the size we asked for.
        unsafe {
            let device = raw;
            let scene = ffi::rtcNewScene(device);
            let q = match quality {
                Quality::Medium => ffi::RTC_BUILD_QUALITY_MEDIUM,
                Quality::High => ffi::RTC_BUILD_QUALITY_HIGH,
            };
            ffi::rtcSetSceneBuildQuality(scene, q);
            let geom = ffi::rtcNewGeometry(device, ffi::RTC_GEOMETRY_TYPE_TRIANGLE);
            ffi::rtcSetGeometryBuildQuality(geom, q);
            let nv = mesh.positions.len();
            let vb = ffi::rtcSetNewGeometryBuffer(
                geom,
                ffi::RTC_BUFFER_TYPE_VERTEX,
                0,
                ffi::RTC_FORMAT_FLOAT3,
                12,
                nv,
            ) as *mut f32;
            let ib = ffi::rtcSetNewGeometryBuffer(
                geom,
                ffi::RTC_BUFFER_TYPE_INDEX,
                0,
                ffi::RTC_FORMAT_UINT3,
                12,
                mesh.indices.len(),
            ) as *mut u32;
            if vb.is_null() || ib.is_null() {
                ffi::rtcReleaseGeometry(geom);
                ffi::rtcReleaseScene(scene);
                bail!("Embree could not allocate the mesh buffers");
            }
            let verts = std::slice::from_raw_parts_mut(vb, nv * 3);
            for (dst, p) in verts.chunks_exact_mut(3).zip(&mesh.positions) {
                dst.copy_from_slice(&p.to_array());
            }
            let idx = std::slice::from_raw_parts_mut(ib, mesh.indices.len() * 3);
            for (dst, t) in idx.chunks_exact_mut(3).zip(&mesh.indices) {
                dst.copy_from_slice(t);
            }
            ffi::rtcCommitGeometry(geom);
            ffi::rtcAttachGeometry(scene, geom);
            ffi::rtcReleaseGeometry(geom);
            ffi::rtcCommitScene(scene);
            let err = ffi::rtcGetDeviceError(device);
            if err != ffi::RTC_ERROR_NONE {
                ffi::rtcReleaseScene(scene);
                bail!("Embree reported error {err} while building the scene");
            }
            Ok(EmbreeScene {
                _device: Arc::clone(dev),
                scene,
                bounds: mesh.bounds(),
                triangles: mesh.num_triangles(),
            })
        }
    }

    /// Nearest hits of `rays` through Embree's stream API (`rtcIntersect1M`),
    /// in packets of `packet` rays, marked coherent.
    pub fn intersect_stream(&self, rays: &[Ray], hits: &mut [Option<Hit>], packet: usize) {
        let mut buf: Vec<ffi::RTCRayHit> = Vec::with_capacity(packet);
        for (rs, hs) in rays
            .chunks(packet.max(1))
            .zip(hits.chunks_mut(packet.max(1)))
        {
            buf.clear();
            buf.extend(rs.iter().map(ray_hit));
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
                *h = to_hit(rh);
            }
        }
    }
}

fn ray_of(r: &Ray) -> ffi::RTCRay {
    ffi::RTCRay {
        org: r.origin.to_array(),
        tnear: r.tnear,
        dir: r.dir.to_array(),
        time: 0.0,
        tfar: r.tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

fn ray_hit(r: &Ray) -> ffi::RTCRayHit {
    ffi::RTCRayHit {
        ray: ray_of(r),
        hit: ffi::RTCHit {
            geom_id: ffi::RTC_INVALID_GEOMETRY_ID,
            inst_id: [ffi::RTC_INVALID_GEOMETRY_ID],
            ..Default::default()
        },
    }
}

fn to_hit(rh: &ffi::RTCRayHit) -> Option<Hit> {
    (rh.hit.geom_id != ffi::RTC_INVALID_GEOMETRY_ID).then_some(Hit {
        t: rh.ray.tfar,
        u: rh.hit.u,
        v: rh.hit.v,
        prim: rh.hit.prim_id,
    })
}

impl Accel for EmbreeScene {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut rh = ray_hit(ray);
        let mut ctx = ffi::RTCIntersectContext::new(ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        // SAFETY: valid scene, context and ray/hit record.
        unsafe { ffi::rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        to_hit(&rh)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let mut r = ray_of(ray);
        let mut ctx = ffi::RTCIntersectContext::new(ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        // SAFETY: valid scene, context and ray record.
        unsafe { ffi::rtcOccluded1(self.scene, &mut ctx, &mut r) };
        // Embree marks an occluded ray by setting tfar to −inf.
        r.tfar == f32::NEG_INFINITY
    }

    fn stats(&self) -> AccelStats {
        AccelStats {
            triangle_refs: self.triangles,
            ..AccelStats::default()
        }
    }

    /// Embree's nodes are not visible: one region, the mesh bounds, holding
    /// every triangle (conservative, as the trait asks).
    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        if enter(&self.bounds) {
            let all: Vec<u32> = (0..self.triangles as u32).collect();
            leaf(&all);
        }
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: the scene came from `build` and is released once, before
        // the device (which `self.device` keeps alive until after this).
        unsafe { ffi::rtcReleaseScene(self.scene) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
    use raykit_core::rng::Pcg32;
    use raykit_core::tri::TestKind;

    /// Embree's answers against brute force over random rays through the
    /// Cornell box: same hit or miss and distance, except rays that graze an
    /// edge (the nearer triangle met within 1% of its edge, computed in f64).
    #[test]
    fn embree_agrees_with_brute_force() {
        let mesh = raykit_scene::builtin("cornell").unwrap().mesh;
        let brute = build_accel(
            AccelKind::Brute,
            TestKind::Moller,
            &mesh,
            &BuildOptions::default(),
        );
        for quality in [Quality::High, Quality::Medium] {
            let em = EmbreeScene::build(&EmbreeDevice::new(1).unwrap(), &mesh, quality).unwrap();
            let mut rng = Pcg32::new(7);
            let b = mesh.bounds();
            let mut stream_rays = Vec::new();
            let mut grazed = 0;
            for _ in 0..4000 {
                let o = rng.in_box(b.min - 2.0, b.max + 2.0);
                let ray = Ray::new(o, rng.unit_vector());
                stream_rays.push(ray);
                let (e, r) = (em.intersect(&ray), brute.intersect(&ray));
                // A ray meeting the nearer answer's triangle within 1% of its
                // edge may be caught by one test and missed by the other.
                let grazes = |ray: &Ray, h: Option<Hit>| {
                    h.is_some_and(|h| crate::verify::edge_margin(&mesh, ray, h.prim).abs() < 0.01)
                };
                let agree = match (e, r) {
                    (Some(e), Some(r)) => (e.t - r.t).abs() <= 1e-4 * r.t,
                    (None, None) => true,
                    _ => false,
                };
                if !agree {
                    let near = match (e, r) {
                        (Some(e), Some(r)) => Some(if e.t < r.t { e } else { r }),
                        _ => e.or(r),
                    };
                    assert!(
                        grazes(&ray, near),
                        "{ray:?}: Embree {e:?}, brute force {r:?}"
                    );
                    grazed += 1;
                }
                let seg = Ray::segment(o, ray.dir, 0.0, 3.0);
                if em.occluded(&seg) != brute.occluded(&seg) {
                    let blocker = em.intersect(&seg).or(brute.intersect(&seg));
                    assert!(grazes(&seg, blocker), "{seg:?}");
                    grazed += 1;
                }
            }
            assert!(grazed < 40, "{grazed} of 8000 answers differ at edges");
            let mut hits = vec![None; stream_rays.len()];
            em.intersect_stream(&stream_rays, &mut hits, 64);
            for (r, h) in stream_rays.iter().zip(&hits) {
                // The stream API answers like the single-ray API (the
                // triangle may differ only on a shared edge: same distance).
                let single = em.intersect(r);
                assert_eq!(h.is_some(), single.is_some(), "{r:?}");
                if let (Some(a), Some(b)) = (h, single) {
                    assert!((a.t - b.t).abs() <= 1e-5 * b.t, "{r:?}: {a:?} vs {b:?}");
                }
            }
        }
    }
}
