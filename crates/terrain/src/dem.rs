//! A digital elevation model: heights on a regular grid with the
//! georeferencing needed to write results back in the same place.

/// Where the grid lies on the earth, as GeoTIFF describes it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GeoRef {
    /// Map x of the top-left corner of the top-left pixel (GDAL's
    /// "pixel is area" origin).
    pub origin_x: f64,
    /// Map y of that corner.
    pub origin_y: f64,
    /// Pixel width in map units (positive: columns go east).
    pub pixel_width: f64,
    /// Pixel height in map units (negative for north-up rasters: rows go
    /// south).
    pub pixel_height: f64,
    /// Whether map units are degrees of longitude/latitude (SRTM, EPSG:4326)
    /// rather than metres.
    pub geographic: bool,
    /// GeoTIFF GeoKeyDirectory (tag 34735) as read, written back unchanged.
    pub geo_keys: Vec<u16>,
    /// GeoTIFF GeoDoubleParams (tag 34736) as read.
    pub geo_doubles: Vec<f64>,
    /// GeoTIFF GeoAsciiParams (tag 34737) as read.
    pub geo_ascii: String,
    /// The coordinate system as WKT, where the source gives it as text (the
    /// `.prj` beside an ASCII grid) rather than GeoKeys. GeoTIFFs written
    /// without GeoKeys carry it in GDAL's `.aux.xml` sidecar
    /// ([`crate::io::write_crs_sidecar`]), which GDAL, rasterio and QGIS read.
    pub crs_wkt: Option<String>,
}

/// Heights on a `width` × `height` grid, row-major from the top (north)
/// row. Sample (col, row) sits at the centre of its pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Dem {
    /// Samples per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Heights in metres (NaN where the source had no data).
    pub heights: Vec<f32>,
    /// The source's nodata value, if it declared one (kept for output).
    pub nodata: Option<f64>,
    /// Georeferencing (identity with 1 m pixels when the source has none).
    pub georef: GeoRef,
}

impl Dem {
    /// A DEM from heights with 1 m pixels and no georeferencing.
    pub fn from_heights(width: usize, height: usize, heights: Vec<f32>) -> Dem {
        assert_eq!(
            heights.len(),
            width * height,
            "heights must be width × height"
        );
        Dem {
            width,
            height,
            heights,
            nodata: None,
            georef: GeoRef {
                pixel_width: 1.0,
                pixel_height: -1.0,
                ..GeoRef::default()
            },
        }
    }

    /// The same grid with rows running south and columns east, as every
    /// caster and writer takes it: a raster stored south-up (positive
    /// pixel height, as GDAL writes some Terragen and NetCDF conversions)
    /// has its rows reversed and its origin moved to the north edge, one
    /// stored east-to-west its columns. The map position of every sample
    /// is unchanged.
    pub fn north_up(mut self) -> Dem {
        let (w, h) = (self.width, self.height);
        let g = &mut self.georef;
        if g.pixel_height > 0.0 {
            g.origin_y += h as f64 * g.pixel_height;
            g.pixel_height = -g.pixel_height;
            for r in 0..h / 2 {
                let (top, bottom) = self.heights.split_at_mut((h - 1 - r) * w);
                top[r * w..(r + 1) * w].swap_with_slice(&mut bottom[..w]);
            }
        }
        if g.pixel_width < 0.0 {
            g.origin_x += w as f64 * g.pixel_width;
            g.pixel_width = -g.pixel_width;
            for row in self.heights.chunks_exact_mut(w) {
                row.reverse();
            }
        }
        self
    }

    /// Height at (`col`, `row`).
    pub fn at(&self, col: usize, row: usize) -> f32 {
        self.heights[row * self.width + col]
    }

    /// Size of a cell in metres along columns and rows: the pixel size, or
    /// for geographic rasters the pixel size in degrees converted at the
    /// raster's middle latitude (equirectangular: 111,320 m per degree of
    /// latitude, times cos(latitude) per degree of longitude).
    pub fn cell_size_m(&self) -> (f64, f64) {
        let g = &self.georef;
        if g.geographic {
            let mid_lat = g.origin_y + g.pixel_height * self.height as f64 * 0.5;
            let m_per_deg = 111_320.0;
            (
                g.pixel_width.abs() * m_per_deg * mid_lat.to_radians().cos(),
                g.pixel_height.abs() * m_per_deg,
            )
        } else {
            (g.pixel_width.abs(), g.pixel_height.abs())
        }
    }

    /// Grid position (fractional column, row) of map coordinates (`x`, `y`)
    /// in the raster's own units; sample (c, r) sits at its pixel centre.
    pub fn map_to_grid(&self, x: f64, y: f64) -> (f64, f64) {
        let g = &self.georef;
        (
            (x - g.origin_x) / g.pixel_width - 0.5,
            (y - g.origin_y) / g.pixel_height - 0.5,
        )
    }

    /// Map coordinates of grid position (`col`, `row`).
    pub fn grid_to_map(&self, col: f64, row: f64) -> (f64, f64) {
        let g = &self.georef;
        (
            g.origin_x + (col + 0.5) * g.pixel_width,
            g.origin_y + (row + 0.5) * g.pixel_height,
        )
    }

    /// Lowest and highest height, ignoring NaN (`None` when all are NaN).
    pub fn range(&self) -> Option<(f32, f32)> {
        self.heights
            .iter()
            .filter(|h| !h.is_nan())
            .fold(None, |acc, &h| match acc {
                None => Some((h, h)),
                Some((lo, hi)) => Some((lo.min(h), hi.max(h))),
            })
    }

    /// The first height beyond ±[`MAX_HEIGHT`] (infinite ones included) as
    /// (column, row, height), scanning rows from the top: a sample no
    /// surface can stand on (a float64 sample beyond the float32 range
    /// reads as infinite).
    pub fn first_unusable(&self) -> Option<(usize, usize, f32)> {
        first_unusable(&self.heights, self.width)
    }

    /// Replace no-data samples (NaN) by `value` (e.g. the lowest height),
    /// so the surface is defined everywhere; returns how many were filled.
    pub fn fill_nodata(&mut self, value: f32) -> usize {
        let mut n = 0;
        for h in &mut self.heights {
            if h.is_nan() {
                *h = value;
                n += 1;
            }
        }
        n
    }
}

/// Largest height magnitude a DEM may hold, metres: beyond it, differences
/// of heights and the rays over them overflow float32 (two heights of ±3e38
/// differ by infinity, and every cell would read as lit).
pub const MAX_HEIGHT: f32 = 1e9;

/// The first sample of row-major `heights`, `width` per row, beyond
/// ±[`MAX_HEIGHT`] (infinite ones included; NaN, no data, is not), as
/// (column, row, height).
pub fn first_unusable(heights: &[f32], width: usize) -> Option<(usize, usize, f32)> {
    let i = heights.iter().position(|h| h.abs() > MAX_HEIGHT)?;
    Some((i % width.max(1), i / width.max(1), heights[i]))
}

/// Why the height `h` cannot be used: not finite, or beyond ±[`MAX_HEIGHT`].
pub fn unusable_height(h: f32) -> String {
    if h.is_infinite() {
        format!(
            "height {h} is not finite (a float64 sample beyond the float32 range reads as \
             infinite); heights must be finite, or NaN for no data"
        )
    } else {
        format!("height {h:e} is beyond ±{MAX_HEIGHT:e} m; heights must lie within it, or be NaN for no data")
    }
}
