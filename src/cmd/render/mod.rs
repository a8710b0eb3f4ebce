//! `raykit render`: a Whitted (1980) ray tracer — glTF, OBJ
//! and other scenes, point/spot/directional lights, shadow rays or shadow
//! maps, mirrors and glass, HDR environments (optionally on an
//! environment box), traced or rasterized primaries, recursive or wavefront
//! integration — written to PNG or EXR, with optional AOVs — on the CPU or,
//! with `--backend gpu`, on the GPU.

mod gpu;
mod output;
pub mod split;

use crate::cmd::trace::parse_names;
use crate::measure::{pool, timed};
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::build_accel;
use raykit_lab::args::scene as setup;
use raykit_render::aov::AovKind;
use raykit_render::shadowmap::{ShadowMapOptions, ShadowMaps};
use raykit_render::whitted::{
    render_whitted, IntegratorKind, PrimaryMode, ShadowMode, WhittedOptions, WhittedScene,
    DEFAULT_MAX_DEPTH,
};
use raykit_render::Encoding;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};

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
raykit render --scene examples/cornell-glass.gltf         # a glTF scene with its own camera and lights\n  \
raykit render --scene dragon.ply.gz --material glass --env data/envmaps/courtyard.exr --env-box\n  \
raykit render --shadows maps --pcf 5 --primary raster --integrator wavefront --out frame.exr --aov depth,normal,id\n  \
raykit render --scene bunny.obj --light dir:-1,-2,-1 --light spot:0,3,2:0,0,0:25:1,0.8,0.6\n  \
raykit render --tile 2/8 --out part2.png && raykit merge-tiles render.png part*.png   # one band per process\n  \
raykit render --orbit 120 --frames 30..60 --out anim/f.png   # frames 30 to 59 of a 120-frame orbit\n\n\
Without --eye the scene's own camera is used, or one framing the whole mesh.\n\
Without --light the scene's lights are used, or one point light above the mesh.\n\
--depth counts rays per path: 1 is direct light only, 2 adds one reflection/refraction bounce.\n\n\
--backend gpu renders the same image on the GPU (wgpu compute; Mesa's lavapipe without a GPU):\n\
--integrator recursive runs one kernel per ray path (one thread per pixel sample, --depth up to 16),\n\
--integrator wavefront a stream of kernels (after Purcell et al. 2002) over ray queues. --accel picks kd-stack,\n\
bvh-threaded (default) or brute, --test plucker or moller. --shadows maps and --primary raster\n\
are CPU-only and are refused with an error."
)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: setup::SceneArgs,
    /// Image width in pixels.
    #[arg(long, default_value_t = 800)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 600)]
    height: u32,
    /// Samples per pixel (jittered anti-aliasing).
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Longest path in rays (1 = direct light only).
    #[arg(long, default_value_t = DEFAULT_MAX_DEPTH)]
    depth: u32,
    /// Shadow test.
    #[arg(long, value_enum, default_value_t = ShadowArg::Rays)]
    shadows: ShadowArg,
    /// Disable shadows (same as --shadows off).
    #[arg(long)]
    no_shadows: bool,
    /// Shadow-map resolution in texels per side (per cube face for point lights).
    #[arg(long, default_value_t = ShadowMapOptions::default().resolution)]
    shadow_map_size: u32,
    /// Shadow-map box filter (percentage-closer filtering) width in texels; 1 = unfiltered.
    #[arg(long, default_value_t = ShadowMapOptions::default().pcf)]
    pcf: u32,
    /// Shadow-map depth bias, constant part, as a fraction of the scene diagonal
    /// (default: automatic).
    #[arg(long)]
    shadow_bias: Option<f32>,
    /// Shadow-map depth bias, slope-scaled part, in texels (default: automatic).
    #[arg(long)]
    shadow_slope_bias: Option<f32>,
    /// First-hit source.
    #[arg(long, value_enum, default_value_t = PrimaryArg::Traced)]
    primary: PrimaryArg,
    /// Ray organisation.
    #[arg(long, value_enum, default_value_t = IntegratorArg::Recursive)]
    integrator: IntegratorArg,
    /// Factor on the linear radiance before encoding.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Ambient radiance, times each surface's diffuse colour.
    #[arg(long, default_value_t = 0.06)]
    ambient: f32,
    /// Also write AOVs of the first hit: any of depth,normal,id (EXR next to
    /// the output, plus PNG previews).
    #[arg(long, value_delimiter = ',')]
    aov: Vec<String>,
    /// Acceleration structure (`raykit info accels`; default bvh8, the
    /// fastest, or bvh-threaded with --backend gpu, which takes kd-stack,
    /// bvh-threaded or brute). The summary line names the one used.
    #[arg(long)]
    accel: Option<String>,
    /// Render on the CPU or the GPU (same image; see below).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
    /// Ray/triangle test (`raykit info tests`).
    #[arg(long, default_value = "moller")]
    test: String,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Output image: `.png` (8-bit sRGB) or `.exr` (linear float). With
    /// --orbit each frame goes to OUT's name with the frame number before
    /// the extension (render.0007.png).
    #[arg(long, default_value = "render.png")]
    out: PathBuf,
    /// Render only horizontal band I of N (I from 0; rows I·H/N up to
    /// (I+1)·H/N) as a PNG part that `raykit merge-tiles` assembles into the
    /// image a one-process render gives, bit for bit.
    #[arg(long, value_name = "I/N", value_parser = split::parse_tile)]
    tile: Option<split::TileArg>,
    /// Camera path: FRAMES frames orbiting the camera target about the up
    /// axis (a full turn; frame 0 is the camera itself).
    #[arg(long, value_name = "FRAMES")]
    orbit: Option<u32>,
    /// Render only frames A..B (B excluded; A..=B includes it) of --orbit.
    #[arg(long, value_name = "A..B", value_parser = split::parse_frames)]
    frames: Option<split::FrameRange>,
    #[command(flatten)]
    build: crate::build_args::BuildArgs,
}

/// Render and write the image.
pub fn run(args: RenderArgs) -> Result<ExitCode> {
    if args.width == 0 || args.height == 0 || args.width > 16384 || args.height > 16384 {
        bail!("--width and --height must be between 1 and 16384");
    }
    if args.spp == 0 || args.spp > 4096 {
        bail!("--spp must be between 1 and 4096");
    }
    if args.depth == 0 || args.depth > 64 {
        bail!("--depth must be between 1 and 64");
    }
    let non_negative = |x: f32| x.is_finite() && x >= 0.0;
    if !non_negative(args.exposure) || !non_negative(args.ambient) {
        bail!("--exposure and --ambient must be finite and ≥ 0");
    }
    let aovs: Vec<AovKind> = args
        .aov
        .iter()
        .map(|a| {
            AovKind::parse(a)
                .ok_or_else(|| anyhow::anyhow!("unknown --aov '{a}': expected depth, normal or id"))
        })
        .collect::<Result<_>>()?;
    let format = output::Format::of(&args.out)?;
    let backend = args.backend;
    let cpu_accel = match backend {
        BackendArg::Cpu => args
            .accel
            .as_deref()
            .unwrap_or(crate::build_args::DEFAULT_ACCEL),
        BackendArg::Gpu => crate::build_args::DEFAULT_ACCEL,
    };
    let (kind, test) = parse_names(cpu_accel, &args.test)?;
    let gpu_kind = match backend {
        BackendArg::Gpu => Some(gpu::gpu_accel(args.accel.as_deref())?),
        BackendArg::Cpu => None,
    };
    let window = match args.tile {
        Some(t) => {
            if format != output::Format::Png {
                bail!("--tile writes PNG parts (with their place in the image) for `raykit merge-tiles`: --out must end in .png");
            }
            if !aovs.is_empty() || backend == BackendArg::Gpu {
                bail!("--tile renders on the CPU without --aov");
            }
            Some(t.window(args.width, args.height)?)
        }
        None => None,
    };
    let shadows: ShadowMode = if args.no_shadows {
        ShadowMode::Off
    } else {
        args.shadows.into()
    };
    let opts = WhittedOptions {
        width: args.width,
        height: args.height,
        samples_per_pixel: args.spp,
        max_depth: args.depth,
        ambient: raykit_core::Vec3::splat(args.ambient),
        shadows,
        primary: args.primary.into(),
        integrator: args.integrator.into(),
        exposure: args.exposure,
        encoding: Encoding::Srgb,
        window,
        ..WhittedOptions::default()
    };
    if gpu_kind.is_some() {
        gpu::check_args(&opts, test)?;
    }
    let pool = pool(args.threads)?;
    let aspect = args.width as f32 / args.height as f32;
    let (setup, load_s) = timed(|| setup::setup(&args.scene, aspect));
    let mut setup = setup?;
    let frames = split::frames(&setup.camera, &args.out, args.orbit, args.frames)?;
    for (_, _, out) in &frames {
        crate::paths::ensure_not_input(out, &[std::path::Path::new(&args.scene.scene)])?;
    }
    let window = window.unwrap_or(raykit_render::Tile::whole(args.width, args.height));
    let samples = window.pixels() * args.spp as u64 * frames.len() as u64;
    let bar = ProgressBar::new(samples).with_style(
        ProgressStyle::with_template("{bar:30} {percent:>3}% {msg} [{elapsed}<{eta}]")
            .expect("valid template"),
    );
    let done = AtomicU64::new(0);
    let start = std::time::Instant::now();
    let progress = |n: u64, rays: u64| {
        let d = done.fetch_add(n, Ordering::Relaxed) + n;
        bar.set_position(d);
        let secs = start.elapsed().as_secs_f64().max(1e-9);
        bar.set_message(format!("{:.2} Mrays/s", rays as f64 / secs / 1e6));
    };
    let mut maps_note = String::new();
    let mut rendered = Vec::with_capacity(frames.len());
    let (build_s, structure) = match gpu_kind {
        Some(gkind) => {
            let mut build_s = 0.0;
            let mut describe = String::new();
            for (number, camera, out) in &frames {
                setup.camera = *camera;
                let g = pool.install(|| {
                    gpu::render(
                        gkind,
                        test,
                        &setup.scene.mesh,
                        &setup,
                        &opts,
                        &args.build.options(),
                        &progress,
                    )
                })?;
                build_s += g.build_seconds;
                describe = g.describe;
                rendered.push((*number, *camera, out.clone(), g.frame));
            }
            (build_s, describe)
        }
        None => {
            let mesh = &setup.scene.mesh;
            let (accel, build_s) =
                pool.install(|| timed(|| build_accel(kind, test, mesh, &args.build.options())));
            let maps = if shadows == ShadowMode::Maps {
                let mut o = ShadowMapOptions::for_mesh(mesh);
                o.resolution = args.shadow_map_size.clamp(16, 16384);
                o.pcf = args.pcf.clamp(1, 15);
                let diag = mesh.bounds().diagonal();
                if let Some(b) = args.shadow_bias {
                    o.bias_constant = b * diag;
                }
                if let Some(b) = args.shadow_slope_bias {
                    o.bias_slope = b;
                }
                let (m, s) = pool.install(|| timed(|| ShadowMaps::build(mesh, &setup.lights, &o)));
                maps_note = format!(", shadow maps {:.0} ms", s * 1e3);
                Some(m)
            } else {
                None
            };
            let scene = WhittedScene {
                mesh,
                accel: accel.as_ref(),
                test,
                lights: &setup.lights,
                environment: &setup.environment,
                shadow_maps: maps.as_ref(),
            };
            for (number, camera, out) in &frames {
                let frame = pool.install(|| render_whitted(&scene, camera, &opts, &progress))?;
                rendered.push((*number, *camera, out.clone(), frame));
            }
            let build = crate::build_args::quality_name(args.build.options().quality);
            (
                build_s,
                format!("{} ({build} build), {}", kind.name(), test.name()),
            )
        }
    };
    bar.finish_and_clear();
    let mesh = &setup.scene.mesh;
    for (number, camera, out, frame) in &rendered {
        match args.tile {
            Some(_) => {
                let part = raykit_io::ImagePart {
                    x: window.x,
                    y: window.y,
                    width: window.width,
                    height: window.height,
                    full_width: args.width,
                    full_height: args.height,
                };
                raykit_io::write_png_part(out, &part, &frame.image.rgb)?;
            }
            None => output::write_image(out, format, &frame.image)?,
        }
        for kind in &aovs {
            output::write_aov(out, *kind, mesh, camera, frame)?;
        }
        let st = &frame.stats;
        let what = match (number, args.tile) {
            (Some(k), Some(t)) => format!("frame {k}, band {}/{} ", t.index, t.count),
            (Some(k), None) => format!("frame {k} "),
            (None, Some(t)) => format!("band {}/{} ", t.index, t.count),
            (None, None) => String::new(),
        };
        eprintln!(
            "{}: {} triangles, {} lights, env {}; load {:.0} ms, build {:.0} ms ({}){}, render {}{:.0} ms \
             ({}×{}, {} spp, depth {}, {:?} shadows, {:?} primaries, {:?}; {:.2} Mrays: {} primary, {} shadow, {} secondary; {:.2} Mrays/s) -> {}",
            setup.scene.name,
            mesh.num_triangles(),
            setup.lights.len(),
            setup.environment.describe(),
            load_s * 1e3,
            build_s * 1e3,
            structure,
            maps_note,
            what,
            st.seconds * 1e3,
            args.width,
            args.height,
            args.spp,
            args.depth,
            shadows,
            opts.primary,
            opts.integrator,
            st.rays() as f64 / 1e6,
            st.primary_rays,
            st.shadow_rays,
            st.secondary_rays,
            st.rays() as f64 / st.seconds.max(1e-9) / 1e6,
            out.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}
