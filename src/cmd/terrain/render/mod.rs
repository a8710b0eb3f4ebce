//! `raykit terrain render`: a DEM rendered by exact height-field ray casting
//! (per-frame quadtree boxes, the maximum mipmap or the per-cell march), Phong
//! shading on the declared surface times the shadow mask, written
//! to a PNG; optionally a steps-per-ray heat map and fly-throughs.

mod args;

pub use args::TerrainRenderArgs;
use args::{check_args, BackendArg, CasterArg};

use super::dem_arg;
use crate::paths::{ensure_distinct, ensure_output};
use anyhow::{anyhow, bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_gpu::{GpuCaster, GpuContext, GpuTerrain};
use raykit_lab::measure::{median_min_max, pool, timed};
use raykit_terrain::georef::format_number;
use raykit_terrain::render_job::{RenderedFrame, TerrainRender, TerrainRenderOptions};
use raykit_terrain::view::{cast_image, Caster};
use raykit_terrain::{HeightField, MaxMipmap, TerrainCamera};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `pattern` with every `{}` replaced by `frame`, zero-padded to `digits`.
fn frame_path(pattern: &Path, frame: u32, digits: usize) -> PathBuf {
    PathBuf::from(
        pattern
            .to_string_lossy()
            .replace("{}", &format!("{frame:0digits$}")),
    )
}

/// Create the folder `path` goes in, if missing.
fn ensure_parent(path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the folder {}", dir.display()))?;
    }
    Ok(())
}

fn write_png(path: &Path, w: u32, h: u32, rgb: &[u8]) -> Result<()> {
    ensure_parent(path)?;
    raykit_io::write_png(path, w, h, rgb)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// The caster: `--caster`, or the backend's faster one (per-frame quadtree boxes
/// on the CPU, the per-ray maximum mipmap on the GPU).
fn resolve_caster(args: &TerrainRenderArgs) -> CasterArg {
    args.caster.unwrap_or(match args.backend {
        BackendArg::Cpu => CasterArg::Boxes,
        BackendArg::Gpu => CasterArg::Maxmip,
    })
}

/// The GPU caster for `--caster` (maxmip or boxes; the reference march
/// runs on the CPU only).
fn gpu_caster(args: &TerrainRenderArgs) -> Result<GpuCaster> {
    match resolve_caster(args) {
        CasterArg::Maxmip => Ok(GpuCaster::MaxMipmap),
        CasterArg::Boxes => Ok(GpuCaster::Boxes { tau: args.tau }),
        CasterArg::March => bail!(
            "--backend gpu casts with --caster maxmip or boxes; --caster march (the reference) \
             runs on the CPU (--backend cpu)"
        ),
    }
}

/// The GPU device and the DEM uploaded to it (`--backend gpu`).
fn open_gpu(field: &HeightField, pyramid: &MaxMipmap) -> Result<(GpuContext, GpuTerrain, f64)> {
    let start = std::time::Instant::now();
    let ctx = GpuContext::new().map_err(|e| anyhow!("--backend gpu: {e}"))?;
    let terrain =
        GpuTerrain::new(&ctx, field, pyramid).map_err(|e| anyhow!("--backend gpu: {e}"))?;
    Ok((ctx, terrain, start.elapsed().as_secs_f64()))
}

/// Render and write the PNG(s).
pub fn run(args: TerrainRenderArgs) -> Result<ExitCode> {
    check_args(&args)?;
    let caster_arg = resolve_caster(&args);
    let gpu_caster = match args.backend {
        BackendArg::Gpu => Some(gpu_caster(&args)?),
        BackendArg::Cpu => None,
    };
    let frames = if args.path.is_some() { args.frames } else { 1 };
    let digits = (frames.saturating_sub(1)).to_string().len();
    let outputs = |pattern: &Path| -> Vec<PathBuf> {
        if args.path.is_some() {
            (0..frames)
                .map(|i| frame_path(pattern, i, digits))
                .collect()
        } else {
            vec![pattern.to_path_buf()]
        }
    };
    let out_paths = outputs(&args.out);
    let heat_paths = args.heatmap.as_deref().map(outputs);
    let mut inputs: Vec<&Path> = vec![Path::new(&args.dem)];
    if let Some(d) = &args.drape {
        inputs.push(d);
    }
    // The folders are made (a fly-through's frames go into a new one), or
    // refused, before the work.
    crate::paths::ensure_extension(&args.out, "--out (a PNG)", &["png"])?;
    if let Some(h) = &args.heatmap {
        crate::paths::ensure_extension(h, "--heatmap (a PNG)", &["png"])?;
    }
    for p in out_paths.iter().chain(heat_paths.iter().flatten()) {
        ensure_parent(p)?;
        ensure_output(p, &inputs)?;
    }
    for (p, h) in out_paths.iter().zip(heat_paths.iter().flatten()) {
        ensure_distinct(p, h, "--out", "--heatmap")?;
    }
    let pool = pool(args.threads)?;

    let (dem, load_s) = timed(|| dem_arg::load(&args.dem));
    let dem = dem?;
    let field = HeightField::new(&dem).map_err(|e| anyhow!("{}: {e}", args.dem))?;
    let (pyramid, pyramid_s) = pool.install(|| timed(|| MaxMipmap::new(&field)));
    let (eye, target) = match args.camera {
        Some((e, t)) => (Some(e), Some(t)),
        None => (args.eye, args.target),
    };
    let options = TerrainRenderOptions {
        eye,
        target,
        path: args.path.clone().map(|p| p.0),
        frames,
        sun: args.sun,
        light: args.light,
        shadows: !args.no_shadows,
        drape: args.drape.clone(),
    };
    let job = pool
        .install(|| TerrainRender::new(&dem, &field, &pyramid, &options))
        .map_err(anyhow::Error::msg)?;
    let (geo, cameras, mask_s) = (job.geo, &job.cameras, job.mask_seconds);

    let gpu = match args.backend {
        BackendArg::Gpu => Some(open_gpu(&field, &pyramid)?),
        BackendArg::Cpu => None,
    };
    let caster = match caster_arg {
        CasterArg::March => Caster::March,
        CasterArg::Maxmip => Caster::MaxMipmap,
        CasterArg::Boxes => Caster::Boxes { tau: args.tau },
    };
    let mut caster_name = match caster_arg {
        CasterArg::March => "march".to_string(),
        CasterArg::Maxmip => "maxmip".to_string(),
        CasterArg::Boxes => format!("boxes, tau {}", args.tau),
    };
    if let Some((ctx, _, setup_s)) = &gpu {
        caster_name += &format!(
            " on the GPU, {}, upload {:.0} ms",
            ctx.describe(),
            setup_s * 1e3
        );
    }

    let bar = if args.path.is_some() {
        ProgressBar::new(frames as u64).with_style(
            ProgressStyle::with_template("{bar:30} {pos}/{len} frames {msg} [{elapsed}<{eta}]")
                .expect("valid template"),
        )
    } else {
        ProgressBar::hidden()
    };
    let pixels = args.width as u64 * args.height as u64;
    let cast = |camera: &TerrainCamera| match &gpu {
        Some((ctx, terrain, _)) => {
            let caster = gpu_caster.expect("set with the GPU");
            terrain
                .cast(ctx, &field, &pyramid, camera, caster)
                .map_err(|e| format!("--backend gpu: {e}"))
        }
        None => Ok(cast_image(&field, &pyramid, camera, caster)),
    };
    let mut write = |i: usize, image: &RenderedFrame| -> Result<(), String> {
        write_png(&out_paths[i], args.width, args.height, &image.rgb)
            .map_err(|e| format!("{e:#}"))?;
        if let (Some(paths), Some((hrgb, _))) = (&heat_paths, &image.heat) {
            write_png(&paths[i], args.width, args.height, hrgb).map_err(|e| format!("{e:#}"))?;
        }
        Ok(())
    };
    let progress = |done: usize, secs: f64| {
        bar.inc(1);
        bar.set_message(format!("{:.1} fps", done as f64 / secs.max(1e-9)));
    };
    let times = pool
        .install(|| {
            job.render_frames(
                args.width,
                args.height,
                args.fov,
                heat_paths.is_some(),
                &cast,
                &mut write,
                &progress,
            )
        })
        .map_err(anyhow::Error::msg)?;
    bar.finish_and_clear();
    let (cast_times, shade_times, write_s, wall_s) =
        (&times.cast, &times.shade, times.write, times.wall);
    let ((boxes_min, boxes_max), steps_max) = (times.boxes, times.steps_max);

    // Summary.
    let name = Path::new(&args.dem)
        .file_name()
        .filter(|_| !args.dem.starts_with(dem_arg::FRACTAL))
        .map_or(args.dem.clone(), |n| n.to_string_lossy().into_owned());
    let light_text = job.light_text();
    let mask_text = if args.no_shadows {
        "shadows off".to_string()
    } else {
        format!("shadow mask {:.0} ms ({light_text})", mask_s * 1e3)
    };
    eprintln!(
        "{name}: {}x{} samples, cell {:.2} x {:.2} m, heights {:.1}..{:.1} m; load {:.0} ms, \
         pyramid {:.0} ms, {mask_text}",
        field.width,
        field.height,
        field.sx,
        field.sy,
        field.zmin,
        field.zmax,
        load_s * 1e3,
        pyramid_s * 1e3,
    );
    let boxes_text = match caster_arg {
        CasterArg::Boxes if boxes_min == boxes_max => format!(", {boxes_max} boxes"),
        CasterArg::Boxes => format!(", {boxes_min}..{boxes_max} boxes"),
        _ => String::new(),
    };
    let heat_text = if heat_paths.is_some() {
        format!(", heat map max {steps_max} steps/ray")
    } else {
        String::new()
    };
    if args.path.is_none() {
        let (cast_s, shade_s) = (cast_times[0], shade_times[0]);
        let m = geo.to_map(cameras[0].0);
        let t = geo.to_map(cameras[0].1);
        eprintln!(
            "render {:.0} ms ({}x{}): cast {:.0} ms ({caster_name}{boxes_text}, {:.1} Mrays/s), \
             shade {:.0} ms, write {:.0} ms{heat_text}; eye {},{},{:.0} target {},{},{:.0} -> {}",
            (cast_s + shade_s) * 1e3,
            args.width,
            args.height,
            cast_s * 1e3,
            pixels as f64 / cast_s.max(1e-9) / 1e6,
            shade_s * 1e3,
            write_s * 1e3,
            format_number(m[0]),
            format_number(m[1]),
            m[2],
            format_number(t[0]),
            format_number(t[1]),
            t[2],
            args.out.display()
        );
    } else {
        let frame_times: Vec<f64> = cast_times
            .iter()
            .zip(shade_times.iter())
            .map(|(c, s)| c + s)
            .collect();
        let (med, min, max) = median_min_max(&frame_times);
        let (cast_med, _, _) = median_min_max(cast_times);
        let (shade_med, _, _) = median_min_max(shade_times);
        eprintln!(
            "{frames} frames ({}x{}): frame time median {:.1} ms (cast {:.1} + shade {:.1}), \
             min {:.1}, max {:.1} ms; {:.1} fps ({caster_name}{boxes_text}, {:.1} Mrays/s); \
             {:.1} s in all with PNG writing{heat_text} -> {}",
            args.width,
            args.height,
            med * 1e3,
            cast_med * 1e3,
            shade_med * 1e3,
            min * 1e3,
            max * 1e3,
            1.0 / med.max(1e-9),
            pixels as f64 / cast_med.max(1e-9) / 1e6,
            wall_s,
            args.out.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns_are_zero_padded() {
        assert_eq!(
            frame_path(Path::new("f/f{}.png"), 7, 3),
            PathBuf::from("f/f007.png")
        );
    }
}
