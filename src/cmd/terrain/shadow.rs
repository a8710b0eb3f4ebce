//! `raykit terrain shadow`: where a point light or the sun is visible from
//! the ground (Min's (2008) terrain shadow map), exact for the declared
//! surface, written as a GeoTIFF with the DEM's georeferencing and a PNG
//! preview; or hours of direct sun per cell over a day. The options follow
//! gdal_viewshed where the meaning is the same (values of visible,
//! invisible, out-of-range and no-data cells, target height, maximum
//! distance, curvature coefficient, creation options).

use super::creation_options;
use super::dem_arg::{self, numbers};
use crate::measure::timed;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_terrain::curvature::curvature_corrected;
use raykit_terrain::georef::MapWorld;
use raykit_terrain::io::GeoTiffLayout;
use raykit_terrain::shadow::{shadow_mask_for_targets, Light, ShadowMethod};
use raykit_terrain::sun::{day_of_year, sun_position};
use raykit_terrain::{Dem, HeightField, MaxMipmap};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Which algorithm.
#[derive(Clone, Copy, ValueEnum)]
pub enum Method {
    /// Each segment through the min/max quadtree (default).
    Fast,
    /// Each segment marched cell by cell (brute force).
    Brute,
}

/// Arguments of `raykit terrain shadow`.
#[derive(Args)]
#[command(after_help = "Exactly one of --light, --sun, --sun-path.\n\n\
The surface is the DEM's grid points joined as two triangles per cell. A grid point is lit when the\n\
segment from the surface there to the light meets no other part of the surface. Map coordinates\n\
are in the DEM's own units (metres for projected rasters, degrees for SRTM .hgt).\n\n\
Output values (gdal_viewshed's -vv, -iv, -ov, -a_nodata): --visible-value (default 1),\n\
--invisible-value (0), --out-of-range-value (0) for cells beyond --max-distance, --nodata-value\n\
(255) where the DEM has no data. The GeoTIFF is DEFLATE-compressed in strips unless --co says\n\
otherwise (--co COMPRESS=DEFLATE|LZW|PACKBITS|NONE, --co TILED=YES, --co BLOCKXSIZE=N).\n\
Unlike gdal_viewshed, the output always covers the whole DEM, and the curvature coefficient is 0\n\
(a flat earth, exact for the declared surface) unless given; gdal_viewshed's default is 0.85714.\n\
The long options have gdal-like aliases: --vv, --iv, --ov, --tz, --md, --cc.\n\n\
Examples:\n  raykit terrain shadow dem.tif --light 429452,5150685,10 --out mask.tif\n  \
raykit terrain shadow dem.tif --light 429452,5150685,10 --vv 255 --tz 2 --md 5000 --cc 0.85714 \\\n      \
--co TILED=YES --out viewshed.tif\n  \
raykit terrain shadow N57E011.hgt --sun 135,20 --out sun.tif --preview sun.png\n  \
raykit terrain shadow dem.tif --sun-path 2026-06-21,45.5,-93.2 --out hours.tif\n  \
raykit terrain shadow fractal:2048 --light 10000,-10000,50 --compare --out m.tif")]
pub struct ShadowArgs {
    /// DEM: GeoTIFF, SRTM .hgt, Terragen .ter, 16-bit PNG, or fractal:SIZE[:SEED].
    dem: String,
    /// Point light X,Y,H: map position and height above the ground there (gdal_viewshed's -ox -oy -oz).
    #[arg(long, value_name = "X,Y,H", allow_hyphen_values = true)]
    light: Option<String>,
    /// With --light: H is an absolute elevation, not a height above the ground.
    #[arg(long)]
    light_elevation: bool,
    /// Directional light AZIMUTH,ELEVATION in degrees (azimuth clockwise from north).
    #[arg(long, value_name = "AZ,EL", allow_hyphen_values = true)]
    sun: Option<String>,
    /// Hours of direct sun per cell over a day: YYYY-MM-DD,LAT,LON (UTC day, output float32 hours).
    #[arg(long, value_name = "DATE,LAT,LON", allow_hyphen_values = true)]
    sun_path: Option<String>,
    /// Minutes between sun positions for --sun-path.
    #[arg(long, default_value_t = 10.0)]
    step_minutes: f64,
    /// Algorithm (both are exact and give identical masks).
    #[arg(long, value_enum, default_value_t = Method::Fast)]
    method: Method,
    /// Run both algorithms, report their times and the cells on which they differ.
    #[arg(long)]
    compare: bool,
    /// Height above the ground of the target at every grid point, metres
    /// (gdal_viewshed's -tz): a cell is lit when the light sees that point.
    #[arg(
        long,
        visible_alias = "tz",
        default_value_t = 0.0,
        value_name = "METRES"
    )]
    target_height: f64,
    /// With --light: cells farther than this from the light, horizontally in
    /// metres, get --out-of-range-value (gdal_viewshed's -md).
    #[arg(long, visible_alias = "md", value_name = "METRES")]
    max_distance: Option<f64>,
    /// With --light: lower every height by COEFF · d² / earth diameter, d the
    /// horizontal distance from the light (curvature and refraction,
    /// gdal_viewshed's -cc; 1 is curvature alone, 0.85714 gdal's default).
    #[arg(
        long,
        visible_alias = "cc",
        default_value_t = 0.0,
        value_name = "COEFF"
    )]
    curvature_coefficient: f64,
    /// Mask value of lit cells (gdal_viewshed's -vv).
    #[arg(long, visible_alias = "vv", default_value_t = 1, value_name = "0-255")]
    visible_value: u8,
    /// Mask value of cells in shadow (gdal_viewshed's -iv).
    #[arg(long, visible_alias = "iv", default_value_t = 0, value_name = "0-255")]
    invisible_value: u8,
    /// Mask value of cells beyond --max-distance (gdal_viewshed's -ov).
    #[arg(long, visible_alias = "ov", default_value_t = 0, value_name = "0-255")]
    out_of_range_value: u8,
    /// Mask value, declared as the GeoTIFF's nodata, where the DEM has no data
    /// (gdal_viewshed's -a_nodata).
    #[arg(long, default_value_t = 255, value_name = "0-255")]
    nodata_value: u8,
    /// GeoTIFF creation option KEY=VALUE, repeatable (gdal's -co):
    /// COMPRESS=DEFLATE|LZW|PACKBITS|NONE (default DEFLATE), TILED=YES|NO,
    /// BLOCKXSIZE=N, BLOCKYSIZE=N (tile size, default 256).
    #[arg(long = "co", value_name = "KEY=VALUE", action = clap::ArgAction::Append)]
    creation_options: Vec<String>,
    /// Output GeoTIFF (mask: --visible-value, --invisible-value, ...; sun
    /// path: float32 hours).
    #[arg(long)]
    out: PathBuf,
    /// PNG preview (default: OUT with .png).
    #[arg(long)]
    preview: Option<PathBuf>,
}

fn compute(
    field: &HeightField,
    pyramid: &MaxMipmap,
    light: &Light,
    method: ShadowMethod,
    target_height: f64,
    label: &str,
) -> (Vec<u8>, f64) {
    let bar = ProgressBar::new((field.width * field.height) as u64).with_style(
        ProgressStyle::with_template("{bar:30} {percent:>3}% {msg} [{elapsed}<{eta}]")
            .expect("valid template"),
    );
    bar.set_message(label.to_string());
    let (mask, s) = timed(|| {
        shadow_mask_for_targets(field, pyramid, light, method, target_height, &|n| {
            bar.inc(n as u64)
        })
    });
    bar.finish_and_clear();
    (mask, s)
}

/// Compute and write the mask (or the hours of sun).
pub fn run(args: ShadowArgs) -> Result<ExitCode> {
    let chosen = [
        args.light.is_some(),
        args.sun.is_some(),
        args.sun_path.is_some(),
    ];
    if chosen.iter().filter(|&&c| c).count() != 1 {
        bail!("give exactly one of --light, --sun, --sun-path");
    }
    if args.light_elevation && args.light.is_none() {
        bail!("--light-elevation applies to --light only");
    }
    if args.light.is_none() && (args.max_distance.is_some() || args.curvature_coefficient != 0.0) {
        bail!("--max-distance and --curvature-coefficient apply to --light only");
    }
    if !(args.target_height.is_finite() && args.target_height >= 0.0) {
        bail!(
            "--target-height {}: expected a height >= 0 metres",
            args.target_height
        );
    }
    if let Some(md) = args.max_distance {
        if !(md.is_finite() && md > 0.0) {
            bail!("--max-distance {md}: expected a distance > 0 metres");
        }
    }
    if !args.curvature_coefficient.is_finite() {
        bail!("--curvature-coefficient must be a finite number");
    }
    let nv = args.nodata_value;
    if nv == args.visible_value || nv == args.invisible_value {
        bail!(
            "--nodata-value {nv} equals --visible-value or --invisible-value: GDAL would read those cells as no data"
        );
    }
    if args.max_distance.is_some() && nv == args.out_of_range_value {
        bail!("--nodata-value {nv} equals --out-of-range-value: GDAL would read those cells as no data");
    }
    let layout = creation_options::layout(&args.creation_options)?;
    let preview = args
        .preview
        .clone()
        .unwrap_or_else(|| args.out.with_extension("png"));
    let input = Path::new(&args.dem);
    crate::paths::ensure_not_input(&args.out, &[input])?;
    crate::paths::ensure_not_input(&preview, &[input])?;
    let (dem, load_s) = timed(|| dem_arg::load(&args.dem));
    let dem = dem?;
    // The light's grid position, for the curvature and the distances.
    let light_grid = match &args.light {
        Some(s) => {
            let [x, y, _] = numbers::<3>("--light", s)?;
            Some(dem.map_to_grid(x, y))
        }
        None => None,
    };
    let field_dem = match light_grid {
        Some((c, r)) if args.curvature_coefficient != 0.0 => {
            curvature_corrected(&dem, c, r, args.curvature_coefficient)
        }
        _ => dem.clone(),
    };
    let field = HeightField::new(&field_dem).map_err(|e| anyhow::anyhow!("{}: {e}", args.dem))?;
    let (pyramid, pyr_s) = timed(|| MaxMipmap::new(&field));
    let method = match args.method {
        Method::Fast => ShadowMethod::Fast,
        Method::Brute => ShadowMethod::BruteForce,
    };
    let nodata: Vec<bool> = dem.heights.iter().map(|h| h.is_nan()).collect();
    eprintln!(
        "{}: {}x{} grid points, cells {:.2} x {:.2} m, load {:.0} ms, pyramid {:.0} ms",
        args.dem,
        dem.width,
        dem.height,
        field.sx,
        field.sy,
        load_s * 1e3,
        pyr_s * 1e3
    );

    if let Some(spec) = &args.sun_path {
        return sun_path(
            &args, spec, &dem, &field, &pyramid, method, &nodata, &preview, &layout,
        );
    }
    let light = if let Some(s) = &args.light {
        let [x, y, h] = numbers::<3>("--light", s)?;
        let geo = MapWorld::new(&dem, &field);
        let [wx, wy] = geo
            .inside(x, y, "--light")
            .map_err(|e| anyhow::anyhow!(e))?;
        let z = if args.light_elevation {
            h
        } else {
            if h < 0.0 {
                bail!("--light '{s}': the height above the ground must be >= 0 (use --light-elevation for an absolute elevation)");
            }
            let (gx, gy) = geo.world_to_grid(wx, wy);
            field.height_at(gx, gy) + h
        };
        Light::Point([wx, wy, z])
    } else {
        let [az, el] = numbers::<2>("--sun", args.sun.as_deref().unwrap_or_default())?;
        if !(0.0..=90.0).contains(&el) {
            bail!("--sun: the elevation must be between 0 and 90 degrees, got {el}");
        }
        Light::Sun {
            azimuth_deg: az,
            elevation_deg: el,
        }
    };
    let tz = args.target_height;
    let (mask, secs) = compute(&field, &pyramid, &light, method, tz, "shadow mask");
    if args.compare {
        let other = match method {
            ShadowMethod::Fast => ShadowMethod::BruteForce,
            ShadowMethod::BruteForce => ShadowMethod::Fast,
        };
        let (m2, s2) = compute(
            &field,
            &pyramid,
            &light,
            other,
            tz,
            "shadow mask (second method)",
        );
        let differ = mask.iter().zip(&m2).filter(|(a, b)| a != b).count();
        let (fast_s, brute_s) = if method == ShadowMethod::Fast {
            (secs, s2)
        } else {
            (s2, secs)
        };
        eprintln!(
            "compare: fast {:.3} s, brute force {:.3} s ({:.1}x), cells that differ: {differ} of {}",
            fast_s,
            brute_s,
            brute_s / fast_s.max(1e-9),
            mask.len()
        );
        if differ > 0 {
            eprintln!("raykit: the two exact methods disagree: please report this");
        }
    }
    // Each cell's class: lit, shadow, out of range or no data.
    let (sx, sy) = (field.sx, field.sy);
    let out_of_range = |i: usize| match (args.max_distance, light_grid) {
        (Some(md), Some((lc, lr))) => {
            let (c, r) = ((i % dem.width) as f64, (i / dem.width) as f64);
            ((c - lc) * sx).hypot((r - lr) * sy) > md
        }
        _ => false,
    };
    let class: Vec<Cell> = (0..mask.len())
        .map(|i| {
            if nodata[i] {
                Cell::NoData
            } else if out_of_range(i) {
                Cell::OutOfRange
            } else if mask[i] == 1 {
                Cell::Lit
            } else {
                Cell::Shadow
            }
        })
        .collect();
    let lit = class.iter().filter(|&&c| c == Cell::Lit).count();
    let values: Vec<u8> = class
        .iter()
        .map(|c| match c {
            Cell::Lit => args.visible_value,
            Cell::Shadow => args.invisible_value,
            Cell::OutOfRange => args.out_of_range_value,
            Cell::NoData => nv,
        })
        .collect();
    raykit_terrain::io::write_geotiff_u8_with(
        &args.out,
        dem.width,
        dem.height,
        &values,
        &dem.georef,
        Some(nv as f64),
        &layout,
    )?;
    let rgb: Vec<u8> = class
        .iter()
        .flat_map(|c| match c {
            Cell::Lit => [235, 225, 190],
            Cell::Shadow => [40, 45, 70],
            Cell::OutOfRange => [120, 120, 120],
            Cell::NoData => [255, 0, 255],
        })
        .collect();
    raykit_io::write_png(&preview, dem.width as u32, dem.height as u32, &rgb)
        .with_context(|| format!("writing {}", preview.display()))?;
    eprintln!(
        "{:?}: {:.1}% of the grid points lit, {:.3} s ({}) -> {} ({}) and {}",
        light,
        100.0 * lit as f64 / mask.len() as f64,
        secs,
        match method {
            ShadowMethod::Fast => "fast",
            ShadowMethod::BruteForce => "brute force",
        },
        args.out.display(),
        describe(&layout),
        preview.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// What a grid point of the mask is.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Cell {
    Lit,
    Shadow,
    OutOfRange,
    NoData,
}

/// The GeoTIFF layout in words, e.g. "DEFLATE, tiles 256x256".
fn describe(layout: &GeoTiffLayout) -> String {
    match layout.tile {
        Some((w, h)) => format!("{}, tiles {w}x{h}", layout.compression.name()),
        None => format!("{}, strips", layout.compression.name()),
    }
}

#[allow(clippy::too_many_arguments)]
fn sun_path(
    args: &ShadowArgs,
    spec: &str,
    dem: &Dem,
    field: &HeightField,
    pyramid: &MaxMipmap,
    method: ShadowMethod,
    nodata: &[bool],
    preview: &Path,
    layout: &GeoTiffLayout,
) -> Result<ExitCode> {
    let parts: Vec<&str> = spec.split(',').collect();
    let [date, lat, lon] = parts[..] else {
        bail!("--sun-path '{spec}': expected YYYY-MM-DD,LAT,LON");
    };
    let ymd: Vec<&str> = date.split('-').collect();
    let day = match ymd[..] {
        [y, m, d] => match (y.parse::<i32>(), m.parse::<u32>(), d.parse::<u32>()) {
            (Ok(y), Ok(m), Ok(d)) => day_of_year(y, m, d),
            _ => None,
        },
        _ => None,
    }
    .with_context(|| format!("--sun-path '{spec}': '{date}' is not a date YYYY-MM-DD"))?;
    let (lat, lon): (f64, f64) = match (lat.trim().parse(), lon.trim().parse()) {
        (Ok(a), Ok(b)) if (-90.0..=90.0).contains(&a) && (-180.0..=180.0).contains(&b) => (a, b),
        _ => bail!("--sun-path '{spec}': LAT must be in -90..90 and LON in -180..180"),
    };
    if !(args.step_minutes >= 1.0 && args.step_minutes <= 120.0) {
        bail!("--step-minutes must be between 1 and 120");
    }
    let step_h = args.step_minutes / 60.0;
    let times: Vec<f64> = (0..)
        .map(|k| (k as f64 + 0.5) * step_h)
        .take_while(|&t| t < 24.0)
        .filter(|&t| sun_position(day, t, lat, lon).1 > 0.0)
        .collect();
    let mut hours = vec![0.0f32; field.width * field.height];
    let bar = ProgressBar::new(times.len() as u64).with_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} sun positions [{elapsed}<{eta}]")
            .expect("valid template"),
    );
    let (_, secs) = timed(|| {
        for &t in &times {
            let (az, el) = sun_position(day, t, lat, lon);
            let light = Light::Sun {
                azimuth_deg: az,
                elevation_deg: el,
            };
            let mask = shadow_mask_for_targets(
                field,
                pyramid,
                &light,
                method,
                args.target_height,
                &|_| {},
            );
            for (h, &m) in hours.iter_mut().zip(&mask) {
                *h += m as f32 * step_h as f32;
            }
            bar.inc(1);
        }
    });
    bar.finish_and_clear();
    for (h, &nd) in hours.iter_mut().zip(nodata) {
        if nd {
            *h = f32::NAN;
        }
    }
    raykit_terrain::io::write_geotiff_f32_with(
        &args.out,
        dem.width,
        dem.height,
        &hours,
        &dem.georef,
        Some(-9999.0),
        layout,
    )?;
    let max = hours
        .iter()
        .copied()
        .filter(|h| !h.is_nan())
        .fold(0.0f32, f32::max);
    let day_len = times.len() as f64 * step_h;
    let rgb: Vec<u8> = hours
        .iter()
        .flat_map(|&h| {
            if h.is_nan() {
                return [255, 0, 255];
            }
            let f = if day_len > 0.0 {
                (h as f64 / day_len).clamp(0.0, 1.0)
            } else {
                0.0
            };
            [
                (30.0 + 225.0 * f) as u8,
                (30.0 + 200.0 * f) as u8,
                (80.0 + 60.0 * f) as u8,
            ]
        })
        .collect();
    raykit_io::write_png(preview, dem.width as u32, dem.height as u32, &rgb)
        .with_context(|| format!("writing {}", preview.display()))?;
    eprintln!(
        "sun path day {day} at ({lat}, {lon}): {} positions above the horizon ({:.1} h of daylight), most sun on a cell {:.1} h, {:.2} s -> {} and {}",
        times.len(),
        day_len,
        max,
        secs,
        args.out.display(),
        preview.display()
    );
    Ok(ExitCode::SUCCESS)
}
