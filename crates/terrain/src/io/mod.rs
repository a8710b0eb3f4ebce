//! Reading and writing DEM files: GeoTIFF (read and write), Esri ASCII
//! grids, SRTM `.hgt`, Terragen `.ter`, grayscale PNG and raw grids, with
//! [`load_dem`] choosing by extension. Every failure is a [`DemError`] naming the file, the
//! position in it and what was expected; no input makes a reader panic.

mod ascii_grid;
mod creation_options;
mod crs_sidecar;
mod error;
mod file_at;
mod gdal_mask;
mod gdal_metadata;
mod geokeys;
mod geotiff_blocks;
mod geotiff_layout;
mod geotiff_lzw_tiles;
mod geotiff_read;
mod geotiff_sparse;
mod geotiff_write;
mod hgt;
mod limits;
mod load;
mod nodata;
mod png;
mod raw;
mod samples;
mod source;
mod terragen;
mod tiff_header;

pub use ascii_grid::read_ascii_grid;
pub use creation_options::layout_from_creation_options;
pub use crs_sidecar::{
    crs_sidecar_path, read_crs_sidecar, remove_crs_sidecar, wkt_is_geographic, write_crs_sidecar,
};
pub use error::DemError;
pub use geokeys::{
    geo_key_short, linear_unit_not_metre, KEY_MODEL_TYPE, KEY_PROJ_LINEAR_UNITS, KEY_RASTER_TYPE,
};
pub use geotiff_blocks::TileSample;
pub use geotiff_layout::{GeoTiffLayout, TiffCompression};
pub use geotiff_read::{
    read_geotiff, TAG_GDAL_NODATA, TAG_GEO_ASCII_PARAMS, TAG_GEO_DOUBLE_PARAMS,
    TAG_GEO_KEY_DIRECTORY, TAG_MODEL_PIXEL_SCALE, TAG_MODEL_TIEPOINT, TAG_MODEL_TRANSFORMATION,
};
pub use geotiff_write::{
    write_dem_geotiff, write_geotiff_f32, write_geotiff_f32_with, write_geotiff_u8,
    write_geotiff_u8_with,
};
pub use hgt::{parse_hgt_name, read_hgt, HGT_VOID};
pub use limits::{check_dimensions, MAX_SAMPLES, MAX_SIDE};
pub use load::{load_dem, LoadOptions, RawSpec, SUPPORTED_EXTENSIONS};
pub use nodata::{nodata_as_f32, nodata_text, NodataF32};
pub use png::read_png;
pub use raw::{read_raw, RawType};
pub use source::{load_dem_source, FRACTAL_PREFIX};
pub use terragen::read_ter;
