//! A DEM's map coordinates ↔ the world metres its height field is cast in
//! (x east, y north from grid point (0, 0), z the height), and the checks
//! that keep camera and light positions near the DEM.

use crate::dem::Dem;
use crate::heightfield::HeightField;

/// Camera points more than this many DEM diagonals outside the DEM are
/// refused: such a point is almost always a coordinate in the wrong units or
/// the wrong reference system, and its image would be a few pixels of DEM.
pub const SANE_DIAGONALS: f64 = 10.0;

/// Map coordinates of a DEM (its own units: metres for projected rasters,
/// degrees for geographic ones) ↔ world metres of its height field. Cameras
/// and lights are given in map coordinates, while the casters work in world
/// metres, where a cell is `sx` × `sy` metres and rows run south.
#[derive(Clone, Copy)]
pub struct MapWorld<'a> {
    /// The DEM, for its georeferencing (origin, pixel size).
    pub dem: &'a Dem,
    /// The height field built from it, for the cell size in metres.
    pub field: &'a HeightField,
}

impl<'a> MapWorld<'a> {
    /// The georeferencing of `field`, built from `dem` (or from a DEM with the
    /// same grid and georeferencing).
    pub fn new(dem: &'a Dem, field: &'a HeightField) -> MapWorld<'a> {
        MapWorld { dem, field }
    }

    /// Map position and height → world metres.
    pub fn to_world(&self, m: [f64; 3]) -> [f64; 3] {
        let (c, r) = self.dem.map_to_grid(m[0], m[1]);
        [c * self.field.sx, -r * self.field.sy, m[2]]
    }

    /// World metres → map position and height (the inverse of
    /// [`MapWorld::to_world`]).
    pub fn to_map(&self, w: [f64; 3]) -> [f64; 3] {
        let (col, row) = self.world_to_grid(w[0], w[1]);
        let (x, y) = self.dem.grid_to_map(col, row);
        [x, y, w[2]]
    }

    /// World position (`x`, `y`) → grid position (column, row), the units of
    /// [`HeightField::height_at`].
    pub fn world_to_grid(&self, x: f64, y: f64) -> (f64, f64) {
        (x / self.field.sx, -y / self.field.sy)
    }

    /// World extent (x to the east edge, y to the south edge) and diagonal,
    /// metres.
    pub fn extent(&self) -> (f64, f64, f64) {
        let f = self.field;
        let (w, h) = ((f.width - 1) as f64 * f.sx, (f.height - 1) as f64 * f.sy);
        (w, h, w.hypot(h))
    }

    /// The map extent of the grid points and the height range, for messages
    /// that tell the user which coordinates the DEM expects.
    pub fn describe_extent(&self) -> String {
        let f = self.field;
        let (x0, y0) = self.dem.grid_to_map(0.0, 0.0);
        let (x1, y1) = self
            .dem
            .grid_to_map((f.width - 1) as f64, (f.height - 1) as f64);
        let units = if self.dem.georef.geographic {
            " (degrees of longitude/latitude)"
        } else {
            ""
        };
        format!(
            "x {}..{}, y {}..{}{units}, heights {:.1}..{:.1} m",
            format_number(x0.min(x1)),
            format_number(x0.max(x1)),
            format_number(y0.min(y1)),
            format_number(y0.max(y1)),
            f.zmin,
            f.zmax
        )
    }

    /// A camera point `map` (given to `flag`, which the error names) in world
    /// metres; refused when it lies more than [`SANE_DIAGONALS`] DEM
    /// diagonals away from the DEM or its heights, or, with `above`, under
    /// the surface.
    pub fn check(&self, flag: &str, map: [f64; 3], above: bool) -> Result<[f64; 3], String> {
        let w = self.to_world(map);
        let f = self.field;
        let (ew, eh, diag) = self.extent();
        let m = SANE_DIAGONALS * diag;
        let shown = format!(
            "{},{},{}",
            format_number(map[0]),
            format_number(map[1]),
            format_number(map[2])
        );
        if !w.iter().all(|c| c.is_finite())
            || w[0] < -m
            || w[0] > ew + m
            || w[1] > m
            || w[1] < -eh - m
        {
            return Err(format!(
                "{flag} {shown}: more than {SANE_DIAGONALS} DEM diagonals ({:.1} km) away from the \
                 DEM; expected map coordinates near {}",
                m / 1e3,
                self.describe_extent()
            ));
        }
        if w[2] < f.zmin as f64 - m || w[2] > f.zmax as f64 + m {
            return Err(format!(
                "{flag} {shown}: height {} m is more than {SANE_DIAGONALS} DEM diagonals \
                 ({:.1} km) outside the DEM's heights {:.1}..{:.1} m",
                format_number(w[2]),
                m / 1e3,
                f.zmin,
                f.zmax
            ));
        }
        let (gx, gy) = self.world_to_grid(w[0], w[1]);
        let (gw, gh) = ((f.width - 1) as f64, (f.height - 1) as f64);
        if above && (0.0..=gw).contains(&gx) && (0.0..=gh).contains(&gy) {
            let ground = f.height_at(gx, gy);
            if w[2] <= ground {
                return Err(format!(
                    "{flag} {shown}: below the terrain surface there ({ground:.1} m); \
                     put the camera above the ground"
                ));
            }
        }
        Ok(w)
    }

    /// Map position (`x`, `y`) (given to `flag`, which the error names) →
    /// world metres (x, y); refused outside the grid points' extent, where
    /// the surface has no height. A position on the extent's edge counts as
    /// inside even where the division by the pixel size rounds it a hair
    /// (10⁻⁹ of the grid) beyond.
    pub fn inside(&self, x: f64, y: f64, flag: &str) -> Result<[f64; 2], String> {
        let dem = self.dem;
        let (col, row) = dem.map_to_grid(x, y);
        let (w, h) = ((dem.width - 1) as f64, (dem.height - 1) as f64);
        let hair = 1e-9 * w.max(h);
        let within = |p: f64, end: f64| (-hair..=end + hair).contains(&p);
        if !within(col, w) || !within(row, h) {
            let (x0, y0) = dem.grid_to_map(0.0, 0.0);
            let (x1, y1) = dem.grid_to_map(w, h);
            let n = format_number;
            return Err(format!(
                "{flag}: ({}, {}) lies outside the DEM, whose grid points span x {}..{}, y {}..{}",
                n(x),
                n(y),
                n(x0),
                n(x1),
                n(y1),
                n(y0)
            ));
        }
        let (col, row) = (col.clamp(0.0, w), row.clamp(0.0, h));
        Ok([col * self.field.sx, -row * self.field.sy])
    }
}

/// A coordinate in a message: integers without decimals, others with up to
/// 6, so that map coordinates read as the user typed them; magnitudes from
/// 10¹⁵ up or under 10⁻⁴ in exponent form (1e300, not 301 digits).
pub fn format_number(x: f64) -> String {
    let a = x.abs();
    if !x.is_finite() || (a != 0.0 && !(1e-4..1e15).contains(&a)) {
        format!("{x:e}")
    } else if x == x.round() {
        format!("{x:.0}")
    } else {
        let s = format!("{x:.6}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A projected 5 × 4 DEM (metres) with an origin far from zero, heights
    /// 100 + col + row.
    fn projected() -> Dem {
        let heights = (0..20).map(|i| 100.0 + (i % 5 + i / 5) as f32).collect();
        let mut dem = Dem::from_heights(5, 4, heights);
        dem.georef.origin_x = 429_000.0;
        dem.georef.origin_y = 5_151_000.0;
        dem.georef.pixel_width = 30.0;
        dem.georef.pixel_height = -30.0;
        dem
    }

    #[test]
    fn map_world_map_round_trips() {
        let dem = projected();
        let field = HeightField::new(&dem).unwrap();
        let geo = MapWorld::new(&dem, &field);
        for m in [
            [429_015.0, 5_150_985.0, 7.0],
            [429_061.25, 5_150_931.5, -3.0],
            [428_000.0, 5_152_000.0, 1e4],
        ] {
            let back = geo.to_map(geo.to_world(m));
            for k in 0..3 {
                assert!((back[k] - m[k]).abs() < 1e-6, "{m:?} -> {back:?}");
            }
        }
    }

    #[test]
    fn world_distances_are_map_distances_on_a_projected_dem() {
        // Map units are metres: two points' world distance is their map
        // distance, and north on the map is +y in the world.
        let dem = projected();
        let field = HeightField::new(&dem).unwrap();
        let geo = MapWorld::new(&dem, &field);
        let (a, b) = ([429_010.0, 5_150_990.0, 0.0], [429_100.0, 5_151_030.0, 0.0]);
        let (wa, wb) = (geo.to_world(a), geo.to_world(b));
        let map_d = (b[0] - a[0]).hypot(b[1] - a[1]);
        let world_d = (wb[0] - wa[0]).hypot(wb[1] - wa[1]);
        assert!((map_d - world_d).abs() < 1e-9);
        assert!(wb[1] > wa[1]);
        // The first grid point (the centre of the top-left pixel) is the
        // world origin.
        let first = geo.to_world([429_015.0, 5_150_985.0, 0.0]);
        assert!(first[0].abs() < 1e-9 && first[1].abs() < 1e-9);
    }

    #[test]
    fn inside_accepts_the_grid_extent_and_names_the_flag_outside() {
        let dem = projected();
        let field = HeightField::new(&dem).unwrap();
        let geo = MapWorld::new(&dem, &field);
        // Grid point (2, 1) is at map (429_000 + 2.5·30, 5_151_000 − 1.5·30).
        let w = geo.inside(429_075.0, 5_150_955.0, "--light").unwrap();
        assert!((w[0] - 2.0 * field.sx).abs() < 1e-9 && (w[1] + field.sy).abs() < 1e-9);
        // Every pixel size, the last grid point's centre is inside.
        for a in [0.1, 0.3, 0.7, 30.0, 1.0 / 3600.0] {
            let mut d = Dem::from_heights(4, 3, vec![0.0; 12]);
            (d.georef.origin_x, d.georef.origin_y) = (1000.0 + a, 2000.0);
            (d.georef.pixel_width, d.georef.pixel_height) = (a, -a);
            let f = HeightField::new(&d).unwrap();
            let g = MapWorld::new(&d, &f);
            for (c, r) in [(3.5, 0.5), (0.5, 2.5), (3.5, 2.5), (0.5, 0.5)] {
                let (x, y) = (1000.0 + a + a * c, 2000.0 - a * r);
                let p = g
                    .inside(x, y, "--light")
                    .unwrap_or_else(|e| panic!("{a}: {e}"));
                let want = [(c - 0.5) * f.sx, -(r - 0.5) * f.sy];
                assert!((p[0] - want[0]).abs() <= 1e-6 * f.sx, "{a} {c} {r}: {p:?}");
                assert!((p[1] - want[1]).abs() <= 1e-6 * f.sy, "{a} {c} {r}: {p:?}");
            }
        }
        let e = geo.inside(0.0, 0.0, "--light").unwrap_err();
        assert!(e.starts_with("--light: (0, 0) lies outside the DEM"), "{e}");
    }

    #[test]
    fn check_refuses_far_points_and_points_under_the_ground() {
        let dem = projected();
        let field = HeightField::new(&dem).unwrap();
        let geo = MapWorld::new(&dem, &field);
        // Above grid point (2, 1), whose height is 100 + 2 + 1.
        let (x, y) = (429_075.0, 5_150_955.0);
        assert!(geo.check("--eye", [x, y, 103.5], true).is_ok());
        let e = geo.check("--eye", [x, y, 102.5], true).unwrap_err();
        assert!(
            e.contains("below the terrain surface there (103.0 m)"),
            "{e}"
        );
        assert!(geo.check("--target", [x, y, 102.5], false).is_ok());
        let e = geo.check("--eye", [0.0, 0.0, 200.0], true).unwrap_err();
        assert!(e.starts_with("--eye 0,0,200: more than"), "{e}");
    }

    #[test]
    fn numbers_in_messages_read_as_typed() {
        for x in [429_452.0, -3.0, 0.25, 11.123456, -93.2] {
            let s = format_number(x);
            assert_eq!(s.parse::<f64>().unwrap(), x, "{s}");
        }
        assert_eq!(format_number(429_452.0), 429_452.to_string());
        // Magnitudes beyond the fixed form come back whole, and short.
        for x in [1e300, -2.5e15, 3e-9, -1e-5, f64::MAX, f64::MIN_POSITIVE] {
            let s = format_number(x);
            assert!(s.len() <= 24, "{s}");
            assert_eq!(s.parse::<f64>().unwrap(), x, "{s}");
        }
    }
}
