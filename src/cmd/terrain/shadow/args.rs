//! The arguments of `raykit terrain shadow`.

use clap::{Args, ValueEnum};
use std::path::PathBuf;

/// Which algorithm.
#[derive(Clone, Copy, ValueEnum)]
pub enum Method {
    /// A point light over the grid: a horizon sweep outward from the light,
    /// with the segment test for the points it leaves; a sun: each segment
    /// through the min/max quadtree (default).
    Fast,
    /// Each segment marched cell by cell (brute force).
    Brute,
}

/// Arguments of `raykit terrain shadow`.
#[derive(Args)]
#[command(after_help = "Exactly one of --light, --sun, --sun-path.\n\n\
The surface is the DEM's grid points joined as two triangles per cell. A grid point is lit when the\n\
segment from the surface there to the light neither crosses the surface nor leaves either end into\n\
the ground: a light on the ground (H = 0) sees along slopes but not through the hill it stands on,\n\
and a slope facing away from the sun is in shadow. Map coordinates\n\
are in the DEM's own units (metres for projected rasters, degrees for SRTM .hgt).\n\n\
Output values (gdal_viewshed's -vv, -iv, -ov, -a_nodata): --visible-value (default 1),\n\
--invisible-value (0), --out-of-range-value (0) for cells beyond --max-distance, --nodata-value\n\
(255, or the highest value the others leave free) where the DEM has no data. The GeoTIFF is\n\
DEFLATE-compressed in strips unless --co says otherwise (--co COMPRESS=DEFLATE|LZW|PACKBITS|NONE,\n\
--co TILED=YES, --co BLOCKXSIZE=N).\n\
Unlike gdal_viewshed, the output always covers the whole DEM, and the curvature coefficient is 0\n\
(a flat earth, exact for the declared surface) unless given; gdal_viewshed's default is 0.85714.\n\
The long options have gdal-like aliases: --vv, --iv, --ov, --tz, --md, --cc.\n\n\
Examples:\n  raykit terrain shadow dem.tif --light 429452,5150685,10 --out mask.tif\n  \
raykit terrain shadow dem.tif --light 429452,5150685,10 --vv 255 --tz 2 --md 5000 --cc 0.85714 \\\n      \
--co TILED=YES --out viewshed.tif\n  \
raykit terrain shadow N57E011.hgt --sun 135,20 --out sun.tif --preview sun.png\n  \
raykit terrain shadow dem.tif --sun-path 2026-06-21,45.5,-93.2 --out hours.tif\n  \
raykit terrain shadow fractal:2048 --light 10000,10000,50 --compare --out m.tif")]
pub struct ShadowArgs {
    /// DEM: GeoTIFF, Esri ASCII grid (.asc), SRTM .hgt, Terragen .ter, 16-bit PNG, raw .r16/.r32, or fractal:SIZE[:SEED].
    pub(super) dem: String,
    /// Point light X,Y,H: map position and height above the ground there (gdal_viewshed's -ox -oy -oz).
    #[arg(long, value_name = "X,Y,H", allow_hyphen_values = true)]
    pub(super) light: Option<String>,
    /// With --light: H is an absolute elevation, not a height above the ground.
    #[arg(long)]
    pub(super) light_elevation: bool,
    /// Directional light AZIMUTH,ELEVATION in degrees (azimuth clockwise from north).
    #[arg(long, value_name = "AZ,EL", allow_hyphen_values = true)]
    pub(super) sun: Option<String>,
    /// Hours of direct sun per cell over a day: YYYY-MM-DD,LAT,LON (UTC day, output float32 hours).
    #[arg(long, value_name = "DATE,LAT,LON", allow_hyphen_values = true)]
    pub(super) sun_path: Option<String>,
    /// Minutes between sun positions for --sun-path.
    #[arg(long, default_value_t = 10.0, requires = "sun_path")]
    pub(super) step_minutes: f64,
    /// Algorithm (both are exact and give identical masks).
    #[arg(long, value_enum, default_value_t = Method::Fast)]
    pub(super) method: Method,
    /// Run both algorithms, report their times and the cells on which they differ.
    #[arg(long, conflicts_with = "sun_path")]
    pub(super) compare: bool,
    /// Height above the ground of the target at every grid point, metres
    /// (gdal_viewshed's -tz): a cell is lit when the light sees that point.
    #[arg(
        long,
        visible_alias = "tz",
        default_value_t = 0.0,
        value_name = "METRES"
    )]
    pub(super) target_height: f64,
    /// With --light: cells farther than this from the light, horizontally in
    /// metres, get --out-of-range-value (gdal_viewshed's -md).
    #[arg(long, visible_alias = "md", value_name = "METRES")]
    pub(super) max_distance: Option<f64>,
    /// With --light: lower every height by COEFF · d² / earth diameter, d the
    /// horizontal distance from the light (curvature and refraction,
    /// gdal_viewshed's -cc; 1 is curvature alone, 0.85714 gdal's default).
    #[arg(
        long,
        visible_alias = "cc",
        default_value_t = 0.0,
        value_name = "COEFF"
    )]
    pub(super) curvature_coefficient: f64,
    /// Mask value of lit cells (gdal_viewshed's -vv).
    #[arg(
        long,
        visible_alias = "vv",
        default_value_t = 1,
        value_name = "0-255",
        conflicts_with = "sun_path"
    )]
    pub(super) visible_value: u8,
    /// Mask value of cells in shadow (gdal_viewshed's -iv).
    #[arg(
        long,
        visible_alias = "iv",
        default_value_t = 0,
        value_name = "0-255",
        conflicts_with = "sun_path"
    )]
    pub(super) invisible_value: u8,
    /// Mask value of cells beyond --max-distance (gdal_viewshed's -ov).
    #[arg(
        long,
        visible_alias = "ov",
        default_value_t = 0,
        value_name = "0-255",
        conflicts_with = "sun_path"
    )]
    pub(super) out_of_range_value: u8,
    /// Mask value, declared as the GeoTIFF's nodata, where the DEM has no data
    /// (gdal_viewshed's -a_nodata); default 255, or the highest value the
    /// other values leave free.
    #[arg(long, value_name = "0-255", conflicts_with = "sun_path")]
    pub(super) nodata_value: Option<u8>,
    /// GeoTIFF creation option KEY=VALUE, repeatable (gdal's -co):
    /// COMPRESS=DEFLATE|LZW|PACKBITS|NONE (default DEFLATE), TILED=YES|NO,
    /// BLOCKXSIZE=N, BLOCKYSIZE=N (tile size, default 256).
    #[arg(long = "co", value_name = "KEY=VALUE", action = clap::ArgAction::Append)]
    pub(super) creation_options: Vec<String>,
    /// Output GeoTIFF (mask: --visible-value, --invisible-value, ...; sun
    /// path: float32 hours).
    #[arg(long)]
    pub(super) out: PathBuf,
    /// PNG preview (default: OUT with .png).
    #[arg(long)]
    pub(super) preview: Option<PathBuf>,
}
