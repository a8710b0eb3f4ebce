//! The arguments of `raykit terrain render` and their checks.

use crate::cmd::terrain::dem_arg;
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

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
pub struct FlyPath(pub Vec<[f64; 3]>);

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
raykit terrain render data/terrain/lidar_dem_400.tif --eye 429100,5150400,650 --target 429452,5150685,400 --caster maxmip\n  \
raykit terrain render data/terrain/lidar_dem_400.tif --drape ortho.png --light 429452,5150685,30\n  \
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
    /// DEM: GeoTIFF (.tif), Esri ASCII grid (.asc), SRTM .hgt, Terragen .ter, 16-bit PNG, raw .r16/.r32, or fractal:SIZE[:SEED].
    pub(super) dem: String,
    /// Image width in pixels.
    #[arg(long, default_value_t = 1600)]
    pub(super) width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 900)]
    pub(super) height: u32,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 50.0)]
    pub(super) fov: f64,
    /// Camera position X,Y,Z in map coordinates (Z: metres).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_xyz, allow_hyphen_values = true, conflicts_with = "path")]
    pub(super) eye: Option<[f64; 3]>,
    /// Point looked at, X,Y,Z in map coordinates (default: the surface at the DEM's centre).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_xyz, allow_hyphen_values = true, conflicts_with = "path")]
    pub(super) target: Option<[f64; 3]>,
    /// Camera EYE:TARGET as X,Y,Z:X,Y,Z in map coordinates (the same as --eye and --target).
    #[arg(long, value_name = "X,Y,Z:X,Y,Z", value_parser = parse_camera, allow_hyphen_values = true, conflicts_with_all = ["eye", "target", "path"])]
    pub(super) camera: Option<([f64; 3], [f64; 3])>,
    /// Ray caster [default: boxes with --backend cpu, maxmip with --backend gpu (the faster of the two on each, measured on lavapipe)].
    #[arg(long, value_enum)]
    pub(super) caster: Option<CasterArg>,
    /// Cast the rays on the CPU or the GPU.
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    pub(super) backend: BackendArg,
    /// LOD of --caster boxes: refine a quadtree node while it covers at least 4·τ² pixels.
    #[arg(long, default_value_t = 16.0)]
    pub(super) tau: f64,
    /// Sun AZIMUTH,ELEVATION in degrees (azimuth clockwise from north) [default: 135,35].
    #[arg(long, value_name = "AZ,EL", value_parser = parse_pair, allow_hyphen_values = true, conflicts_with = "light")]
    pub(super) sun: Option<[f64; 2]>,
    /// Point light X,Y,H: map position and height in metres above the ground there.
    #[arg(long, value_name = "X,Y,H", value_parser = parse_xyz, allow_hyphen_values = true)]
    pub(super) light: Option<[f64; 3]>,
    /// No shadow mask (diffuse and specular everywhere the surface faces the light).
    #[arg(long)]
    pub(super) no_shadows: bool,
    /// Orthophoto (RGB PNG) stretched over the DEM's extent, instead of the height colours.
    #[arg(long, value_name = "IMAGE.png")]
    pub(super) drape: Option<PathBuf>,
    /// Output PNG (with --path: a pattern containing {}).
    #[arg(long, default_value = "terrain.png")]
    pub(super) out: PathBuf,
    /// Also write the steps per ray (cells tested + nodes/boxes visited) as a heat map PNG
    /// (linear from black = 0 to white = the most, which the summary prints).
    #[arg(long, value_name = "HEAT.png")]
    pub(super) heatmap: Option<PathBuf>,
    /// Fly-through: eye positions X,Y,Z:X,Y,Z:... in map coordinates (at least two).
    #[arg(long, value_name = "X,Y,Z:X,Y,Z:...", value_parser = parse_path, allow_hyphen_values = true)]
    pub(super) path: Option<FlyPath>,
    /// Frames of the fly-through.
    #[arg(long, default_value_t = 60, requires = "path")]
    pub(super) frames: u32,
    /// Worker threads (0 = one per core; at most 4096).
    #[arg(long, default_value_t = 0)]
    pub(super) threads: usize,
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

/// Validate the plain numeric arguments.
pub(super) fn check_args(args: &TerrainRenderArgs) -> Result<()> {
    let max = raykit_io::MAX_IMAGE_SIDE;
    if args.width == 0 || args.width > max {
        bail!("--width must be between 1 and {max}, got {}", args.width);
    }
    if args.height == 0 || args.height > max {
        bail!("--height must be between 1 and {max}, got {}", args.height);
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
}
