//! Rendering a frame with either integrator, with traced or rasterized
//! primaries (hybrid rendering: rasterized first hits, traced rays after).

use super::options::{IntegratorKind, PrimaryMode, ShadowMode, WhittedOptions};
use super::samples::sample_position;
use super::tracer::{ShadowSource, Tracer};
use super::wavefront::wavefront_pass;
use crate::env::Environment;
use crate::image::Image;
use crate::raster;
use crate::shadowmap::ShadowMaps;
use crate::tiles::{map_pixels, Tile};
use raykit_core::glam::Vec3;
use raykit_core::tri::TestKind;
use raykit_core::{Accel, Camera, Hit, Light, Ray, TriangleMesh};
use std::time::Instant;

/// The scene a frame is rendered from.
#[derive(Clone, Copy)]
pub struct WhittedScene<'a> {
    /// Geometry with materials.
    pub mesh: &'a TriangleMesh,
    /// An accel built on `mesh`.
    pub accel: &'a dyn Accel,
    /// The ray/triangle test `accel` uses: the rasterizer computes its
    /// barycentrics with the same test, so rasterized and traced first hits
    /// agree bit for bit.
    pub test: TestKind,
    /// Lights.
    pub lights: &'a [Light],
    /// What rays leaving the scene see.
    pub environment: &'a Environment,
    /// Shadow maps of `lights`, needed when the options ask for them.
    pub shadow_maps: Option<&'a ShadowMaps>,
}

impl<'a> WhittedScene<'a> {
    /// A scene whose shadows are traced as rays (no shadow maps; see
    /// [`WhittedScene::with_shadow_maps`]).
    pub fn new(
        mesh: &'a TriangleMesh,
        accel: &'a dyn Accel,
        test: TestKind,
        lights: &'a [Light],
        environment: &'a Environment,
    ) -> Self {
        WhittedScene {
            mesh,
            accel,
            test,
            lights,
            environment,
            shadow_maps: None,
        }
    }

    /// The same scene with the shadow maps of its lights (Williams 1978),
    /// for the options that ask for them.
    pub fn with_shadow_maps(self, shadow_maps: Option<&'a ShadowMaps>) -> Self {
        WhittedScene {
            shadow_maps,
            ..self
        }
    }
}

/// Where the time of a frame went and how many rays it traced.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// Camera rays traced through the accel.
    pub primary_rays: u64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// Reflection and refraction rays traced.
    pub secondary_rays: u64,
    /// Seconds spent rasterizing visibility buffers.
    pub raster_seconds: f64,
    /// Seconds for the whole frame (rasterization included).
    pub seconds: f64,
    /// Paths that ended in the environment (the Purcell-style stream tracer's state −2).
    pub environment_hits: u64,
}

impl FrameStats {
    /// All rays traced.
    pub fn rays(&self) -> u64 {
        self.primary_rays + self.shadow_rays + self.secondary_rays
    }
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The image (linear radiance times exposure, and its encoding).
    pub image: Image,
    /// First hit of each pixel's first sample, row-major (for AOVs).
    pub first_hits: Vec<Option<Hit>>,
    /// Counts and times.
    pub stats: FrameStats,
}

/// Error of [`render_whitted`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// Shadow maps were asked for but the scene has none.
    NoShadowMaps,
    /// The frame's buffers need more memory than the process can allocate.
    OutOfMemory {
        /// Pixels rendered (the window's, when there is one).
        pixels: u64,
        /// Bytes the frame's buffers take at once, at least.
        bytes: u64,
    },
}

/// Bytes a frame holds per pixel at once, at least: the radiance sum (12),
/// the primaries' hits and the first hits kept for the AOVs (20 each). A
/// lower bound, so that no frame the machine could render is refused.
const FRAME_BYTES_PER_PIXEL: u64 = 52;

impl std::fmt::Display for FrameError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FrameError::NoShadowMaps => {
                write!(
                    f,
                    "shadow maps were asked for, but none were built for the scene"
                )
            }
            FrameError::OutOfMemory { pixels, bytes } => write!(
                f,
                "{pixels} pixels need at least {:.1} GiB while the frame renders, more than this \
                 process can allocate; render it in pieces (a window of the frame: `raykit \
                 render --tile I/N` and `raykit merge-tiles`)",
                *bytes as f64 / (1u64 << 30) as f64
            ),
        }
    }
}

impl std::error::Error for FrameError {}

/// Render `scene` through `camera` with the Whitted integrator chosen in
/// `opts`. `progress(samples, rays)` is called as pixel samples finish, with
/// their number and the total of rays traced so far in the frame
/// finish. Sample positions come from [`sample_position`], so the recursive
/// and wavefront integrators and the traced and rasterized primaries all
/// see the same camera rays; the result does not depend on the thread count.
/// With `opts.window` only that rectangle of the frame is rendered (clipped
/// to the frame), each pixel as in the whole frame.
pub fn render_whitted(
    scene: &WhittedScene,
    camera: &Camera,
    opts: &WhittedOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Frame, FrameError> {
    let start = Instant::now();
    let shadows = match opts.shadows {
        ShadowMode::Off => ShadowSource::Off,
        ShadowMode::Rays => ShadowSource::Rays,
        ShadowMode::Maps => ShadowSource::Maps(scene.shadow_maps.ok_or(FrameError::NoShadowMaps)?),
    };
    let tracer = Tracer::new(
        scene.mesh,
        scene.accel,
        scene.lights,
        scene.environment,
        shadows,
        opts.ambient,
        opts.max_depth,
    );
    let (frame_width, frame_height) = (opts.width, opts.height);
    let window = opts
        .window
        .unwrap_or(Tile::whole(frame_width, frame_height))
        .clipped(frame_width, frame_height);
    let (width, height) = (window.width, window.height);
    let n = width as usize * height as usize;
    // Asked for before any buffer is made: an allocation that fails part
    // way through aborts the process.
    let bytes = n as u64 * FRAME_BYTES_PER_PIXEL;
    if Vec::<u8>::new().try_reserve_exact(bytes as usize).is_err() {
        return Err(FrameError::OutOfMemory {
            pixels: n as u64,
            bytes,
        });
    }
    let spp = opts.samples_per_pixel.max(1);
    let rays = camera.rays(frame_width, frame_height);
    let mut sum = vec![Vec3::ZERO; n];
    let mut first_hits = Vec::new();
    let mut raster_seconds = 0.0;
    for sample in 0..spp {
        // Camera rays by frame pixel, and by window pixel for the passes.
        let frame_ray = |x: u32, y: u32| {
            let (fx, fy) = sample_position(opts.seed, frame_width, spp, x, y, sample);
            rays.ray(fx, fy)
        };
        let ray_of = |x: u32, y: u32| frame_ray(window.x + x, window.y + y);
        let primary = match opts.primary {
            // The wavefront integrator traces its primaries as one batch
            // itself; the recursive one gets them here as one batch too.
            PrimaryMode::Traced if matches!(opts.integrator, IntegratorKind::Recursive) => {
                Some(traced_primaries(&tracer, width, height, &ray_of))
            }
            PrimaryMode::Traced => None,
            PrimaryMode::Rasterized => {
                let t = Instant::now();
                // The rasterizer's setup depends on the frame, so the whole
                // visibility buffer is rasterized and the window cut out.
                let vis = raster::visibility(
                    scene.mesh,
                    scene.test,
                    camera,
                    frame_width,
                    frame_height,
                    &frame_ray,
                );
                raster_seconds += t.elapsed().as_secs_f64();
                Some(crop(&vis, frame_width, &window))
            }
        };
        let hits = match opts.integrator {
            IntegratorKind::Recursive => recursive_pass(
                &tracer,
                width,
                height,
                &ray_of,
                primary.as_deref(),
                &mut sum,
                progress,
            ),
            IntegratorKind::Wavefront => {
                let hits = wavefront_pass(&tracer, width, height, &ray_of, primary, &mut sum);
                progress(n as u64, tracer.counts.total());
                hits
            }
        };
        if sample == 0 {
            first_hits = hits;
        }
    }
    let scale = opts.exposure / spp as f32;
    let linear: Vec<Vec3> = sum.into_iter().map(|c| c * scale).collect();
    let image = Image::from_linear(width, height, linear, opts.encoding);
    let c = &tracer.counts;
    let stats = FrameStats {
        primary_rays: c.primary.get(),
        shadow_rays: c.shadow.get(),
        secondary_rays: c.secondary.get(),
        raster_seconds,
        seconds: start.elapsed().as_secs_f64(),
        environment_hits: c.environment.get(),
    };
    Ok(Frame {
        image,
        first_hits,
        stats,
    })
}

/// The values of `window` in a row-major buffer `frame_width` wide.
fn crop<T: Copy>(values: &[T], frame_width: u32, window: &Tile) -> Vec<T> {
    (window.y..window.y + window.height)
        .flat_map(|y| {
            let row = y as usize * frame_width as usize;
            values[row + window.x as usize..row + (window.x + window.width) as usize]
                .iter()
                .copied()
        })
        .collect()
}

/// The nearest hit of every pixel's camera ray (from `ray_of`), row-major,
/// through [`raykit_core::Accel::intersect_batch`] in 4 × 4 pixel blocks
/// ([`crate::primary::trace_primaries`]), so that a wide BVH over Möller
/// traces them as coherent packets (Wald et al. 2001),
/// with the single-ray answers.
fn traced_primaries(
    tracer: &Tracer,
    width: u32,
    height: u32,
    ray_of: &(dyn Fn(u32, u32) -> Ray + Sync),
) -> Vec<Option<Hit>> {
    let hits = crate::primary::trace_primaries(tracer.accel, width, height, ray_of);
    tracer.counts.primary.add(hits.len() as u64);
    hits
}

/// One sample of every pixel (rays from `ray_of`), depth-first per path,
/// tile-parallel; adds the radiance to `sum` and returns the first hits.
fn recursive_pass(
    tracer: &Tracer,
    width: u32,
    height: u32,
    ray_of: &(dyn Fn(u32, u32) -> Ray + Sync),
    primary: Option<&[Option<Hit>]>,
    sum: &mut [Vec3],
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Vec<Option<Hit>> {
    let traced = map_pixels(
        width,
        height,
        &|x, y| {
            let ray = ray_of(x, y);
            let hit = match primary {
                Some(p) => p[y as usize * width as usize + x as usize],
                None => {
                    tracer.counts.primary.add(1);
                    tracer.accel.intersect(&ray)
                }
            };
            let l = match &hit {
                Some(h) => tracer.shade_recursive(&ray, h, 1),
                None => tracer.miss(&ray),
            };
            (l, hit)
        },
        &|n| progress(n, tracer.counts.total()),
    );
    traced
        .into_iter()
        .zip(sum.iter_mut())
        .map(|((l, hit), s)| {
            *s += l;
            hit
        })
        .collect()
}
