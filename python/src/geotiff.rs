//! `write_geotiff`: a `(rows, cols)` uint8 or float32 grid as a
//! single-band GeoTIFF (raykit-terrain's writer, atomic), placed like a DEM.

use crate::errors::{dem_error, value_error};
use crate::threads::detached;
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use raykit_terrain::io::{load_dem, write_geotiff_f32, write_geotiff_u8, LoadOptions};
use raykit_terrain::GeoRef;
use std::path::PathBuf;

/// Write `values` (`(rows, cols)` uint8 or float32) to `path` as a GeoTIFF.
/// Its georeferencing is that of the DEM file `like` (transform and every
/// GeoTIFF key, so the coordinate reference system too), whose grid must
/// have the same shape; without `like`, rasterio's north-up `transform`
/// `(a, b, c, d, e, f)` places it, in degrees when `geographic`.
#[pyfunction]
#[pyo3(signature = (path, values, transform=None, geographic=false, nodata=None, like=None))]
pub fn write_geotiff(
    py: Python<'_>,
    path: PathBuf,
    values: &Bound<'_, PyAny>,
    transform: Option<(f64, f64, f64, f64, f64, f64)>,
    geographic: bool,
    nodata: Option<f64>,
    like: Option<PathBuf>,
) -> PyResult<()> {
    let (rows, cols) = match values.extract::<PyReadonlyArray2<'_, u8>>() {
        Ok(a) => (a.shape()[0], a.shape()[1]),
        Err(_) => {
            let a: PyReadonlyArray2<'_, f32> = values
                .extract()
                .map_err(|_| value_error("values must be a 2-D uint8 or float32 array"))?;
            (a.shape()[0], a.shape()[1])
        }
    };
    let georef = match (&like, transform) {
        (Some(dem_path), _) => {
            // On this process's all-cores pool: the reader is parallel.
            let dem = detached(py, 0, || load_dem(dem_path, &LoadOptions::default()))?
                .map_err(dem_error)?;
            if (dem.height, dem.width) != (rows, cols) {
                return Err(value_error(format!(
                    "{}: its grid is {} x {} (rows x cols), the values are {rows} x {cols}",
                    dem_path.display(),
                    dem.height,
                    dem.width
                )));
            }
            dem.georef
        }
        (None, Some((a, b, c, d, e, f))) => {
            if b != 0.0 || d != 0.0 || !(a > 0.0 && e < 0.0) {
                return Err(value_error(format!(
                    "transform ({a}, {b}, {c}, {d}, {e}, {f}): expected a north-up raster, b = d = 0, a > 0, e < 0"
                )));
            }
            GeoRef {
                origin_x: c,
                origin_y: f,
                pixel_width: a,
                pixel_height: e,
                geographic,
                ..GeoRef::default()
            }
        }
        (None, None) => return Err(value_error("write_geotiff needs transform or like")),
    };
    if let Ok(a) = values.extract::<PyReadonlyArray2<'_, u8>>() {
        let data = a.as_array().iter().copied().collect::<Vec<u8>>();
        detached(py, 0, || {
            write_geotiff_u8(&path, cols, rows, &data, &georef, nodata)
        })?
        .map_err(dem_error)
    } else {
        let a: PyReadonlyArray2<'_, f32> = values.extract()?;
        let data = a.as_array().iter().copied().collect::<Vec<f32>>();
        detached(py, 0, || {
            write_geotiff_f32(&path, cols, rows, &data, &georef, nodata)
        })?
        .map_err(dem_error)
    }
}
