//! The arguments of `raykit render`.

use clap::{Args, ValueEnum};
use raykit_lab::args::build_args::number_in;
use raykit_render::shadowmap::ShadowMapOptions;
use raykit_render::whitted::{IntegratorKind, PrimaryMode, ShadowMode, DEFAULT_MAX_DEPTH};
use std::path::PathBuf;

fn fraction(text: &str) -> Result<f32, String> {
    number_in(text, 0.0, 1.0)
}

fn texels(text: &str) -> Result<f32, String> {
    number_in(text, 0.0, 1e3)
}

fn radiance(text: &str) -> Result<f32, String> {
    number_in(text, 0.0, 1e6)
}

/// Shadow test on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ShadowArg {
    /// Shadow rays: one occlusion query per light and hit.
    Rays,
    /// Shadow maps rendered from each light, box-filtered (Williams 1978).
    Maps,
    /// No shadows.
    Off,
}

/// First-hit source on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PrimaryArg {
    /// Trace camera rays.
    Traced,
    /// Rasterize a visibility buffer (hybrid rendering: rasterized first hits, traced rays after).
    Raster,
}

/// Ray organisation on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum IntegratorArg {
    /// Depth-first recursion per camera sample.
    Recursive,
    /// Stream organisation after Purcell et al. (2002): stages over ray queues.
    Wavefront,
}

/// Where the frame is rendered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    /// The CPU renderer (every feature), tile-parallel on the worker threads.
    Cpu,
    /// WGSL compute kernels through wgpu (any Vulkan, Metal or DX12 GPU, or
    /// Mesa's lavapipe): one kernel per ray path for --integrator
    /// recursive, a stream of kernels (after Purcell et al. 2002) for --integrator wavefront.
    Gpu,
}

impl From<ShadowArg> for ShadowMode {
    fn from(a: ShadowArg) -> ShadowMode {
        match a {
            ShadowArg::Rays => ShadowMode::Rays,
            ShadowArg::Maps => ShadowMode::Maps,
            ShadowArg::Off => ShadowMode::Off,
        }
    }
}

impl From<PrimaryArg> for PrimaryMode {
    fn from(a: PrimaryArg) -> PrimaryMode {
        match a {
            PrimaryArg::Traced => PrimaryMode::Traced,
            PrimaryArg::Raster => PrimaryMode::Rasterized,
        }
    }
}

impl From<IntegratorArg> for IntegratorKind {
    fn from(a: IntegratorArg) -> IntegratorKind {
        match a {
            IntegratorArg::Recursive => IntegratorKind::Recursive,
            IntegratorArg::Wavefront => IntegratorKind::Wavefront,
        }
    }
}

/// Arguments of `raykit render`.
#[derive(Args)]
#[command(
    after_help = "Examples:\n  raykit render                                   # builtin:whitted (mirror + glass Cornell box) to render.png\n  \
raykit render --scene examples/whitted-cornell.gltf       # a glTF scene with its own camera and lights\n  \
raykit render --scene dragon.ply.gz --material glass --env data/envmaps/courtyard.exr --env-box\n  \
raykit render --shadows maps --pcf 5 --primary raster --integrator wavefront --out frame.exr --aov depth,normal,id\n  \
raykit render --scene bunny.obj --light dir:-1,-2,-1 --light spot:0,3,2:0,0,0:25:1,0.8,0.6\n  \
for i in 0 1 2 3; do raykit render --tile $i/4 --out part$i.png; done; raykit merge-tiles render.png part*.png   # one band per process\n  \
mkdir -p anim; raykit render --orbit 120 --frames 30..60 --out anim/f.png   # frames 30 to 59 of a 120-frame orbit\n\n\
Without --eye the scene's own camera is used, or one framing the whole mesh.\n\
Without --light the scene's lights are used, or one point light above the mesh.\n\
--depth counts rays per path: 1 is direct light only, 2 adds one reflection/refraction bounce.\n\n\
--backend gpu renders the same image on the GPU (wgpu compute; Mesa's lavapipe without a GPU):\n\
--integrator recursive runs one kernel per ray path (one thread per pixel sample, --depth up to 16),\n\
--integrator wavefront a stream of kernels (after Purcell et al. 2002) over ray queues. --accel picks kd-stack,\n\
kd-ropes, bvh-threaded (default), cwbvh or brute, --test plucker or moller. --shadows maps and --primary raster\n\
are CPU-only and are refused with an error."
)]
pub struct RenderArgs {
    #[command(flatten)]
    pub(super) scene: super::setup::SceneArgs,
    /// Image width in pixels [default: 800, or 4/3 of --height when only
    /// that is given].
    #[arg(long)]
    pub(super) width: Option<u32>,
    /// Image height in pixels [default: 600, or 3/4 of --width when only
    /// that is given].
    #[arg(long)]
    pub(super) height: Option<u32>,
    /// Samples per pixel (jittered anti-aliasing).
    #[arg(long, default_value_t = 1)]
    pub(super) spp: u32,
    /// Longest path in rays (1 = direct light only).
    #[arg(long, default_value_t = DEFAULT_MAX_DEPTH)]
    pub(super) depth: u32,
    /// Shadow test.
    #[arg(long, value_enum, default_value_t = ShadowArg::Rays)]
    pub(super) shadows: ShadowArg,
    /// Disable shadows (same as --shadows off).
    #[arg(long)]
    pub(super) no_shadows: bool,
    /// Shadow-map resolution in texels per side (per cube face for point
    /// lights), 16-4096 (a point light's cube map holds 6 × 4096² depths at
    /// the most, 400 MB).
    #[arg(long, default_value_t = ShadowMapOptions::default().resolution, value_parser = clap::value_parser!(u32).range(16..=4096))]
    pub(super) shadow_map_size: u32,
    /// Shadow-map box filter (percentage-closer filtering) width in texels,
    /// 1-15; 1 = unfiltered.
    #[arg(long, default_value_t = ShadowMapOptions::default().pcf, value_parser = clap::value_parser!(u32).range(1..=15))]
    pub(super) pcf: u32,
    /// Shadow-map depth bias, constant part, as a fraction of the scene diagonal,
    /// 0-1 (default: automatic).
    #[arg(long, value_parser = fraction)]
    pub(super) shadow_bias: Option<f32>,
    /// Shadow-map depth bias, slope-scaled part, in texels, 0-1000 (default:
    /// automatic).
    #[arg(long, value_parser = texels)]
    pub(super) shadow_slope_bias: Option<f32>,
    /// First-hit source.
    #[arg(long, value_enum, default_value_t = PrimaryArg::Traced)]
    pub(super) primary: PrimaryArg,
    /// Ray organisation.
    #[arg(long, value_enum, default_value_t = IntegratorArg::Recursive)]
    pub(super) integrator: IntegratorArg,
    /// Factor on the linear radiance before encoding.
    #[arg(long, default_value_t = 1.0, value_parser = radiance)]
    pub(super) exposure: f32,
    /// Ambient radiance, times each surface's diffuse colour.
    #[arg(long, default_value_t = 0.06, value_parser = radiance)]
    pub(super) ambient: f32,
    /// Also write AOVs of the first hit: any of depth,normal,id (EXR next to
    /// the output, plus PNG previews; the id is an f32 channel, exact for
    /// the first 2^24 triangles, -1 where the ray missed).
    #[arg(long, value_delimiter = ',')]
    pub(super) aov: Vec<String>,
    /// Acceleration structure (`raykit info accels`; default bvh8, the
    /// fastest, or bvh-threaded with --backend gpu, which takes kd-stack,
    /// kd-ropes, bvh-threaded, cwbvh (the compressed bvh8) or brute). The
    /// summary line names the one used.
    #[arg(long)]
    pub(super) accel: Option<String>,
    /// Render on the CPU or the GPU (same image; see below).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub(super) backend: BackendArg,
    /// Ray/triangle test (`raykit info tests`).
    #[arg(long, default_value = "moller")]
    pub(super) test: String,
    /// Worker threads (0 = one per core; at most 4096).
    #[arg(long, default_value_t = 0)]
    pub(super) threads: usize,
    /// Output image: `.png` (8-bit sRGB) or `.exr` (linear float). With
    /// --orbit each frame goes to OUT's name with the frame number before
    /// the extension (render.0007.png).
    #[arg(long, default_value = "render.png")]
    pub(super) out: PathBuf,
    /// Render only horizontal band I of N (I from 0; rows I·H/N up to
    /// (I+1)·H/N) as a PNG part that `raykit merge-tiles` assembles into the
    /// image a one-process render gives, bit for bit. CPU backend only,
    /// without --aov.
    #[arg(long, value_name = "I/N", value_parser = super::split::parse_tile)]
    pub(super) tile: Option<super::split::TileArg>,
    /// Camera path: FRAMES frames orbiting the camera target about the up
    /// axis (a full turn; frame 0 is the camera itself).
    #[arg(long, value_name = "FRAMES", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub(super) orbit: Option<u32>,
    /// Render only frames A..B (B excluded; A..=B includes it) of --orbit.
    #[arg(long, value_name = "A..B", value_parser = super::split::parse_frames)]
    pub(super) frames: Option<super::split::FrameRange>,
    #[command(flatten)]
    pub(super) build: raykit_lab::args::build_args::BuildArgs,
}

impl RenderArgs {
    /// The image's width and height: as given, 800 × 600 when neither is,
    /// and the other side at 4:3 when one is.
    pub(super) fn size(&self) -> (u32, u32) {
        let scale =
            |side: u32, by: u64, over: u64| ((side as u64 * by + over / 2) / over).max(1) as u32;
        match (self.width, self.height) {
            (Some(w), Some(h)) => (w, h),
            (Some(w), None) => (w, scale(w, 3, 4)),
            (None, Some(h)) => (scale(h, 4, 3), h),
            (None, None) => (800, 600),
        }
    }
}
