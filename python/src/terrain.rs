//! Terrain from numpy height grids: the DEM with its affine transform
//! (rasterio's `Affine(a, b, c, d, e, f)`: x = a·col + b·row + c,
//! y = d·col + e·row + f at pixel corners), shadow masks and ray-cast
//! images (raykit-terrain).

use crate::arrays::c_order;
use crate::errors::{dem_error, value_error};
use crate::threads::detached;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use raykit_terrain::camera::{centre, default_camera};
use raykit_terrain::georef::{format_number, MapWorld};
use raykit_terrain::io::{load_dem as read_dem, LoadOptions};
use raykit_terrain::shadow::{shadow_mask_for_targets, Light, ShadowMethod};
use raykit_terrain::view::{cast_image, Caster};
use raykit_terrain::{Dem, GeoRef, HeightField, MaxMipmap, TerrainCamera};
use std::path::PathBuf;

/// The six terms of rasterio's affine transform.
type Transform = (f64, f64, f64, f64, f64, f64);

/// Largest image side `cast` (and so `render`) accepts: the per-pixel
/// buffers of an 8192 × 8192 image take a few GiB; a 16384 one four times
/// as much.
const MAX_SIDE: u32 = 8192;

/// A DEM file's heights (NaN where no data), transform, whether its map
/// units are degrees, and its nodata value.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn load_dem(
    py: Python<'_>,
    path: PathBuf,
) -> PyResult<(Bound<'_, PyArray2<f32>>, Transform, bool, Option<f64>)> {
    // On this process's all-cores pool: the GeoTIFF reader is parallel.
    let dem = detached(py, 0, || read_dem(&path, &LoadOptions::default()))?.map_err(dem_error)?;
    let g = &dem.georef;
    let transform = (
        g.pixel_width,
        0.0,
        g.origin_x,
        0.0,
        g.pixel_height,
        g.origin_y,
    );
    let (geographic, nodata) = (g.geographic, dem.nodata);
    let heights = Array2::from_shape_vec((dem.height, dem.width), dem.heights)
        .expect("width × height samples");
    Ok((heights.into_pyarray(py), transform, geographic, nodata))
}

/// The DEM of a `(rows, cols)` height grid placed by `transform`.
fn dem(heights: &PyReadonlyArray2<'_, f32>, t: Transform, geographic: bool) -> PyResult<Dem> {
    let (a, b, c, d, e, f) = t;
    let n = format_number;
    let named = format!(
        "transform ({}, {}, {}, {}, {}, {})",
        n(a),
        n(b),
        n(c),
        n(d),
        n(e),
        n(f)
    );
    if b != 0.0 || d != 0.0 {
        return Err(value_error(format!(
            "rotated or sheared transform (terms b = {}, d = {}); expected a north-up \
             transformation with zero rotation terms",
            n(b),
            n(d)
        )));
    }
    if !(a > 0.0 && e < 0.0 && a.is_finite() && e.is_finite() && c.is_finite() && f.is_finite()) {
        return Err(value_error(format!(
            "{named}: expected a north-up raster, a > 0 and \
             e < 0 (columns east, rows south)"
        )));
    }
    let shape = heights.shape();
    let (rows, cols) = (shape[0], shape[1]);
    let (x1, y1) = (c + a * cols as f64, f + e * rows as f64);
    if !(x1.is_finite() && y1.is_finite() && c + a != c && f + e != f) {
        return Err(value_error(format!(
            "{named}: the pixel size is too small to tell \
             neighbouring pixels apart at the origin, or the {cols} x {rows} grid reaches \
             beyond the largest coordinates"
        )));
    }
    let values = c_order(heights, "heights")?.to_vec();
    let mut dem = Dem::from_heights(cols, rows, values);
    dem.georef = GeoRef {
        origin_x: c,
        origin_y: f,
        pixel_width: a,
        pixel_height: e,
        geographic,
        ..GeoRef::default()
    };
    Ok(dem)
}

/// The DEM of a `(rows, cols)` height grid placed by `transform`, and its
/// surface, which takes the DEM's copy of the heights: one copy of the
/// caller's array, not two (the DEM keeps its grid and georeferencing).
fn surface(
    py: Python<'_>,
    heights: &PyReadonlyArray2<'_, f32>,
    t: Transform,
    geographic: bool,
    threads: i64,
) -> PyResult<(Dem, HeightField)> {
    let mut dem = dem(heights, t, geographic)?;
    // Infinite heights and absurd cell sizes are refused here, by name.
    // On the call's pool: the height range and the fill of missing
    // heights are parallel passes over the grid.
    let field = detached(py, threads, || HeightField::take(&mut dem))?.map_err(value_error)?;
    Ok((dem, field))
}

/// Per grid point 1 where the light is visible from the surface, 0 in
/// shadow, 255 where the DEM has no data (NaN), as `raykit terrain
/// shadow` writes it. Exactly one of `sun` (azimuth, elevation in
/// degrees) and `light` (map x, y and the height above the ground, or
/// with `light_elevation` the absolute elevation). With `observer`, the
/// light is a viewshed's observer and errors name it so.
#[pyfunction]
#[pyo3(signature = (heights, transform, geographic=false, sun=None, light=None, light_elevation=false, method="fast", threads=0, observer=false))]
#[allow(clippy::too_many_arguments)]
pub fn shadow<'py>(
    py: Python<'py>,
    heights: PyReadonlyArray2<'py, f32>,
    transform: Transform,
    geographic: bool,
    sun: Option<(f64, f64)>,
    light: Option<(f64, f64, f64)>,
    light_elevation: bool,
    method: &str,
    threads: i64,
    observer: bool,
) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let method = match method {
        "fast" => ShadowMethod::Fast,
        "brute" => ShadowMethod::BruteForce,
        _ => {
            return Err(value_error(format!(
                "unknown method '{method}'; expected fast or brute"
            )))
        }
    };
    let (dem, field) = surface(py, &heights, transform, geographic, threads)?;
    let given = heights.as_slice().expect("C-contiguous, as dem() checked");
    let light = match (sun, light) {
        (Some((az, el)), None) => {
            if light_elevation {
                return Err(value_error("light_elevation applies to light only"));
            }
            if !(0.0..=90.0).contains(&el) {
                return Err(value_error(format!(
                    "sun: the elevation must be between 0 and 90 degrees, got {}",
                    format_number(el)
                )));
            }
            if !az.is_finite() {
                return Err(value_error(format!(
                    "sun: the azimuth must be a finite number of degrees, got {}",
                    format_number(az)
                )));
            }
            Light::Sun {
                azimuth_deg: az,
                elevation_deg: el,
            }
        }
        (None, Some(at)) => {
            point_light(&dem, &field, given, at, light_elevation, observer).map_err(value_error)?
        }
        _ => return Err(value_error("give exactly one of sun, light")),
    };
    let mask = detached(py, threads, || {
        // The quadtree is built only if the light needs it.
        let mut mask = shadow_mask_for_targets(&field, None, &light, method, 0.0, &|_| {});
        use rayon::prelude::*;
        // No data where the caller's heights are NaN, a chunk at a time.
        const CHUNK: usize = 1 << 16;
        mask.par_chunks_mut(CHUNK)
            .zip(given.par_chunks(CHUNK))
            .for_each(|(m, h)| {
                for (m, h) in m.iter_mut().zip(h) {
                    if h.is_nan() {
                        *m = 255;
                    }
                }
            });
        mask
    })?;
    let mask = Array2::from_shape_vec((dem.height, dem.width), mask).expect("one per sample");
    Ok(mask.into_pyarray(py))
}

/// The point light at map position (`x`, `y`), `h` metres above the
/// declared surface (or at elevation `h` with `light_elevation`), in world
/// metres; `given` are the caller's heights, NaN where no data. With
/// `observer`, the light is a viewshed's observer and errors name it so.
/// Refused: outside the grid points, a height that is not finite, below
/// the ground, or over no data without `light_elevation`.
fn point_light(
    dem: &Dem,
    field: &HeightField,
    given: &[f32],
    (x, y, h): (f64, f64, f64),
    light_elevation: bool,
    observer: bool,
) -> Result<Light, String> {
    let (what, elevation_flag) = match observer {
        true => ("observer", "observer_elevation"),
        false => ("light", "light_elevation"),
    };
    let n = format_number;
    let named = format!("{what} ({}, {}, {})", n(x), n(y), n(h));
    let [wx, wy] = MapWorld::new(dem, field).inside(x, y, what)?;
    if !h.is_finite() {
        return Err(format!("{named}: the height must be a finite number"));
    }
    let z = if light_elevation {
        h
    } else {
        if h < 0.0 {
            return Err(format!(
                "{named}: the height above the ground must be >= 0 \
                 (use {elevation_flag}=True for an absolute elevation)"
            ));
        }
        let (gx, gy) = (wx / field.sx, -wy / field.sy);
        if let Some((col, row)) = field
            .samples_under(gx, gy)
            .find(|&(c, r)| given[r * dem.width + c].is_nan())
        {
            return Err(format!(
                "{named}: the ground there has no data (no height at row \
                 {row}, column {col}); give the elevation itself with {elevation_flag}=True"
            ));
        }
        field.height_at(gx, gy) + h
    };
    Ok(Light::Point([wx, wy, z]))
}

/// Checks point lights as [`shadow`] would, without computing a mask: the
/// first that it would refuse raises its `ValueError`, prefixed with
/// `observers[i]: ` (with `observer`) or `lights[i]: `. One surface serves
/// every light.
#[pyfunction]
#[pyo3(signature = (heights, transform, lights, geographic=false, light_elevation=false, observer=false))]
pub fn check_lights(
    py: Python<'_>,
    heights: PyReadonlyArray2<'_, f32>,
    transform: Transform,
    lights: Vec<(f64, f64, f64)>,
    geographic: bool,
    light_elevation: bool,
    observer: bool,
) -> PyResult<()> {
    let (dem, field) = surface(py, &heights, transform, geographic, 0)?;
    let given = heights.as_slice().expect("C-contiguous, as dem() checked");
    let list = if observer { "observers" } else { "lights" };
    for (i, &at) in lights.iter().enumerate() {
        point_light(&dem, &field, given, at, light_elevation, observer)
            .map_err(|e| value_error(format!("{list}[{i}]: {e}")))?;
    }
    Ok(())
}

/// The views `raykit terrain render` takes without coordinates, in map
/// coordinates (x, y in map units, z in metres): the default camera's
/// eye and target (`camera::default_camera`: the eye 3/4 of the way from
/// the centre to the south-west grid point, looking 20° down towards the
/// centre) and the surface point at the centre grid position, which an
/// eye given without a target looks at.
#[pyfunction]
#[pyo3(signature = (heights, transform, geographic=false))]
#[allow(clippy::type_complexity)]
pub fn default_views(
    py: Python<'_>,
    heights: PyReadonlyArray2<'_, f32>,
    transform: Transform,
    geographic: bool,
) -> PyResult<([f64; 3], [f64; 3], [f64; 3])> {
    let (dem, field) = surface(py, &heights, transform, geographic, 0)?;
    let map = MapWorld::new(&dem, &field);
    let (eye, target) = default_camera(&field);
    Ok((
        map.to_map(eye),
        map.to_map(target),
        map.to_map(centre(&field)),
    ))
}

/// One ray per pixel of a pinhole camera at map position `eye` looking at
/// `target` (z in metres), cast on the declared surface: a dict of `t`
/// (metres, inf on a miss), `col` and `row` of the hit cell (-1 on a
/// miss), `steps` per ray, the unit world `directions` (x east, y north,
/// z up), the eye in world metres from grid point (0, 0) and the cell size.
#[pyfunction]
#[pyo3(signature = (heights, transform, eye, target, geographic=false, fov=50.0, width=1600, height=900, caster="boxes", tau=16.0, threads=0))]
#[allow(clippy::too_many_arguments)]
pub fn cast<'py>(
    py: Python<'py>,
    heights: PyReadonlyArray2<'py, f32>,
    transform: Transform,
    eye: [f64; 3],
    target: [f64; 3],
    geographic: bool,
    fov: f64,
    width: u32,
    height: u32,
    caster: &str,
    tau: f64,
    threads: i64,
) -> PyResult<Bound<'py, PyDict>> {
    if width == 0 || width > MAX_SIDE || height == 0 || height > MAX_SIDE {
        return Err(value_error(format!(
            "width and height must be between 1 and {MAX_SIDE}, got {width} x {height}"
        )));
    }
    if !(1.0..179.0).contains(&fov) {
        return Err(value_error(format!(
            "fov must be between 1 and 179 degrees, got {fov}"
        )));
    }
    let caster = match caster {
        "march" => Caster::March,
        "maxmip" => Caster::MaxMipmap,
        "boxes" if tau > 0.0 && tau <= 4096.0 => Caster::Boxes { tau },
        "boxes" => {
            return Err(value_error(format!(
                "tau must be a number of pixels in (0, 4096], got {tau}"
            )))
        }
        _ => {
            return Err(value_error(format!(
                "unknown caster '{caster}'; expected march, maxmip or boxes"
            )))
        }
    };
    let (dem, field) = surface(py, &heights, transform, geographic, threads)?;
    let camera = TerrainCamera {
        eye: MapWorld::new(&dem, &field).to_world(eye),
        target: MapWorld::new(&dem, &field).to_world(target),
        vfov_deg: fov,
        width,
        height,
    };
    let d = [
        camera.target[0] - camera.eye[0],
        camera.target[1] - camera.eye[1],
        camera.target[2] - camera.eye[2],
    ];
    if !(camera
        .eye
        .iter()
        .chain(&camera.target)
        .all(|c| c.is_finite())
        && d.iter().any(|&c| c != 0.0))
    {
        return Err(value_error(
            "eye and target must be finite and differ (the camera needs a direction to look in)",
        ));
    }
    let (w, h) = (width as usize, height as usize);
    let (t, col, row, steps, dirs) = detached(py, threads, || {
        let pyramid = MaxMipmap::new(&field);
        let image = cast_image(&field, &pyramid, &camera, caster);
        let frame = camera.frame();
        let t: Vec<f64> = image
            .hits
            .iter()
            .map(|h| h.map_or(f64::INFINITY, |h| h.t))
            .collect();
        let col: Vec<i64> = image
            .hits
            .iter()
            .map(|h| h.map_or(-1, |h| h.col as i64))
            .collect();
        let row: Vec<i64> = image
            .hits
            .iter()
            .map(|h| h.map_or(-1, |h| h.row as i64))
            .collect();
        let steps: Vec<u32> = image.steps.iter().map(|s| s.cells + s.nodes).collect();
        let dirs: Vec<f64> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .flat_map(|(x, y)| frame.direction(x as u32, y as u32))
            .collect();
        (t, col, row, steps, dirs)
    })?;
    let grid = |v| Array2::from_shape_vec((h, w), v).expect("one per pixel");
    let out = PyDict::new(py);
    out.set_item("t", grid(t).into_pyarray(py))?;
    out.set_item(
        "col",
        Array2::from_shape_vec((h, w), col)
            .expect("one per pixel")
            .into_pyarray(py),
    )?;
    out.set_item(
        "row",
        Array2::from_shape_vec((h, w), row)
            .expect("one per pixel")
            .into_pyarray(py),
    )?;
    out.set_item(
        "steps",
        Array2::from_shape_vec((h, w), steps)
            .expect("one per pixel")
            .into_pyarray(py),
    )?;
    out.set_item(
        "directions",
        Array3::from_shape_vec((h, w, 3), dirs)
            .expect("three per pixel")
            .into_pyarray(py),
    )?;
    out.set_item("eye", camera.eye.to_vec())?;
    out.set_item("cell_size", (field.sx, field.sy))?;
    Ok(out)
}
