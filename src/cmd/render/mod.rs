//! `raykit render`: a Whitted (1980) ray tracer — glTF, OBJ
//! and other scenes, point/spot/directional lights, shadow rays or shadow
//! maps, mirrors and glass, HDR environments (optionally on an
//! environment box), traced or rasterized primaries, recursive or wavefront
//! integration — written to PNG or EXR, with optional AOVs — on the CPU or,
//! with `--backend gpu`, on the GPU.

mod args;
mod gpu;
mod picture;
pub mod split;

use args::BackendArg;
pub use args::RenderArgs;

use crate::cmd::trace::parse_names;
use anyhow::{bail, Result};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::build_accel;
use raykit_lab::args::scene as setup;
use raykit_lab::measure::{pool, timed};
use raykit_render::animation::{animation_frames, AnimationFrame};
use raykit_render::aov::AovKind;
use raykit_render::output::{aov_paths, write_aov, write_image, ImageFormat};
use raykit_render::shadowmap::{ShadowMapOptions, ShadowMaps};
use raykit_render::whitted::{render_whitted, ShadowMode, WhittedOptions, WhittedScene};
use raykit_render::Encoding;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};

/// Render and write the image.
pub fn run(args: RenderArgs) -> Result<ExitCode> {
    let max = raykit_io::MAX_IMAGE_SIDE;
    let (width, height) = args.size();
    if width == 0 || height == 0 || width > max || height > max {
        bail!("--width and --height must be between 1 and {max}");
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
    let format = ImageFormat::of(&args.out).map_err(anyhow::Error::msg)?;
    let backend = args.backend;
    let cpu_accel = match backend {
        BackendArg::Cpu => args
            .accel
            .as_deref()
            .unwrap_or(raykit_lab::args::build_args::DEFAULT_ACCEL),
        BackendArg::Gpu => raykit_lab::args::build_args::DEFAULT_ACCEL,
    };
    let (kind, test) = parse_names(cpu_accel, &args.test)?;
    let gpu_kind = match backend {
        BackendArg::Gpu => Some(gpu::gpu_accel(args.accel.as_deref())?),
        BackendArg::Cpu => None,
    };
    let window = match args.tile {
        Some(t) => {
            if format != ImageFormat::Png {
                bail!("--tile writes PNG parts (with their place in the image) for `raykit merge-tiles`: --out must end in .png");
            }
            if backend == BackendArg::Gpu {
                bail!("--tile renders on the CPU only: leave out --backend gpu");
            }
            if !aovs.is_empty() {
                bail!("--tile writes PNG parts of the image only: leave out --aov");
            }
            Some(t.window(width, height)?)
        }
        None => None,
    };
    let shadows: ShadowMode = if args.no_shadows {
        ShadowMode::Off
    } else {
        args.shadows.into()
    };
    let opts = WhittedOptions {
        width,
        height,
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
    let aspect = width as f32 / height as f32;
    let (setup, load_s) = timed(|| setup::setup(&args.scene, aspect));
    let mut setup = setup?;
    let frames = animation_frames(&setup.camera, &args.out, args.orbit, args.frames)?;
    // Each frame's AOV files are outputs too.
    let aov_files: Vec<std::path::PathBuf> = frames
        .iter()
        .flat_map(|f| aovs.iter().flat_map(|&k| aov_paths(&f.out, k)))
        .collect();
    let outs: Vec<&std::path::Path> = frames
        .iter()
        .map(|f| f.out.as_path())
        .chain(aov_files.iter().map(|p| p.as_path()))
        .collect();
    // The environment map is read too (a name such as `sky` names no file).
    let inputs = [
        std::path::Path::new(&args.scene.scene),
        std::path::Path::new(&args.scene.env),
    ];
    crate::paths::ensure_outputs(&outs, &inputs)?;
    let window = window.unwrap_or(raykit_render::Tile::whole(width, height));
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
            for AnimationFrame {
                number,
                camera,
                out,
            } in &frames
            {
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
                shadow_maps_fit(&setup.lights, args.shadow_map_size)?;
                let mut o = ShadowMapOptions::for_mesh(mesh);
                o.resolution = args.shadow_map_size;
                o.pcf = args.pcf;
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
            let scene = WhittedScene::new(
                mesh,
                accel.as_ref(),
                test,
                &setup.lights,
                &setup.environment,
            )
            .with_shadow_maps(maps.as_ref());
            for AnimationFrame {
                number,
                camera,
                out,
            } in &frames
            {
                let frame = pool.install(|| render_whitted(&scene, camera, &opts, &progress))?;
                rendered.push((*number, *camera, out.clone(), frame));
            }
            let build = args.build.options().quality.name();
            (
                build_s,
                format!("{} ({build} build), {}", kind.name(), test.name()),
            )
        }
    };
    bar.finish_and_clear();
    let mesh = &setup.scene.mesh;
    let scene_print = args.tile.map(|_| picture::scene(mesh, &setup.environment));
    for (number, camera, out, frame) in &rendered {
        match args.tile {
            Some(_) => {
                let part = raykit_io::ImagePart {
                    x: window.x,
                    y: window.y,
                    width: window.width,
                    height: window.height,
                    full_width: width,
                    full_height: height,
                    picture: picture::fingerprint(
                        scene_print.unwrap_or_default(),
                        camera,
                        &setup.lights,
                        &opts,
                    ),
                };
                raykit_io::write_png_part(out, &part, &frame.image.rgb)?;
            }
            None => write_image(out, format, &frame.image)?,
        }
        for kind in &aovs {
            let (exr, png) = write_aov(out, *kind, mesh, camera, frame)?;
            eprintln!(
                "{} AOV -> {} and {}",
                kind.name(),
                exr.display(),
                png.display()
            );
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
             ({}×{}, {} spp, depth {}, {} shadows, {} primaries, {}; {:.2} Mrays: {} primary, {} shadow, {} secondary; {:.2} Mrays/s) -> {}",
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
            width,
            height,
            args.spp,
            args.depth,
            format!("{shadows:?}").to_lowercase(),
            format!("{:?}", opts.primary).to_lowercase(),
            format!("{:?}", opts.integrator).to_lowercase(),
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

/// Most memory the shadow maps of one render may take.
const SHADOW_MAP_BUDGET: u64 = 8 << 30;

/// Refuses shadow maps of `size`² texels whose depths would need more than
/// [`SHADOW_MAP_BUDGET`]: one map per light, six for a point light's cube.
fn shadow_maps_fit(lights: &[raykit_core::light::Light], size: u32) -> Result<()> {
    let faces: u64 = lights
        .iter()
        .map(|l| match l {
            raykit_core::light::Light::Point(_) => 6,
            _ => 1,
        })
        .sum();
    let bytes = faces * u64::from(size).pow(2) * 4;
    if bytes > SHADOW_MAP_BUDGET {
        bail!(
            "shadow maps of {} lights ({faces} faces) at {size}² texels need {:.1} GiB, more than {} GiB: \
             lower --shadow-map-size",
            lights.len(),
            bytes as f64 / (1u64 << 30) as f64,
            SHADOW_MAP_BUDGET >> 30
        );
    }
    Ok(())
}
