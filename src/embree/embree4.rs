//! Embree 4 as a second comparison backend: the library is found and
//! loaded at run time (see [`Embree4::load`]), so a raykit built anywhere
//! can compare against whichever `libembree4.so.4` the machine has, e.g.
//! the one in the PyPI wheel `embreex`. Builds a scene like the Embree 3
//! backend and answers rays through every query API Embree 4 offers on the
//! CPU: single rays (`rtcIntersect1` / `rtcOccluded1`) and packets of 4, 8
//! and 16 (`rtcIntersectN` / `rtcOccludedN`).

use super::ffi4 as ffi;
use super::Quality;
use anyhow::{anyhow, bail, Context, Result};
use raykit_core::accel::AccelStats;
use raykit_core::{Aabb, Accel, Hit, Ray, TriangleMesh};
use rayon::prelude::*;
use std::ffi::CString;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Environment variable naming the Embree 4 library file.
pub const LIBRARY_ENV: &str = "RAYKIT_EMBREE4";

/// Rays handed to one rayon task by the packet traces (a multiple of 16).
const TASK_RAYS: usize = 1024;

/// A query API of Embree 4: single rays or packets of 4, 8 or 16.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Api {
    /// `rtcIntersect1` / `rtcOccluded1`, one call per ray.
    Single,
    /// `rtcIntersect4` / `rtcOccluded4`.
    Packet4,
    /// `rtcIntersect8` / `rtcOccluded8`.
    Packet8,
    /// `rtcIntersect16` / `rtcOccluded16`.
    Packet16,
}

impl Api {
    /// Every API, single rays first.
    pub const ALL: [Api; 4] = [Api::Single, Api::Packet4, Api::Packet8, Api::Packet16];

    /// The suffix of the Embree call: `1`, `4`, `8` or `16`.
    pub fn width(self) -> usize {
        match self {
            Api::Single => 1,
            Api::Packet4 => 4,
            Api::Packet8 => 8,
            Api::Packet16 => 16,
        }
    }
}

/// A loaded Embree 4 library and its function table.
pub struct Embree4 {
    api: ffi::Api,
    /// The file loaded, for reports.
    pub path: PathBuf,
    /// The library's version, e.g. `4.4.0`.
    pub version: String,
    /// Kept loaded as long as `api` is used.
    _lib: libloading::Library,
}

impl Embree4 {
    /// Find and load Embree 4: the file `$RAYKIT_EMBREE4` names, else the
    /// `libembree4*.so*` of the `embreex` wheel that `python3` (the one
    /// `$RAYKIT_PYTHON` names, else `python3` on the PATH) imports. The
    /// error names every place tried.
    pub fn load() -> Result<Arc<Embree4>> {
        let path = find_library()?;
        // SAFETY: loading runs the library's initialisers; Embree's and
        // TBB's have no preconditions.
        let lib = unsafe { libloading::Library::new(&path) }
            .with_context(|| format!("loading Embree 4 from {}", path.display()))?;
        // SAFETY: the file is an Embree 4 library (its name, and the
        // version check below); `lib` lives as long as the table.
        let api = unsafe { ffi::Api::load(&lib) }
            .with_context(|| format!("{}: not an Embree 4 library", path.display()))?;
        // SAFETY: an empty configuration string; the device is released
        // right after reading its version.
        let version = unsafe {
            let dev = (api.rtcNewDevice)(c"".as_ptr());
            if dev.is_null() {
                bail!("{}: Embree could not create a device", path.display());
            }
            let v = (api.rtcGetDeviceProperty)(dev, ffi::RTC_DEVICE_PROPERTY_VERSION);
            (api.rtcReleaseDevice)(dev);
            v
        };
        if !(40000..50000).contains(&version) {
            bail!(
                "{}: reports Embree version {version}, expected 4.x",
                path.display()
            );
        }
        Ok(Arc::new(Embree4 {
            api,
            path,
            version: format!(
                "{}.{}.{}",
                version / 10000,
                version / 100 % 100,
                version % 100
            ),
            _lib: lib,
        }))
    }
}

/// Where [`Embree4::load`] looks, in order.
fn find_library() -> Result<PathBuf> {
    let mut tried = Vec::new();
    if let Some(p) = std::env::var_os(LIBRARY_ENV) {
        let p = PathBuf::from(p);
        if p.is_file() {
            return Ok(p);
        }
        tried.push(format!("${LIBRARY_ENV} = {} (no such file)", p.display()));
    } else {
        tried.push(format!("${LIBRARY_ENV} (not set)"));
    }
    let python = std::env::var("RAYKIT_PYTHON").unwrap_or_else(|_| "python3".to_string());
    let probe = "import embreex, os; print(os.path.join(os.path.dirname(os.path.dirname(embreex.__file__)), 'embreex.libs'))";
    match std::process::Command::new(&python)
        .args(["-c", probe])
        .output()
    {
        Ok(o) if o.status.success() => {
            let dir = PathBuf::from(String::from_utf8_lossy(&o.stdout).trim());
            match library_in(&dir) {
                Some(p) => return Ok(p),
                None => tried.push(format!(
                    "{python}'s embreex wheel: no libembree4*.so* in {}",
                    dir.display()
                )),
            }
        }
        Ok(o) => tried.push(format!(
            "{python} -c 'import embreex': {}",
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .last()
                .unwrap_or("failed")
        )),
        Err(e) => tried.push(format!("{python}: {e}")),
    }
    Err(anyhow!(
        "Embree 4 not found; tried {}. Install it with `pip install embreex` (its wheel carries libembree4) or set {LIBRARY_ENV} to a libembree4.so.4",
        tried.join("; ")
    ))
}

/// The first `libembree4*.so*` file in `dir`.
fn library_in(dir: &Path) -> Option<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("libembree4") && n.contains(".so"))
        })
        .collect();
    found.sort();
    found.into_iter().next()
}

/// An Embree 4 device: its thread pool and allocator.
pub struct Embree4Device {
    lib: Arc<Embree4>,
    raw: ffi::RTCDevice,
}

// SAFETY: an Embree device may be used from any thread.
unsafe impl Send for Embree4Device {}
// SAFETY: as above.
unsafe impl Sync for Embree4Device {}

impl Embree4Device {
    /// A device with `threads` build threads (0: all cores). The variable
    /// RAYKIT_EMBREE_CONFIG adds to the configuration string, as for
    /// Embree 3.
    pub fn new(lib: &Arc<Embree4>, threads: usize) -> Result<Arc<Embree4Device>> {
        let config = CString::new(super::device_config(threads))?;
        // SAFETY: a valid NUL-terminated configuration string.
        let raw = unsafe { (lib.api.rtcNewDevice)(config.as_ptr()) };
        if raw.is_null() {
            bail!("Embree 4 could not create a device");
        }
        Ok(Arc::new(Embree4Device {
            lib: Arc::clone(lib),
            raw,
        }))
    }
}

impl Drop for Embree4Device {
    fn drop(&mut self) {
        // SAFETY: created by `new`, released once.
        unsafe { (self.lib.api.rtcReleaseDevice)(self.raw) };
    }
}

/// A committed Embree 4 scene holding one triangle mesh.
pub struct Embree4Scene {
    device: Arc<Embree4Device>,
    scene: ffi::RTCScene,
    bounds: Aabb,
    triangles: usize,
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
        let api = &device.lib.api;
        let q = match quality {
            Quality::Medium => ffi::RTC_BUILD_QUALITY_MEDIUM,
            Quality::High => ffi::RTC_BUILD_QUALITY_HIGH,
        };
        // SAFETY: plain FFI calls with valid arguments; every buffer Embree
        // returns is written within the size we asked for.
        unsafe {
            let scene = (api.rtcNewScene)(device.raw);
            (api.rtcSetSceneBuildQuality)(scene, q);
            let geom = (api.rtcNewGeometry)(device.raw, ffi::RTC_GEOMETRY_TYPE_TRIANGLE);
            (api.rtcSetGeometryBuildQuality)(geom, q);
            let nv = mesh.positions.len();
            let vb = (api.rtcSetNewGeometryBuffer)(
                geom,
                ffi::RTC_BUFFER_TYPE_VERTEX,
                0,
                ffi::RTC_FORMAT_FLOAT3,
                12,
                nv,
            ) as *mut f32;
            let ib = (api.rtcSetNewGeometryBuffer)(
                geom,
                ffi::RTC_BUFFER_TYPE_INDEX,
                0,
                ffi::RTC_FORMAT_UINT3,
                12,
                mesh.indices.len(),
            ) as *mut u32;
            if vb.is_null() || ib.is_null() {
                (api.rtcReleaseGeometry)(geom);
                (api.rtcReleaseScene)(scene);
                bail!("Embree 4 could not allocate the mesh buffers");
            }
            let verts = std::slice::from_raw_parts_mut(vb, nv * 3);
            for (dst, p) in verts.chunks_exact_mut(3).zip(&mesh.positions) {
                dst.copy_from_slice(&p.to_array());
            }
            let idx = std::slice::from_raw_parts_mut(ib, mesh.indices.len() * 3);
            for (dst, t) in idx.chunks_exact_mut(3).zip(&mesh.indices) {
                dst.copy_from_slice(t);
            }
            (api.rtcCommitGeometry)(geom);
            (api.rtcAttachGeometry)(scene, geom);
            (api.rtcReleaseGeometry)(geom);
            (api.rtcCommitScene)(scene);
            let err = (api.rtcGetDeviceError)(device.raw);
            if err != ffi::RTC_ERROR_NONE {
                (api.rtcReleaseScene)(scene);
                bail!("Embree 4 reported error {err} while building the scene");
            }
            Ok(Embree4Scene {
                device: Arc::clone(device),
                scene,
                bounds: mesh.bounds(),
                triangles: mesh.num_triangles(),
            })
        }
    }

    fn api(&self) -> &ffi::Api {
        &self.device.lib.api
    }

    /// Nearest hits of `rays` through `api`, in parallel over the rayon
    /// pool; `coherent` is the hint passed in the query arguments.
    pub fn intersect_with(&self, api: Api, rays: &[Ray], hits: &mut [Option<Hit>], coherent: bool) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        let flags = query_flags(coherent);
        rays.par_chunks(TASK_RAYS)
            .zip(hits.par_chunks_mut(TASK_RAYS))
            .for_each(|(r, h)| match api {
                Api::Single => {
                    for (ray, hit) in r.iter().zip(h) {
                        *hit = self.intersect1(ray, flags);
                    }
                }
                Api::Packet4 => self.intersect_packets::<4>(r, h, flags),
                Api::Packet8 => self.intersect_packets::<8>(r, h, flags),
                Api::Packet16 => self.intersect_packets::<16>(r, h, flags),
            });
    }

    /// Occlusion of `rays` through `api`, in parallel over the rayon pool.
    pub fn occluded_with(&self, api: Api, rays: &[Ray], occluded: &mut [bool], coherent: bool) {
        assert_eq!(rays.len(), occluded.len(), "one result per ray");
        let flags = query_flags(coherent);
        rays.par_chunks(TASK_RAYS)
            .zip(occluded.par_chunks_mut(TASK_RAYS))
            .for_each(|(r, o)| match api {
                Api::Single => {
                    for (ray, o) in r.iter().zip(o) {
                        *o = self.occluded1(ray, flags);
                    }
                }
                Api::Packet4 => self.occluded_packets::<4>(r, o, flags),
                Api::Packet8 => self.occluded_packets::<8>(r, o, flags),
                Api::Packet16 => self.occluded_packets::<16>(r, o, flags),
            });
    }

    fn intersect1(&self, ray: &Ray, flags: u32) -> Option<Hit> {
        let mut rh = ffi::RTCRayHit {
            ray: ray_of(ray),
            hit: ffi::RTCHit {
                geom_id: ffi::RTC_INVALID_GEOMETRY_ID,
                ..Default::default()
            },
        };
        let mut args = ffi::RTCQueryArguments::new(flags);
        // SAFETY: valid scene, ray/hit record and arguments.
        unsafe { (self.api().rtcIntersect1)(self.scene, &mut rh, &mut args) };
        (rh.hit.geom_id != ffi::RTC_INVALID_GEOMETRY_ID).then_some(Hit {
            t: rh.ray.tfar,
            u: rh.hit.u,
            v: rh.hit.v,
            prim: rh.hit.prim_id,
        })
    }

    fn occluded1(&self, ray: &Ray, flags: u32) -> bool {
        let mut r = ray_of(ray);
        let mut args = ffi::RTCQueryArguments::new(flags);
        // SAFETY: valid scene, ray record and arguments.
        unsafe { (self.api().rtcOccluded1)(self.scene, &mut r, &mut args) };
        // Embree marks an occluded ray by setting tfar to −inf.
        r.tfar == f32::NEG_INFINITY
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
                *h = (p.geom_id[i] != ffi::RTC_INVALID_GEOMETRY_ID).then_some(Hit {
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
pub trait PacketCalls<const N: usize> {
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
        [p.dir_x[i], p.dir_y[i], p.dir_z[i]] = r.dir.to_array();
        p.tnear[i] = r.tnear;
        p.tfar[i] = r.tfar;
    }
    (valid, p)
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

impl Drop for Embree4Scene {
    fn drop(&mut self) {
        // SAFETY: the scene came from `build` and is released once, before
        // the device (which `self.device` keeps alive until after this).
        unsafe { (self.api().rtcReleaseScene)(self.scene) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
    use raykit_core::rng::Pcg32;
    use raykit_core::tri::TestKind;

    /// Embree 4 through each API against brute force on the Stanford bunny
    /// (a real scanned mesh), random rays through its box: same hit or miss
    /// and distance, except rays grazing an edge (the nearer triangle met
    /// within 1% of its edge, f64). Needs the library (scripts/test
    /// installs `embreex`); fails, naming what it tried, where it is
    /// missing.
    #[test]
    fn embree4_agrees_with_brute_force_through_every_api() {
        let lib = Embree4::load().unwrap_or_else(|e| panic!("{e:#}"));
        let bunny = concat!(env!("CARGO_MANIFEST_DIR"), "/data/meshes/bunny_3674.obj");
        let mesh = crate::scene_arg::load(bunny).unwrap().mesh;
        let brute = build_accel(
            AccelKind::Brute,
            TestKind::Moller,
            &mesh,
            &BuildOptions::default(),
        );
        let em = Embree4Scene::build(&Embree4Device::new(&lib, 1).unwrap(), &mesh, Quality::High)
            .unwrap();
        let mut rng = Pcg32::new(11);
        let b = mesh.bounds();
        let pad = (b.max - b.min) * 0.5;
        let rays: Vec<Ray> = (0..3001)
            .map(|_| {
                let o = rng.in_box(b.min - pad, b.max + pad);
                let target = rng.in_box(b.min, b.max);
                Ray::segment(
                    o,
                    (target - o).normalize(),
                    0.0,
                    (target - o).length() * 1.5,
                )
            })
            .collect();
        let mut want = vec![None; rays.len()];
        brute.intersect_batch(&rays, &mut want);
        let mut want_occ = vec![false; rays.len()];
        brute.occluded_batch(&rays, &mut want_occ);
        let hits_somewhere = want.iter().filter(|h| h.is_some()).count();
        assert!(hits_somewhere > rays.len() / 4, "{hits_somewhere} hits");
        for api in Api::ALL {
            let mut got = vec![None; rays.len()];
            em.intersect_with(api, &rays, &mut got, false);
            let mut v = crate::verify::compare_hits(&want, &got);
            v.edge_grazes = crate::verify::edge_grazes(&mesh, &rays, &want, &got);
            assert!(v.ok(), "{api:?} intersect: {v:?}");
            assert!(v.hit_miss + v.distance < 30, "{api:?}: {v:?}");
            let mut occ = vec![false; rays.len()];
            em.occluded_with(api, &rays, &mut occ, true);
            let mut v = crate::verify::compare_occlusion(&want_occ, &occ);
            (v.edge_grazes, _) =
                crate::verify::occlusion_grazes(&mesh, &rays, &want_occ, &occ, |r| {
                    let (mut a, mut b) = (vec![None; r.len()], vec![None; r.len()]);
                    brute.intersect_batch(r, &mut a);
                    em.intersect_with(api, r, &mut b, false);
                    (a, b)
                });
            assert!(v.ok(), "{api:?} occluded: {v:?}");
        }
    }
}
