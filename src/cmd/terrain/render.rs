//! `raykit terrain render`: a DEM rendered by exact height-field ray casting
//! (per-frame quadtree boxes, the maximum mipmap or the per-cell march), Phong
//! shading on the declared surface times the shadow mask, written
//! to a PNG; optionally a steps-per-ray heat map and fly-throughs.

use super::dem_arg;
use crate::measure::{median_min_max, pool, timed};
use crate::paths::ensure_not_input;
use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_gpu::{GpuCaster, GpuContext, GpuTerrain};
use raykit_terrain::camera::{centre, default_camera, path_cameras};
use raykit_terrain::georef::{format_number, MapWorld};
use raykit_terrain::shade::{self, Albedo, Drape, Shading};
use raykit_terrain::shadow::{light_above_ground, shadow_mask, Light, ShadowMethod};
use raykit_terrain::view::{cast_image, Caster};
use raykit_terrain::{HeightField, MaxMipmap, TerrainCamera};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Which caster (all three are exact and give identical images).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CasterArg {
    /// Per-cell 2D DDA from the grid's bounding box (the reference).
    March,
    /// Per-ray maximum-mipmap quadtree traversal (Tevs et al. 2008).
    Maxmip,
    /// Per-frame quadtree boxes with LOD τ, then a march from each pixel's box entry.
    Boxes,
}

/// Where the rays are cast (shading is on the host either way).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    /// The CPU casters, parallel over rows (every --caster).
    Cpu,
    /// raykit-gpu's WGSL kernels (wgpu: Vulkan, Metal, DX12 or Mesa's lavapipe), f32 (--caster maxmip or boxes).
    Gpu,
}

/// Eye positions of a fly-through, map coordinates.
#[derive(Clone, Debug)]
pub struct FlyPath(Vec<[f64; 3]>);

/// Arguments of `raykit terrain render`.
#[derive(Args)]
#[command(
    after_help = "Map coordinates are in the DEM's own units: metres for projected rasters, \
degrees of longitude/latitude for geographic ones such as SRTM .hgt; Z and heights are metres.\n\n\
Default camera (without --eye): the eye stands 3/4 of the way from the DEM's centre to its \
south-west corner, above the highest point, looking north-east towards the centre 20° below \
the horizontal (the top of the image shows sky at the default 50° field of view). Without \
--target the camera looks at the surface at the DEM's centre.\n\n\
Shading: Phong (ambient + diffuse + specular) with the normal of the hit triangle of the \
declared surface (two triangles per cell), times the shadow mask (exact, per grid point, \
interpolated bilinearly over the hit cell's four corners). Colours: a hypsometric ramp over the \
DEM's height range (greens, browns, greys, white) or --drape. Rays that miss see a sky gradient.\n\n\
Examples:\n  raykit terrain render N57E011.hgt --out n57.png\n  \
raykit terrain render fractal:1025:7 --sun 300,20 --heatmap steps.png\n  \
raykit terrain render dem.tif --eye 429000,5149000,900 --target 430500,5151000,300 --caster maxmip\n  \
raykit terrain render dem.tif --drape ortho.png --light 429452,5150685,30\n  \
raykit terrain render fractal:513 --path 500,500,2300:4000,2500,2100:4500,4500,2200 --frames 120 --out frames/f{}.png\n  \
raykit terrain render N57E011.hgt --backend gpu --heatmap steps.png\n\n\
GPU backend (--backend gpu): the heights and the maximum mipmap are uploaded once and a WGSL \
kernel casts one ray per pixel in f32 on the same declared surface: --caster maxmip (the \
default there) walks the maximum mipmap per ray (Tevs et al. 2008) as the CPU does; --caster boxes takes the \
boxes from the CPU's per-frame quadtree traversal, finds each pixel's nearest box entry and \
marches from there. Hit cells, distances and step counts come back and the host shades them \
with the same code, so the image equals the CPU's but at the rare pixels where f32 rounding \
decides (a hit on a cell border or a ray grazing the surface). It needs a wgpu adapter (a \
Vulkan, Metal or DX12 driver, or Mesa's software lavapipe: apt-get install \
mesa-vulkan-drivers); --caster march runs on the CPU only; the DEM's heights and pyramid must \
each fit one storage buffer of the device (the error names the limit).\n\n\
Fly-through: --path renders --frames images along the polyline (evenly by distance); the camera \
looks along the path, 10° downward. --out (and --heatmap) must contain {}, replaced by the frame \
number (from 0, zero-padded to the same width)."
)]
pub struct TerrainRenderArgs {
    /// DEM: GeoTIFF (.tif), SRTM .hgt, Terragen .ter, 16-bit PNG, raw .r16/.r32, or fractal:SIZE[:SEED].
    dem: String,
    /// Image width in pixels.
    #[arg(long, default_value_t = 1600)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 900)]
    height: u32,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 50.0)]
    fov: f64,
    /// Camera position X,Y,Z in map coordinates (Z: metres).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_xyz, allow_hyphen_values = true, conflicts_with = "path")]
    eye: Option<[f64; 3]>,
    /// Point looked at, X,Y,Z in map coordinates (default: the surface at the DEM's centre).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_xyz, allow_hyphen_values = true, conflicts_with = "path")]
    target: Option<[f64; 3]>,
    /// Camera EYE:TARGET as X,Y,Z:X,Y,Z in map coordinates (the same as --eye and --target).
    #[arg(long, value_name = "X,Y,Z:X,Y,Z", value_parser = parse_camera, allow_hyphen_values = true, conflicts_with_all = ["eye", "target", "path"])]
    camera: Option<([f64; 3], [f64; 3])>,
    /// Ray caster [default: boxes with --backend cpu, maxmip with --backend gpu (the faster of the two on each, measured on lavapipe)].
    #[arg(long, value_enum)]
    caster: Option<CasterArg>,
    /// Cast the rays on the CPU or the GPU.
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
    /// LOD of --caster boxes: refine a quadtree node while it covers at least 4·τ² pixels.
    #[arg(long, default_value_t = 16.0)]
    tau: f64,
    /// Sun AZIMUTH,ELEVATION in degrees (azimuth clockwise from north) [default: 135,35].
    #[arg(long, value_name = "AZ,EL", value_parser = parse_pair, allow_hyphen_values = true, conflicts_with = "light")]
    sun: Option<[f64; 2]>,
    /// Point light X,Y,H: map position and height in metres above the ground there.
    #[arg(long, value_name = "X,Y,H", value_parser = parse_xyz, allow_hyphen_values = true)]
    light: Option<[f64; 3]>,
    /// No shadow mask (diffuse and specular everywhere the surface faces the light).
    #[arg(long)]
    no_shadows: bool,
    /// Orthophoto (RGB PNG) stretched over the DEM's extent, instead of the height colours.
    #[arg(long, value_name = "IMAGE.png")]
    drape: Option<PathBuf>,
    /// Output PNG (with --path: a pattern containing {}).
    #[arg(long, default_value = "terrain.png")]
    out: PathBuf,
    /// Also write the steps per ray (cells tested + nodes/boxes visited) as a heat map PNG
    /// (linear from black = 0 to white = the most, which the summary prints).
    #[arg(long, value_name = "HEAT.png")]
    heatmap: Option<PathBuf>,
    /// Fly-through: eye positions X,Y,Z:X,Y,Z:... in map coordinates (at least two).
    #[arg(long, value_name = "X,Y,Z:X,Y,Z:...", value_parser = parse_path, allow_hyphen_values = true)]
    path: Option<FlyPath>,
    /// Frames of the fly-through.
    #[arg(long, default_value_t = 60, requires = "path")]
    frames: u32,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
}

/// Parse `x,y,z`.
fn parse_xyz(s: &str) -> Result<[f64; 3], String> {
    dem_arg::parse_numbers::<3>(s, "X,Y,Z")
}

/// Parse `X,Y,Z:X,Y,Z` (eye, then target).
fn parse_camera(s: &str) -> Result<([f64; 3], [f64; 3]), String> {
    let (e, t) = s
        .split_once(':')
        .ok_or_else(|| format!("expected EYE:TARGET as X,Y,Z:X,Y,Z, got '{s}'"))?;
    Ok((parse_xyz(e)?, parse_xyz(t)?))
}

/// Parse `a,b`.
fn parse_pair(s: &str) -> Result<[f64; 2], String> {
    dem_arg::parse_numbers::<2>(s, "AZ,EL")
}

/// Parse `x,y,z:x,y,z:...`.
fn parse_path(s: &str) -> Result<FlyPath, String> {
    let points = s
        .split(':')
        .enumerate()
        .map(|(i, p)| parse_xyz(p).map_err(|e| format!("point {}: {e}", i + 1)))
        .collect::<Result<Vec<_>, _>>()?;
    if points.len() < 2 {
        return Err(format!(
            "expected at least two points X,Y,Z:X,Y,Z, got {}",
            points.len()
        ));
    }
    Ok(FlyPath(points))
}

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

/// Validate the plain numeric arguments.
fn check_args(args: &TerrainRenderArgs) -> Result<()> {
    if args.width == 0 || args.width > 16384 {
        bail!("--width must be between 1 and 16384, got {}", args.width);
    }
    if args.height == 0 || args.height > 16384 {
        bail!("--height must be between 1 and 16384, got {}", args.height);
    }
    if !(args.fov >= 1.0 && args.fov < 179.0) {
        bail!("--fov must be between 1 and 179 degrees, got {}", args.fov);
    }
    if !(args.tau > 0.0 && args.tau <= 4096.0) {
        bail!(
            "--tau must be a number of pixels in (0, 4096], got {}",
            args.tau
        );
    }
    if args.frames == 0 || args.frames > 100_000 {
        bail!("--frames must be between 1 and 100000, got {}", args.frames);
    }
    if let Some([az, el]) = args.sun {
        if !(el > 0.0 && el <= 90.0) {
            bail!("--sun {az},{el}: the elevation must be in (0, 90] degrees above the horizon");
        }
        if !(-360.0..=720.0).contains(&az) {
            bail!("--sun {az},{el}: the azimuth must be in degrees, 0..360 clockwise from north");
        }
    }
    if let Some([_, _, h]) = args.light {
        if h < 0.0 {
            bail!("--light: the height above the ground must not be negative, got {h}");
        }
    }
    if args.path.is_some() {
        if !args.out.to_string_lossy().contains("{}") {
            bail!(
                "--out {}: with --path it must be a pattern containing {{}} (the frame number), \
                 e.g. frames/f{{}}.png",
                args.out.display()
            );
        }
        if let Some(h) = &args.heatmap {
            if !h.to_string_lossy().contains("{}") {
                bail!(
                    "--heatmap {}: with --path it must be a pattern containing {{}}",
                    h.display()
                );
            }
        }
    }
    Ok(())
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
    for p in out_paths.iter().chain(heat_paths.iter().flatten()) {
        ensure_not_input(p, &inputs)?;
    }
    let pool = pool(args.threads)?;

    let (dem, load_s) = timed(|| dem_arg::load(&args.dem));
    let dem = dem?;
    let field = HeightField::new(&dem).map_err(|e| anyhow!("{}: {e}", args.dem))?;
    let geo = MapWorld::new(&dem, &field);
    let (pyramid, pyramid_s) = pool.install(|| timed(|| MaxMipmap::new(&field)));

    // Light.
    let light = match args.light {
        Some(l) => {
            let w = geo.to_world([l[0], l[1], 0.0]);
            let p = light_above_ground(&field, w[0], w[1], l[2]).ok_or_else(|| {
                anyhow!(
                    "--light {},{}: outside the DEM; expected map coordinates within {}",
                    format_number(l[0]),
                    format_number(l[1]),
                    geo.describe_extent()
                )
            })?;
            Light::Point(p)
        }
        None => {
            let [az, el] = args.sun.unwrap_or([135.0, 35.0]);
            Light::Sun {
                azimuth_deg: az,
                elevation_deg: el,
            }
        }
    };
    let (mask, mask_s) = if args.no_shadows {
        (None, 0.0)
    } else {
        let (m, s) =
            pool.install(|| timed(|| shadow_mask(&field, &pyramid, &light, ShadowMethod::Fast)));
        (Some(m), s)
    };
    let drape = match &args.drape {
        Some(p) => {
            let img = image::open(p)
                .with_context(|| format!("--drape {}: cannot read the image", p.display()))?
                .to_rgb8();
            Some(Drape::new(img.width(), img.height(), img.as_raw()))
        }
        None => None,
    };
    let albedo = match &drape {
        Some(d) => Albedo::Drape(d),
        None => Albedo::Ramp {
            zmin: field.zmin as f64,
            zmax: field.zmax as f64,
        },
    };
    let shading = Shading {
        field: &field,
        light,
        mask: mask.as_deref(),
        albedo,
    };

    // Cameras (world metres).
    let (_, _, diag) = geo.extent();
    let cameras: Vec<([f64; 3], [f64; 3])> = match &args.path {
        Some(FlyPath(points)) => {
            let world = points
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    geo.check(&format!("--path (point {})", i + 1), *p, true)
                        .map_err(|e| anyhow!(e))
                })
                .collect::<Result<Vec<_>>>()?;
            path_cameras(&world, frames, diag).map_err(|e| anyhow!("--path: {e}"))?
        }
        None => {
            let (def_eye, def_target) = default_camera(&field);
            let (cam_eye, cam_target) = match args.camera {
                Some((e, t)) => (Some(e), Some(t)),
                None => (args.eye, args.target),
            };
            let eye = match cam_eye {
                Some(e) => geo.check("--eye", e, true).map_err(|e| anyhow!(e))?,
                None => def_eye,
            };
            let target = match cam_target {
                Some(t) => geo.check("--target", t, false).map_err(|e| anyhow!(e))?,
                None if cam_eye.is_some() => centre(&field),
                None => def_target,
            };
            let d = [target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]];
            if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= 1e-9 * diag.max(1.0) {
                bail!("--target must differ from --eye (the camera needs a direction to look in)");
            }
            vec![(eye, target)]
        }
    };

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
    let mut cast_times = Vec::with_capacity(cameras.len());
    let mut shade_times = Vec::with_capacity(cameras.len());
    let mut write_s = 0.0;
    let (mut boxes_min, mut boxes_max, mut steps_max) = (usize::MAX, 0usize, 0u32);
    let wall = std::time::Instant::now();
    for (i, &(eye, target)) in cameras.iter().enumerate() {
        let camera = TerrainCamera {
            eye,
            target,
            vfov_deg: args.fov,
            width: args.width,
            height: args.height,
        };
        let (cast, cast_s) = match &gpu {
            Some((ctx, terrain, _)) => {
                let caster = gpu_caster.expect("set with the GPU");
                let (cast, s) = timed(|| terrain.cast(ctx, &field, &pyramid, &camera, caster));
                (cast.map_err(|e| anyhow!("--backend gpu: {e}"))?, s)
            }
            None => pool.install(|| timed(|| cast_image(&field, &pyramid, &camera, caster))),
        };
        let frame = camera.frame();
        let (rgb, shade_s) = pool.install(|| timed(|| shading.image(&frame, &cast.hits)));
        let start_write = std::time::Instant::now();
        write_png(&out_paths[i], args.width, args.height, &rgb)?;
        if let Some(heat) = &heat_paths {
            let (hrgb, max) = shade::heatmap(&cast.steps);
            steps_max = steps_max.max(max);
            write_png(&heat[i], args.width, args.height, &hrgb)?;
        }
        write_s += start_write.elapsed().as_secs_f64();
        boxes_min = boxes_min.min(cast.boxes);
        boxes_max = boxes_max.max(cast.boxes);
        cast_times.push(cast_s);
        shade_times.push(shade_s);
        bar.inc(1);
        let secs = wall.elapsed().as_secs_f64().max(1e-9);
        bar.set_message(format!("{:.1} fps", (i + 1) as f64 / secs));
    }
    bar.finish_and_clear();
    let wall_s = wall.elapsed().as_secs_f64();

    // Summary.
    let name = Path::new(&args.dem)
        .file_name()
        .filter(|_| !args.dem.starts_with(dem_arg::FRACTAL))
        .map_or(args.dem.clone(), |n| n.to_string_lossy().into_owned());
    let light_text = match light {
        Light::Sun {
            azimuth_deg,
            elevation_deg,
        } => format!("sun {azimuth_deg}°/{elevation_deg}°"),
        Light::Point(p) => format!("point light at {:.1} m", p[2]),
    };
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
            .zip(&shade_times)
            .map(|(c, s)| c + s)
            .collect();
        let (med, min, max) = median_min_max(&frame_times);
        let (cast_med, _, _) = median_min_max(&cast_times);
        let (shade_med, _, _) = median_min_max(&shade_times);
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
    fn parses_points_and_paths() {
        assert_eq!(parse_xyz("1,-2, 3.5").unwrap(), [1.0, -2.0, 3.5]);
        assert!(parse_xyz("1,2").is_err());
        assert!(parse_xyz("1,2,nan").is_err());
        assert!(parse_pair("135,35").is_ok());
        assert_eq!(parse_path("0,0,1:1,1,2").unwrap().0.len(), 2);
        assert!(parse_path("0,0,1").is_err());
        assert!(parse_path("0,0,1:x").unwrap_err().contains("point 2"));
    }

    #[test]
    fn frame_patterns_are_zero_padded() {
        assert_eq!(
            frame_path(Path::new("f/f{}.png"), 7, 3),
            PathBuf::from("f/f007.png")
        );
    }
}
