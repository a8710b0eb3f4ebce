//! `raykit terrain shadow`: where a point light or the sun is visible from
//! the ground (Min's (2008) terrain shadow map), exact for the declared
//! surface, written as a GeoTIFF with the DEM's georeferencing and a PNG
//! preview; or hours of direct sun per cell over a day. The options follow
//! gdal_viewshed where the meaning is the same (values of visible,
//! invisible, out-of-range and no-data cells, target height, maximum
//! distance, curvature coefficient, creation options).

mod args;
mod sun_path;

use args::Method;
pub use args::ShadowArgs;
use sun_path::sun_path;

use super::dem_arg::{self, numbers};
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_lab::measure::timed;
use raykit_terrain::curvature::curvature_corrected;
use raykit_terrain::georef::{format_number, MapWorld};
use raykit_terrain::io::layout_from_creation_options;
use raykit_terrain::mask_cells::{MaskClasses, MaskValues, Preview, Range, PREVIEW_PALETTE};
use raykit_terrain::shadow::{shadow_mask_for_targets, Light, ShadowMethod};
use raykit_terrain::{HeightField, MaxMipmap};
use rayon::prelude::*;
use std::path::Path;
use std::process::ExitCode;

/// The mask of one light, timed, with a progress bar; the fast method
/// builds the min/max quadtree only if this light needs it.
fn compute(
    field: &HeightField,
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
        shadow_mask_for_targets(field, None, light, method, target_height, &|n| {
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
    // Values GDAL must not read as no data: lit, shadow, and out of range
    // when there is a range.
    let taken = |v: u8| {
        v == args.visible_value
            || v == args.invisible_value
            || (args.max_distance.is_some() && v == args.out_of_range_value)
    };
    let nv = match args.nodata_value {
        Some(nv) => nv,
        None => (0..=255u8)
            .rev()
            .find(|&v| !taken(v))
            .expect("three values leave one of 256 free"),
    };
    if nv == args.visible_value || nv == args.invisible_value {
        bail!(
            "--nodata-value {nv} equals --visible-value or --invisible-value: GDAL would read those cells as no data"
        );
    }
    if args.max_distance.is_some() && nv == args.out_of_range_value {
        bail!("--nodata-value {nv} equals --out-of-range-value: GDAL would read those cells as no data");
    }
    let layout =
        layout_from_creation_options(&args.creation_options).map_err(anyhow::Error::msg)?;
    let preview = args
        .preview
        .clone()
        .unwrap_or_else(|| args.out.with_extension("png"));
    let input = Path::new(&args.dem);
    crate::paths::ensure_extension(&args.out, "--out (a GeoTIFF)", &["tif", "tiff"])?;
    crate::paths::ensure_extension(&preview, "--preview (a PNG)", &["png"])?;
    crate::paths::ensure_output(&args.out, &[input])?;
    crate::paths::ensure_output(&preview, &[input])?;
    crate::paths::ensure_distinct(&args.out, &preview, "--out", "--preview")?;
    let (dem, load_s) = timed(|| dem_arg::load(&args.dem));
    let mut dem = dem?;
    // The light's grid position, for the curvature and the distances.
    let light_grid = match &args.light {
        Some(s) => {
            let [x, y, _] = numbers::<3>("--light", s)?;
            Some(dem.map_to_grid(x, y))
        }
        None => None,
    };
    // Where the DEM has no data: none when it has data everywhere.
    // Both passes go a chunk at a time with plain loops, which compile to
    // vector operations.
    const CHUNK: usize = 1 << 16;
    let nodata: Option<Vec<bool>> = dem
        .heights
        .par_chunks(CHUNK)
        .any(|c| c.iter().fold(false, |any, h| any | h.is_nan()))
        .then(|| {
            let mut nodata = vec![false; dem.heights.len()];
            nodata
                .par_chunks_mut(CHUNK)
                .zip(dem.heights.par_chunks(CHUNK))
                .for_each(|(n, h)| n.iter_mut().zip(h).for_each(|(n, h)| *n = h.is_nan()));
            nodata
        });
    // The DEM's heights move into the surface (its grid and georeferencing
    // stay), unless the curvature makes new ones.
    let field = match light_grid {
        Some((c, r)) if args.curvature_coefficient != 0.0 => {
            let cc = args.curvature_coefficient;
            HeightField::new(&curvature_corrected(&dem, c, r, cc)).map_err(|e| {
                let cc = raykit_terrain::georef::format_number(cc);
                anyhow::anyhow!("{}, lowered by --curvature-coefficient {cc}: {e}", args.dem)
            })
        }
        _ => HeightField::take(&mut dem).map_err(|e| anyhow::anyhow!("{}: {e}", args.dem)),
    }?;
    let method = match args.method {
        Method::Fast => ShadowMethod::Fast,
        Method::Brute => ShadowMethod::BruteForce,
    };
    let unit = raykit_terrain::io::linear_unit_not_metre(&dem.georef.geo_keys);
    eprintln!(
        "{}: {}x{} grid points, cells {:.2} x {:.2} {}, load {:.0} ms",
        args.dem,
        dem.width,
        dem.height,
        field.sx,
        field.sy,
        unit.as_deref().unwrap_or("m"),
        load_s * 1e3,
    );
    if let Some(unit) = &unit {
        eprintln!(
            "note: the map's coordinates are in {unit}; the grid is taken in its own units, \
             so heights, --light's height, --tz and --md are read in them too \
             (--curvature-coefficient assumes metres)"
        );
    }

    if let Some(spec) = &args.sun_path {
        let (pyramid, pyr_s) = timed(|| MaxMipmap::new(&field));
        eprintln!("min/max quadtree {:.0} ms", pyr_s * 1e3);
        let nodata = nodata.unwrap_or_else(|| vec![false; field.heights.len()]);
        return sun_path(
            &args, spec, &dem, &field, &pyramid, method, &nodata, &preview, &layout,
        );
    }
    // What the summary line calls the light, in the user's map coordinates.
    let named;
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
            let no_ground = nodata.as_ref().and_then(|nodata| {
                field
                    .samples_under(gx, gy)
                    .find(|&(c, r)| nodata[r * dem.width + c])
            });
            if let Some((col, row)) = no_ground {
                bail!("--light '{s}': the ground there has no data (no height at row {row}, column {col}); give the light's elevation with --light-elevation");
            }
            field.height_at(gx, gy) + h
        };
        let z_text = if z.abs() < 1e15 {
            format!("{z:.2}")
        } else {
            format_number(z)
        };
        named = format!("point light at {x}, {y}, elevation {z_text} m");
        Light::Point([wx, wy, z])
    } else {
        let [az, el] = numbers::<2>("--sun", args.sun.as_deref().unwrap_or_default())?;
        if !(0.0..=90.0).contains(&el) {
            bail!(
                "--sun: the elevation must be between 0 and 90 degrees, got {}",
                format_number(el)
            );
        }
        named = format!(
            "sun at azimuth {}°, elevation {}°",
            format_number(az),
            format_number(el)
        );
        Light::Sun {
            azimuth_deg: az,
            elevation_deg: el,
        }
    };
    let tz = args.target_height;
    let (mask, secs) = compute(&field, &light, method, tz, "shadow mask");
    if args.compare {
        let other = match method {
            ShadowMethod::Fast => ShadowMethod::BruteForce,
            ShadowMethod::BruteForce => ShadowMethod::Fast,
        };
        let (m2, s2) = compute(&field, &light, other, tz, "shadow mask (second method)");
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
    let range = match (args.max_distance, light_grid) {
        (Some(max_distance), Some(light_grid)) => Some(Range {
            light_grid,
            cell: (field.sx, field.sy),
            max_distance,
        }),
        _ => None,
    };
    let mask_values = MaskValues {
        visible: args.visible_value,
        invisible: args.invisible_value,
        out_of_range: args.out_of_range_value,
        nodata: nv,
    };
    let classes = MaskClasses {
        nodata: nodata.as_deref(),
        width: dem.width,
        range: range.as_ref(),
    };
    let cells = mask.len();
    let mut values = mask;
    let rasters = classes.write_values(&mut values, &mask_values);
    let (palette, indices) = match &rasters.preview {
        Preview::ByValue(palette) => (&palette[..], &values),
        Preview::Indices(indices) => (&PREVIEW_PALETTE[..], indices),
    };
    // The GeoTIFF and the preview, side by side.
    let (tif, png) = rayon::join(
        || {
            raykit_terrain::io::write_geotiff_u8_with(
                &args.out,
                dem.width,
                dem.height,
                &values,
                &dem.georef,
                Some(nv as f64),
                &layout,
            )
        },
        || {
            let (w, h) = (dem.width as u32, dem.height as u32);
            raykit_io::write_png_indexed(&preview, w, h, palette, indices)
                .with_context(|| format!("writing {}", preview.display()))
        },
    );
    tif?;
    png?;
    // Points without data are neither lit nor in shadow.
    let without_data = nodata
        .as_deref()
        .map_or(0, |n| n.iter().filter(|&&b| b).count());
    let with_data = (cells - without_data).max(1);
    eprintln!(
        "{named}: {:.1}% of the grid points with data lit, {:.3} s ({}) -> {} ({}) and {}",
        100.0 * rasters.lit as f64 / with_data as f64,
        secs,
        match method {
            ShadowMethod::Fast => "fast",
            ShadowMethod::BruteForce => "brute force",
        },
        args.out.display(),
        layout.describe(),
        preview.display()
    );
    Ok(ExitCode::SUCCESS)
}
