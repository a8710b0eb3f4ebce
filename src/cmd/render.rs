//! `raykit render`: Phong shading with shadow rays, written to a PNG.

use crate::cmd::trace::parse_names;
use crate::measure::{pool, timed};
use crate::scene_arg;
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::build_accel;
use raykit_core::raysets::standard_light;
use raykit_core::{Camera, Vec3};
use raykit_render::{render, PointLight, RenderOptions};
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `raykit render`.
#[derive(Args)]
#[command(
    after_help = "Examples:\n  raykit render                                   # builtin:cornell to render.png\n  \
raykit render --scene builtin:terrain --width 1600 --height 900\n  \
raykit render --scene dragon.ply.gz --eye 0,0.2,0.4 --target 0,0.1,0 --spp 4\n  \
raykit render --scene bunny.obj --light 1,2,1 --light -1,2,0:0.5,0.5,1\n\n\
Without --eye the scene's own camera is used, or one framing the whole mesh.\n\
Without --light the scene's lights are used, or one light above the mesh."
)]
pub struct RenderArgs {
    /// Scene: builtin:NAME[:key=value,...] (`raykit info scenes`) or a mesh file.
    #[arg(long, default_value = "builtin:cornell")]
    scene: String,
    /// Image width in pixels.
    #[arg(long, default_value_t = 800)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 600)]
    height: u32,
    /// Camera position x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<Vec3>,
    /// Point the camera looks at, x,y,z (default: the mesh centre).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    target: Option<Vec3>,
    /// Up direction x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,1,0")]
    up: Vec3,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 40.0)]
    fov: f32,
    /// Point light `x,y,z` or `x,y,z:r,g,b` (irradiance at the mesh centre); repeatable.
    #[arg(long, value_name = "X,Y,Z[:R,G,B]", allow_hyphen_values = true)]
    light: Vec<String>,
    /// Samples per pixel (jittered anti-aliasing).
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Disable shadow rays.
    #[arg(long)]
    no_shadows: bool,
    /// Acceleration structure (`raykit info accels`).
    #[arg(long, default_value = "bvh2")]
    accel: String,
    /// Ray/triangle test (`raykit info tests`).
    #[arg(long, default_value = "moller")]
    test: String,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Output PNG.
    #[arg(long, default_value = "render.png")]
    out: PathBuf,
    #[command(flatten)]
    build: crate::build_args::BuildArgs,
}

/// Parse `x,y,z`.
pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected three numbers x,y,z, got '{s}'"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => Err(format!("expected three finite numbers x,y,z, got '{s}'")),
    }
}

/// Render and write the PNG.
pub fn run(args: RenderArgs) -> Result<ExitCode> {
    if args.width == 0 || args.height == 0 || args.width > 16384 || args.height > 16384 {
        bail!("--width and --height must be between 1 and 16384");
    }
    if args.spp == 0 || args.spp > 4096 {
        bail!("--spp must be between 1 and 4096");
    }
    if !(1.0..179.0).contains(&args.fov) {
        bail!("--fov must be between 1 and 179 degrees");
    }
    let (kind, test) = parse_names(&args.accel, &args.test)?;
    crate::paths::ensure_not_input(&args.out, &[std::path::Path::new(&args.scene)])?;
    let pool = pool(args.threads)?;
    let (scene, load_s) = timed(|| scene_arg::load(&args.scene));
    let mut scene = scene?;
    if scene.mesh.normals.is_none() {
        scene.mesh.compute_vertex_normals();
    }
    let bounds = scene.mesh.bounds();
    let mut camera = scene.camera.unwrap_or_else(|| {
        Camera::fit_points(
            &bounds,
            &scene.mesh.positions,
            args.fov,
            args.width as f32 / args.height as f32,
        )
    });
    if let Some(eye) = args.eye {
        camera = Camera {
            eye,
            target: args.target.unwrap_or(bounds.center()),
            up: args.up,
            vfov_deg: args.fov,
        };
    } else if let Some(target) = args.target {
        camera.target = target;
    }
    let mut lights = Vec::new();
    for spec in &args.light {
        lights.push(
            parse_light(spec, bounds.center())
                .with_context(|| format!("--light '{spec}'"))?
                .into(),
        );
    }
    if lights.is_empty() {
        lights = scene.lights.clone();
    }
    if lights.is_empty() {
        let p = standard_light(&bounds);
        lights.push(
            PointLight::with_irradiance_at(p, Vec3::splat(1.0), p.distance(bounds.center())).into(),
        );
    }
    let (accel, build_s) =
        pool.install(|| timed(|| build_accel(kind, test, &scene.mesh, &args.build.options())));
    let opts = RenderOptions {
        width: args.width,
        height: args.height,
        samples_per_pixel: args.spp,
        shadows: !args.no_shadows,
        ..RenderOptions::default()
    };
    let pixels = args.width as u64 * args.height as u64;
    let bar = ProgressBar::new(pixels).with_style(
        ProgressStyle::with_template("{bar:30} {percent:>3}% {msg} [{elapsed}<{eta}]")
            .expect("valid template"),
    );
    let rays_per_pixel = args.spp as u64 * (1 + if opts.shadows { lights.len() as u64 } else { 0 });
    let start = std::time::Instant::now();
    let progress = |n: u64| {
        bar.inc(n);
        let secs = start.elapsed().as_secs_f64().max(1e-9);
        bar.set_message(format!(
            "{:.1} Mrays/s",
            (bar.position() * rays_per_pixel) as f64 / secs / 1e6
        ));
    };
    let (image, render_s) = pool.install(|| {
        timed(|| {
            render(
                &scene.mesh,
                &lights,
                accel.as_ref(),
                &camera,
                &opts,
                &progress,
            )
        })
    });
    bar.finish_and_clear();
    raykit_io::write_png(&args.out, image.width, image.height, &image.rgb)?;
    eprintln!(
        "{}: {} triangles, load {:.0} ms, build {:.0} ms ({}, {}), render {:.0} ms ({}×{}, {} spp, {} lights, ~{:.1} Mrays/s) -> {}",
        scene.name,
        scene.mesh.num_triangles(),
        load_s * 1e3,
        build_s * 1e3,
        kind.name(),
        test.name(),
        render_s * 1e3,
        args.width,
        args.height,
        args.spp,
        lights.len(),
        (pixels * rays_per_pixel) as f64 / render_s / 1e6,
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// `x,y,z` or `x,y,z:r,g,b`; the colour is the irradiance at `reference`.
fn parse_light(spec: &str, reference: Vec3) -> Result<PointLight> {
    let (pos, colour) = match spec.split_once(':') {
        Some((p, c)) => (p, Some(c)),
        None => (spec, None),
    };
    let position = parse_vec3(pos).map_err(anyhow::Error::msg)?;
    let irradiance = match colour {
        Some(c) => parse_vec3(c).map_err(anyhow::Error::msg)?,
        None => Vec3::ONE,
    };
    let d = position.distance(reference).max(1e-6);
    Ok(PointLight::with_irradiance_at(position, irradiance, d))
}
