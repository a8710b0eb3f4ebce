//! The classes of a written shadow mask's cells and the values they are
//! written as, following gdal_viewshed's output options (`-vv`, `-iv`,
//! `-ov`, `-a_nodata`): lit, in shadow, beyond the maximum distance from
//! the light, or without data in the DEM.

/// What a grid point of a written mask is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaskCell {
    /// The light is visible from the point.
    Lit,
    /// The surface hides the light.
    Shadow,
    /// Farther from the light than the maximum distance.
    OutOfRange,
    /// The DEM has no height there.
    NoData,
}

/// The values the classes are written as (gdal_viewshed's `-vv`, `-iv`,
/// `-ov` and `-a_nodata`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaskValues {
    /// Value of lit cells.
    pub visible: u8,
    /// Value of cells in shadow.
    pub invisible: u8,
    /// Value of cells beyond the maximum distance.
    pub out_of_range: u8,
    /// Value of cells without data, declared as the GeoTIFF's nodata.
    pub nodata: u8,
}

/// A maximum horizontal distance from a point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// The light's grid position (column, row).
    pub light_grid: (f64, f64),
    /// Cell size in metres (east, south).
    pub cell: (f64, f64),
    /// The maximum distance, metres.
    pub max_distance: f64,
}

impl MaskCell {
    /// The value the cell is written as.
    pub fn value(self, values: &MaskValues) -> u8 {
        match self {
            MaskCell::Lit => values.visible,
            MaskCell::Shadow => values.invisible,
            MaskCell::OutOfRange => values.out_of_range,
            MaskCell::NoData => values.nodata,
        }
    }

    /// The cell's colour in a preview image: light sand when lit, dark
    /// blue in shadow, grey beyond range, magenta without data.
    pub fn preview(self) -> [u8; 3] {
        PREVIEW_PALETTE[self.preview_index() as usize]
    }

    /// The cell's entry in [`PREVIEW_PALETTE`], for a palette image.
    pub fn preview_index(self) -> u8 {
        match self {
            MaskCell::Lit => 0,
            MaskCell::Shadow => 1,
            MaskCell::OutOfRange => 2,
            MaskCell::NoData => 3,
        }
    }
}

/// The preview colours of lit, shadowed, out-of-range and no-data cells.
pub const PREVIEW_PALETTE: [[u8; 3]; 4] = [
    [235, 225, 190],
    [40, 45, 70],
    [120, 120, 120],
    [255, 0, 255],
];

/// The classes of a mask's grid points (row-major, `width` wide): no data
/// where `nodata` is set, then out of range where `range` says so, then lit
/// where `mask` is 1, else in shadow.
#[derive(Clone, Copy, Debug)]
pub struct MaskClasses<'a> {
    /// The shadow mask, 1 where lit.
    pub mask: &'a [u8],
    /// Where the DEM has no data; none when it has data everywhere.
    pub nodata: Option<&'a [bool]>,
    /// Grid points per row.
    pub width: usize,
    /// The maximum distance from the light, if any.
    pub range: Option<&'a Range>,
}

/// What a mask is written as: each grid point's value, its preview palette
/// index ([`PREVIEW_PALETTE`]) and the number of lit points.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaskRasters {
    /// The values written, row-major.
    pub values: Vec<u8>,
    /// The preview's palette indices, row-major.
    pub preview: Vec<u8>,
    /// Grid points lit.
    pub lit: usize,
}

impl MaskClasses<'_> {
    /// The class of grid point `i`.
    #[inline]
    pub fn at(&self, i: usize) -> MaskCell {
        let out_of_range = |i: usize| match self.range {
            Some(r) => {
                let (lc, lr) = r.light_grid;
                let (c, row) = ((i % self.width) as f64, (i / self.width) as f64);
                ((c - lc) * r.cell.0).hypot((row - lr) * r.cell.1) > r.max_distance
            }
            None => false,
        };
        if self.nodata.is_some_and(|n| n[i]) {
            MaskCell::NoData
        } else if out_of_range(i) {
            MaskCell::OutOfRange
        } else if self.mask[i] == 1 {
            MaskCell::Lit
        } else {
            MaskCell::Shadow
        }
    }

    /// Every grid point's value under `values`, its preview index and the
    /// lit count, in one parallel pass over the grid: each point's class
    /// as a three-bit code (no data, out of range, lit) looked up in a
    /// table of eight, so that the loop has no branches.
    pub fn rasters(&self, values: &MaskValues) -> MaskRasters {
        use rayon::prelude::*;
        const CHUNK: usize = 1 << 16;
        // The class of each code, in `at`'s order of precedence.
        let class = |code: usize| {
            if code & 4 != 0 {
                MaskCell::NoData
            } else if code & 2 != 0 {
                MaskCell::OutOfRange
            } else if code & 1 != 0 {
                MaskCell::Lit
            } else {
                MaskCell::Shadow
            }
        };
        let value: [u8; 8] = std::array::from_fn(|c| class(c).value(values));
        let index: [u8; 8] = std::array::from_fn(|c| class(c).preview_index());
        let n = self.mask.len();
        let (mut out, mut preview) = (vec![0u8; n], vec![0u8; n]);
        let lit = out
            .par_chunks_mut(CHUNK)
            .zip(preview.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(k, (out, preview))| {
                let first = k * CHUNK;
                let mask = &self.mask[first..first + out.len()];
                let mut codes: Vec<u8> = mask.iter().map(|&m| u8::from(m == 1)).collect();
                if let Some(nodata) = self.nodata {
                    let nodata = &nodata[first..first + out.len()];
                    for (c, &nd) in codes.iter_mut().zip(nodata) {
                        *c |= u8::from(nd) << 2;
                    }
                }
                if self.range.is_some() {
                    for (j, c) in codes.iter_mut().enumerate() {
                        *c |= u8::from(self.at(first + j) == MaskCell::OutOfRange) << 1;
                    }
                }
                let mut lit = 0;
                for ((o, p), &c) in out.iter_mut().zip(preview.iter_mut()).zip(&codes) {
                    lit += usize::from(c == 1);
                    *o = value[c as usize];
                    *p = index[c as usize];
                }
                lit
            })
            .sum();
        MaskRasters {
            values: out,
            preview,
            lit,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The class of grid point `i` by the definition, brute force.
    fn expected(i: usize, width: usize, mask: &[u8], nodata: &[bool], r: &Range) -> MaskCell {
        let (c, row) = ((i % width) as f64, (i / width) as f64);
        let (dc, dr) = (
            (c - r.light_grid.0) * r.cell.0,
            (row - r.light_grid.1) * r.cell.1,
        );
        if nodata[i] {
            MaskCell::NoData
        } else if (dc * dc + dr * dr).sqrt() > r.max_distance {
            MaskCell::OutOfRange
        } else if mask[i] == 1 {
            MaskCell::Lit
        } else {
            MaskCell::Shadow
        }
    }

    /// Classes and rasters of a `width`-wide grid against the brute force.
    fn check(width: usize, mask: &[u8], nodata: &[bool], range: &Range) {
        let classes = MaskClasses {
            mask,
            nodata: Some(nodata),
            width,
            range: Some(range),
        };
        let values = MaskValues {
            visible: 7,
            invisible: 3,
            out_of_range: 9,
            nodata: 255,
        };
        let rasters = classes.rasters(&values);
        let mut lit = 0;
        for i in 0..mask.len() {
            let want = expected(i, width, mask, nodata, range);
            assert_eq!(classes.at(i), want, "cell {i}");
            assert_eq!(rasters.values[i], want.value(&values), "cell {i}");
            assert_eq!(rasters.preview[i], want.preview_index(), "cell {i}");
            lit += usize::from(want == MaskCell::Lit);
        }
        assert_eq!(rasters.lit, lit);
    }

    #[test]
    fn classes_follow_nodata_then_range_then_mask() {
        // A 3x2 grid, light at column 0, row 0, 1 m cells, range 1.5 m.
        let range = Range {
            light_grid: (0.0, 0.0),
            cell: (1.0, 1.0),
            max_distance: 1.5,
        };
        check(
            3,
            &[1, 0, 1, 1, 0, 0],
            &[false, false, false, true, false, false],
            &range,
        );
        // A grid of several parallel chunks, mask and no-data at random.
        let (w, h) = (301, 257);
        let mut rng = raykit_core::rng::Pcg32::new(3);
        let mask: Vec<u8> = (0..w * h).map(|_| (rng.next_u32() & 1) as u8).collect();
        let nodata: Vec<bool> = (0..w * h)
            .map(|_| rng.next_u32().is_multiple_of(17))
            .collect();
        let range = Range {
            light_grid: (120.5, 90.25),
            cell: (2.0, 3.0),
            max_distance: 400.0,
        };
        check(w, &mask, &nodata, &range);
    }
}
