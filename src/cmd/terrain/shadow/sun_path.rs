//! `raykit terrain shadow --sun-path`: hours of direct sun per cell over a
//! day, as a float32 GeoTIFF and a PNG preview.

use super::args::ShadowArgs;
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_lab::measure::timed;
use raykit_terrain::io::GeoTiffLayout;
use raykit_terrain::shadow::ShadowMethod;
use raykit_terrain::sun::day_of_year;
use raykit_terrain::sun_hours::{sun_hours, SunDay};
use raykit_terrain::{Dem, HeightField, MaxMipmap};
use std::path::Path;
use std::process::ExitCode;

/// Hours of sun for `--sun-path SPEC`, written to `--out` and `preview`.
#[allow(clippy::too_many_arguments)]
pub fn sun_path(
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
    let sun_day = SunDay {
        day,
        lat,
        lon,
        step_hours: args.step_minutes / 60.0,
    };
    let bar = ProgressBar::new(sun_day.times().len() as u64).with_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} sun positions [{elapsed}<{eta}]")
            .expect("valid template"),
    );
    let (hours, secs) = timed(|| {
        sun_hours(
            field,
            pyramid,
            method,
            args.target_height,
            &sun_day,
            nodata,
            &|| bar.inc(1),
        )
    });
    bar.finish_and_clear();
    raykit_terrain::io::write_geotiff_f32_with(
        &args.out,
        dem.width,
        dem.height,
        &hours.hours,
        &dem.georef,
        Some(-9999.0),
        layout,
    )?;
    let rgb = hours.preview();
    raykit_io::write_png(preview, dem.width as u32, dem.height as u32, &rgb)
        .with_context(|| format!("writing {}", preview.display()))?;
    eprintln!(
        "sun path day {day} at ({lat}, {lon}): {} positions above the horizon ({:.1} h of daylight), most sun on a cell {:.1} h, {:.2} s -> {} and {}",
        hours.positions,
        hours.day_hours,
        hours.max(),
        secs,
        args.out.display(),
        preview.display()
    );
    Ok(ExitCode::SUCCESS)
}
