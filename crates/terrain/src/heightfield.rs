//! The declared surface: the one every terrain ray caster, shadow mask and
//! renderer here intersects, so that "exact" has a meaning.
//!
//! **Surface model.** Heights sit on the grid points. Each cell between four
//! neighbouring points is two triangles split along the diagonal from its
//! top-left point (col, row) to its bottom-right point (col+1, row+1):
//! the triangle above the diagonal ((c, r), (c+1, r), (c+1, r+1)) and the
//! one below it ((c, r), (c+1, r+1), (c, r+1)). The surface is continuous and
//! piecewise planar, the same as the triangle mesh `raykit` builds from the
//! DEM, so mesh ray casting is an independent reference for it.
//!
//! **Coordinates.** World space is metres with x east, y north, z up: grid
//! point (col, row) is at (col · sx, −row · sy, height). Rays are converted
//! once to grid units (x / sx, −y / sy, z); the ray parameter `t` is the same
//! in both, so distances need no conversion back. All intersection
//! arithmetic is in f64.

use crate::dem::{first_unusable, unusable_height, Dem, MAX_HEIGHT};

/// A ray in grid units (see the module documentation), f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridRay {
    /// Origin: column, row, height.
    pub o: [f64; 3],
    /// Direction per unit `t`.
    pub d: [f64; 3],
}

impl GridRay {
    /// The point at parameter `t`.
    pub fn at(&self, t: f64) -> [f64; 3] {
        [
            self.o[0] + t * self.d[0],
            self.o[1] + t * self.d[1],
            self.o[2] + t * self.d[2],
        ]
    }
}

/// A hit: ray parameter, cell, and the work it took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainHit {
    /// Ray parameter of the hit (world distance when the ray direction was a
    /// unit vector in metres).
    pub t: f64,
    /// Column of the hit cell.
    pub col: u32,
    /// Row of the hit cell.
    pub row: u32,
}

/// Cell tests and node visits of one ray, for the "steps per ray" heat maps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Steps {
    /// Cells whose two triangles were tested.
    pub cells: u32,
    /// Quadtree nodes or boxes visited.
    pub nodes: u32,
}

/// One of a cell's two triangles as a plane in cell coordinates `(u, v)`
/// in `[0, 1]²`: `z = z0 + du · u + dv · v`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellPlane {
    /// Height at the cell's (col, row) corner, u = v = 0.
    pub z0: f64,
    /// Rise per cell along u (columns).
    pub du: f64,
    /// Rise per cell along v (rows).
    pub dv: f64,
}

impl CellPlane {
    /// Height at (`u`, `v`).
    pub fn height(&self, u: f64, v: f64) -> f64 {
        self.z0 + self.du * u + self.dv * v
    }
}

/// Tolerance of the inside-triangle test in cell units.
const INSIDE_EPS: f64 = 1e-9;

/// How far [`HeightField::clip`] widens the z range beyond the lowest and
/// highest heights, relative to the largest height (or the ray's origin
/// height, or 1 m): far above the rounding of a hit's `t`, far below any
/// height difference a DEM stores.
pub const Z_PAD: f64 = 1e-9;

/// A height field ready for ray casting: heights (no-data filled), grid
/// size, cell size in metres.
#[derive(Clone, Debug)]
pub struct HeightField {
    /// Grid points per row.
    pub width: usize,
    /// Rows of grid points.
    pub height: usize,
    /// Heights in metres, row-major from the north row.
    pub heights: Vec<f32>,
    /// Cell size along x (columns), metres.
    pub sx: f64,
    /// Cell size along y (rows), metres.
    pub sy: f64,
    /// Lowest and highest height.
    pub zmin: f32,
    /// Highest height.
    pub zmax: f32,
}

/// The lowest and highest height of `heights` that are not NaN, and whether
/// any is NaN; eight lanes at a time, so that the loop compiles to vector
/// operations.
fn valid_range(heights: &[f32]) -> (f32, f32, bool) {
    const LANES: usize = 8;
    let (mut lo, mut hi) = ([f32::INFINITY; LANES], [f32::NEG_INFINITY; LANES]);
    let mut nan = [false; LANES];
    let lanes = heights.chunks_exact(LANES);
    let rest = lanes.remainder();
    for h in lanes {
        for k in 0..LANES {
            lo[k] = lo[k].min(h[k]);
            hi[k] = hi[k].max(h[k]);
            nan[k] |= h[k].is_nan();
        }
    }
    let mut out = (f32::INFINITY, f32::NEG_INFINITY, false);
    for (k, &h) in rest.iter().enumerate() {
        lo[k] = lo[k].min(h);
        hi[k] = hi[k].max(h);
        nan[k] |= h.is_nan();
    }
    for k in 0..LANES {
        out = (out.0.min(lo[k]), out.1.max(hi[k]), out.2 || nan[k]);
    }
    out
}

impl HeightField {
    /// The surface of `dem`; no-data samples become the lowest height.
    /// Needs at least 2 × 2 grid points with at least one valid height.
    pub fn new(dem: &Dem) -> Result<HeightField, String> {
        Self::with_heights(dem, dem.heights.clone()).map_err(|(e, _)| e)
    }

    /// [`HeightField::new`] with `dem`'s heights moved into the surface
    /// instead of copied (a 4096² DEM holds 64 MiB of them), leaving
    /// `dem.heights` empty; on an error they stay in `dem`.
    pub fn take(dem: &mut Dem) -> Result<HeightField, String> {
        let heights = std::mem::take(&mut dem.heights);
        Self::with_heights(dem, heights).map_err(|(e, heights)| {
            dem.heights = heights;
            e
        })
    }

    /// The surface of `dem`'s grid over `heights` (`dem`'s own), no-data
    /// samples replaced in place by the lowest height; on an error, the
    /// message and `heights` untouched.
    fn with_heights(dem: &Dem, mut heights: Vec<f32>) -> Result<HeightField, (String, Vec<f32>)> {
        if dem.width < 2 || dem.height < 2 {
            let e = format!(
                "a height field needs at least 2 rows and 2 columns of samples, got {} row{} and {} column{}",
                dem.height,
                if dem.height == 1 { "" } else { "s" },
                dem.width,
                if dem.width == 1 { "" } else { "s" },
            );
            return Err((e, heights));
        }
        use rayon::prelude::*;
        // Lowest and highest valid height, and whether any is missing.
        let (zmin, zmax, missing) = heights.par_chunks(1 << 16).map(valid_range).reduce(
            || (f32::INFINITY, f32::NEG_INFINITY, false),
            |a, b| (a.0.min(b.0), a.1.max(b.1), a.2 || b.2),
        );
        if zmin > zmax {
            let e = "the DEM has no valid height (every sample is no-data)".to_string();
            return Err((e, heights));
        }
        if let Some((col, row, h)) = (zmin < -MAX_HEIGHT || zmax > MAX_HEIGHT)
            .then(|| first_unusable(&heights, dem.width))
            .flatten()
        {
            let e = format!("row {row}, column {col}: {}", unusable_height(h));
            return Err((e, heights));
        }
        let g = &dem.georef;
        if g.geographic {
            let (north, south) = (g.origin_y, g.origin_y + g.pixel_height * dem.height as f64);
            if !((-90.0..=90.0).contains(&north) && (-90.0..=90.0).contains(&south)) {
                return Err((
                    format!(
                        "geographic rows span latitudes {north} to {south}, outside -90 to 90 \
                         (is the raster in degrees?)"
                    ),
                    heights,
                ));
            }
        }
        let (sx, sy) = dem.cell_size_m();
        // Beyond these, positions and view rays over the grid lose their
        // meaning in f64 (products of coordinates underflow or overflow).
        let sane = |c: f64| (1e-9..=1e9).contains(&c);
        if !(sane(sx) && sane(sy)) {
            return Err((
                format!("cell size must be between 1e-9 and 1e9 m, got {sx:e} x {sy:e}"),
                heights,
            ));
        }
        if missing {
            heights.par_iter_mut().for_each(|h| {
                if h.is_nan() {
                    *h = zmin
                }
            });
        }
        Ok(HeightField {
            width: dem.width,
            height: dem.height,
            heights,
            sx,
            sy,
            zmin,
            zmax,
        })
    }

    /// Cells along x and y.
    pub fn cells(&self) -> (usize, usize) {
        (self.width - 1, self.height - 1)
    }

    /// Height at grid point (`col`, `row`).
    pub fn at(&self, col: usize, row: usize) -> f32 {
        self.heights[row * self.width + col]
    }

    /// The plane of cell (`col`, `row`)'s upper triangle ((c, r), (c+1, r),
    /// (c+1, r+1), where u ≥ v) or lower one ((c, r), (c+1, r+1), (c, r+1)):
    /// the one definition of the declared surface that every caster, mask
    /// and shader uses.
    #[inline]
    pub fn cell_plane(&self, col: usize, row: usize, upper: bool) -> CellPlane {
        let h00 = self.at(col, row) as f64;
        let h10 = self.at(col + 1, row) as f64;
        let h01 = self.at(col, row + 1) as f64;
        let h11 = self.at(col + 1, row + 1) as f64;
        if upper {
            CellPlane {
                z0: h00,
                du: h10 - h00,
                dv: h11 - h10,
            }
        } else {
            CellPlane {
                z0: h00,
                du: h11 - h01,
                dv: h01 - h00,
            }
        }
    }

    /// Surface height at grid-unit position (`x`, `y`), clamped into the
    /// grid.
    pub fn height_at(&self, x: f64, y: f64) -> f64 {
        let (cw, ch) = self.cells();
        let c = (x.floor().max(0.0) as usize).min(cw - 1);
        let r = (y.floor().max(0.0) as usize).min(ch - 1);
        let (u, v) = (x - c as f64, y - r as f64);
        self.cell_plane(c, r, u >= v).height(u, v)
    }

    /// The grid points (col, row) whose heights make the surface at
    /// grid-unit position (`x`, `y`), as [`HeightField::height_at`] reads
    /// it: the corners of the triangle under it that carry weight (one at
    /// a grid point, two on an edge, three inside).
    pub fn samples_under(&self, x: f64, y: f64) -> impl Iterator<Item = (usize, usize)> {
        let (cw, ch) = self.cells();
        let c = (x.floor().max(0.0) as usize).min(cw - 1);
        let r = (y.floor().max(0.0) as usize).min(ch - 1);
        let (u, v) = (x - c as f64, y - r as f64);
        let corners = if u >= v {
            [(c, r, 1.0 - u), (c + 1, r, u - v), (c + 1, r + 1, v)]
        } else {
            [(c, r, 1.0 - v), (c, r + 1, v - u), (c + 1, r + 1, u)]
        };
        corners
            .into_iter()
            .filter(|&(_, _, w)| w != 0.0)
            .map(|(c, r, _)| (c, r))
    }

    /// World position (metres, x east, y north, z up) of grid point
    /// (`col`, `row`).
    pub fn point(&self, col: usize, row: usize) -> [f64; 3] {
        [
            col as f64 * self.sx,
            -(row as f64) * self.sy,
            self.at(col, row) as f64,
        ]
    }

    /// A world-space ray in grid units.
    pub fn grid_ray(&self, origin: [f64; 3], dir: [f64; 3]) -> GridRay {
        GridRay {
            o: [origin[0] / self.sx, -origin[1] / self.sy, origin[2]],
            d: [dir[0] / self.sx, -dir[1] / self.sy, dir[2]],
        }
    }

    /// The ray's parameter interval inside the grid's bounding box (x in
    /// `[0, width−1]`, y in `[0, height−1]`, z in `[zmin, zmax]`),
    /// intersected with `[tmin, tmax]`; `None` when empty.
    ///
    /// The z range is widened by [`Z_PAD`] of the largest height involved:
    /// where the surface lies at `zmin` or `zmax` (a flat grid, the sea at
    /// the lowest height), the box's end and [`HeightField::hit_cell`]'s
    /// `t` for the same hit come from different formulas and may round to
    /// either side of each other, which would lose the hit.
    pub fn clip(&self, ray: &GridRay, tmin: f64, tmax: f64) -> Option<(f64, f64)> {
        let (zmin, zmax) = (self.zmin as f64, self.zmax as f64);
        let scale = zmin.abs().max(zmax.abs()).max(ray.o[2].abs()).max(1.0);
        let pad = Z_PAD * scale;
        let lo = [0.0, 0.0, zmin - pad];
        let hi = [
            (self.width - 1) as f64,
            (self.height - 1) as f64,
            zmax + pad,
        ];
        slab(ray, lo, hi, tmin, tmax)
    }

    /// The nearest hit with `t` in `[tmin, tmax]` on the two triangles of
    /// cell (`col`, `row`), if any. Rays parallel to a triangle's plane do
    /// not hit it.
    pub fn hit_cell(
        &self,
        col: usize,
        row: usize,
        ray: &GridRay,
        tmin: f64,
        tmax: f64,
    ) -> Option<f64> {
        let u0 = ray.o[0] - col as f64;
        let v0 = ray.o[1] - row as f64;
        let [du, dv, dz] = ray.d;
        let oz = ray.o[2];
        let mut best: Option<f64> = None;
        for upper in [true, false] {
            let CellPlane {
                z0: h00,
                du: b,
                dv: c,
            } = self.cell_plane(col, row, upper);
            let denom = dz - b * du - c * dv;
            if denom == 0.0 || !denom.is_finite() {
                continue;
            }
            let t = -(oz - h00 - b * u0 - c * v0) / denom;
            if !(t >= tmin && t <= tmax) || best.is_some_and(|bt| bt <= t) {
                continue;
            }
            let (u, v) = (u0 + t * du, v0 + t * dv);
            let inside = if upper {
                v >= -INSIDE_EPS && u <= 1.0 + INSIDE_EPS && v <= u + INSIDE_EPS
            } else {
                u >= -INSIDE_EPS && v <= 1.0 + INSIDE_EPS && u <= v + INSIDE_EPS
            };
            if inside {
                best = Some(t);
            }
        }
        best
    }

    /// The surface as a triangle mesh in world coordinates (two triangles
    /// per cell, split as declared), for mesh ray casting and rendering.
    pub fn to_mesh(&self) -> raykit_core::TriangleMesh {
        use raykit_core::Vec3;
        let positions: Vec<Vec3> = (0..self.height)
            .flat_map(|r| (0..self.width).map(move |c| (c, r)))
            .map(|(c, r)| {
                let p = self.point(c, r);
                Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
            })
            .collect();
        let w = self.width as u32;
        let (cw, ch) = self.cells();
        let mut indices = Vec::with_capacity(cw * ch * 2);
        for r in 0..ch as u32 {
            for c in 0..cw as u32 {
                let (p00, p10, p01, p11) = (
                    r * w + c,
                    r * w + c + 1,
                    (r + 1) * w + c,
                    (r + 1) * w + c + 1,
                );
                // Counter-clockwise seen from above (x east, y north).
                indices.push([p00, p11, p10]);
                indices.push([p00, p01, p11]);
            }
        }
        raykit_core::TriangleMesh::new(positions, indices)
    }
}

/// Slab test of `ray` against the box `[lo, hi]` within `[tmin, tmax]`.
pub fn slab(ray: &GridRay, lo: [f64; 3], hi: [f64; 3], tmin: f64, tmax: f64) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (tmin, tmax);
    for a in 0..3 {
        let d = ray.d[a];
        if d == 0.0 {
            if ray.o[a] < lo[a] || ray.o[a] > hi[a] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d;
        let (mut ta, mut tb) = ((lo[a] - ray.o[a]) * inv, (hi[a] - ray.o[a]) * inv);
        if ta > tb {
            std::mem::swap(&mut ta, &mut tb);
        }
        t0 = t0.max(ta);
        t1 = t1.min(tb);
        if t0 > t1 {
            return None;
        }
    }
    Some((t0, t1))
}

/// The index of the cell (or node, at `scale` cells per node) that a ray
/// at coordinate `x` moving with direction `d` is in: the floor, except on a
/// boundary, where the direction decides.
pub(crate) fn index_along(x: f64, d: f64, scale: f64) -> i64 {
    let q = x / scale;
    let f = q.floor();
    if q == f && d < 0.0 {
        f as i64 - 1
    } else {
        f as i64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The surface's height range, and the filling of no-data samples,
    /// against a plain loop, on grids of one or several parallel chunks
    /// whose sizes are no multiple of the lanes; `take` moves the heights
    /// and gives them back on an error.
    #[test]
    fn range_and_filling_match_a_plain_loop() {
        let mut rng = raykit_core::rng::Pcg32::new(9);
        for (w, h) in [(2, 2), (3, 7), (301, 257), (517, 300)] {
            let heights: Vec<f32> = (0..w * h)
                .map(|_| {
                    if rng.next_u32().is_multiple_of(13) {
                        f32::NAN
                    } else {
                        rng.range_f32(-400.0, 3000.0)
                    }
                })
                .collect();
            let valid = heights.iter().filter(|h| !h.is_nan());
            let lo = valid
                .clone()
                .fold(f32::INFINITY, |a, &b| if b < a { b } else { a });
            let hi = valid.fold(f32::NEG_INFINITY, |a, &b| if b > a { b } else { a });
            let mut dem = Dem::from_heights(w, h, heights.clone());
            let copied = HeightField::new(&dem).unwrap();
            let field = HeightField::take(&mut dem).unwrap();
            assert!(dem.heights.is_empty(), "{w}x{h}: the heights moved");
            for f in [&copied, &field] {
                assert_eq!((f.zmin, f.zmax), (lo, hi), "{w}x{h}");
                for (i, (&got, &given)) in f.heights.iter().zip(&heights).enumerate() {
                    let want = if given.is_nan() { lo } else { given };
                    assert_eq!(got, want, "{w}x{h}, sample {i}");
                }
            }
        }
        let mut empty = Dem::from_heights(3, 3, vec![f32::NAN; 9]);
        assert!(HeightField::take(&mut empty).is_err());
        assert_eq!(empty.heights.len(), 9, "the heights are given back");
    }

    /// `samples_under` names exactly the samples whose change moves
    /// `height_at` there: each sample of a grid is raised in turn, at
    /// random positions, at grid points, on cell edges and on diagonals.
    #[test]
    fn samples_under_are_those_height_at_reads() {
        let (w, h) = (5, 4);
        let mut rng = raykit_core::rng::Pcg32::new(17);
        let base: Vec<f32> = (0..w * h).map(|_| rng.range_f32(0.0, 10.0)).collect();
        let mut at: Vec<(f64, f64)> = (0..200)
            .map(|_| {
                (
                    rng.range_f32(0.0, 4.0) as f64,
                    rng.range_f32(0.0, 3.0) as f64,
                )
            })
            .collect();
        for i in 0..=8 {
            let q = i as f64 * 0.5;
            at.extend([
                (q.min(4.0), 1.0),
                (2.0, (q * 0.75).min(3.0)),
                (q.min(3.0), q.min(3.0)),
            ]);
            at.push((1.25 + (q * 0.25).min(1.0), 0.25 + (q * 0.25).min(1.0)));
        }
        let field = HeightField::new(&Dem::from_heights(w, h, base.clone())).unwrap();
        for &(x, y) in &at {
            let named: Vec<(usize, usize)> = field.samples_under(x, y).collect();
            for i in 0..w * h {
                let mut raised = base.clone();
                raised[i] += 100.0;
                let f = HeightField::new(&Dem::from_heights(w, h, raised)).unwrap();
                let moved = f.height_at(x, y) != field.height_at(x, y);
                let listed = named.contains(&(i % w, i / w));
                assert_eq!(moved, listed, "({x}, {y}), sample {i}: {named:?}");
            }
        }
    }
}
