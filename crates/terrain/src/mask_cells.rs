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
/// where the mask is 1, else in shadow.
#[derive(Clone, Copy, Debug)]
pub struct MaskClasses<'a> {
    /// Where the DEM has no data; none when it has data everywhere.
    pub nodata: Option<&'a [bool]>,
    /// Grid points per row.
    pub width: usize,
    /// The maximum distance from the light, if any.
    pub range: Option<&'a Range>,
}

/// How a mask's preview is coloured.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Preview {
    /// The written values index this palette (the classes present are
    /// written as different values).
    ByValue(Vec<[u8; 3]>),
    /// These palette indices ([`PREVIEW_PALETTE`]), row-major.
    Indices(Vec<u8>),
}

/// What a mask's written values leave to say: how its preview is
/// coloured, and the number of lit points.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaskRasters {
    /// The preview's colouring.
    pub preview: Preview,
    /// Grid points lit.
    pub lit: usize,
}

impl MaskClasses<'_> {
    /// The class of grid point `i` of `mask`.
    #[inline]
    pub fn at(&self, mask: &[u8], i: usize) -> MaskCell {
        if self.nodata.is_some_and(|n| n[i]) {
            MaskCell::NoData
        } else if self.out_of_range(i) {
            MaskCell::OutOfRange
        } else if mask[i] == 1 {
            MaskCell::Lit
        } else {
            MaskCell::Shadow
        }
    }

    /// Whether grid point `i` lies beyond the maximum distance.
    fn out_of_range(&self, i: usize) -> bool {
        self.range.is_some_and(|r| {
            let (lc, lr) = r.light_grid;
            let (c, row) = ((i % self.width) as f64, (i / self.width) as f64);
            ((c - lc) * r.cell.0).hypot((row - lr) * r.cell.1) > r.max_distance
        })
    }

    /// The classes that can occur: lit and shadow always, out of range
    /// with a range, no data with a no-data mask.
    fn present(&self) -> Vec<MaskCell> {
        let mut classes = vec![MaskCell::Lit, MaskCell::Shadow];
        if self.range.is_some() {
            classes.push(MaskCell::OutOfRange);
        }
        if self.nodata.is_some() {
            classes.push(MaskCell::NoData);
        }
        classes
    }

    /// A preview palette indexed by the written value, when the classes
    /// that can occur are written as different values: each class's value
    /// holds its colour ([`MaskCell::preview`]), other entries black.
    pub fn preview_palette(&self, values: &MaskValues) -> Option<Vec<[u8; 3]>> {
        let present = self.present();
        let mut palette = vec![None; 256];
        for class in present {
            let entry = &mut palette[class.value(values) as usize];
            if entry.is_some() {
                return None;
            }
            *entry = Some(class.preview());
        }
        let len = palette.iter().rposition(Option::is_some)? + 1;
        Some(palette[..len].iter().map(|c| c.unwrap_or([0; 3])).collect())
    }

    /// The class codes of `cells`, the grid points from `first` on of a
    /// mask (1 where lit): bit 0 lit, bit 1 out of range, bit 2 no data.
    fn codes(&self, first: usize, cells: &[u8]) -> Vec<u8> {
        let mut codes: Vec<u8> = cells.iter().map(|&m| u8::from(m == 1)).collect();
        if let Some(nodata) = self.nodata {
            let nodata = &nodata[first..first + cells.len()];
            for (c, &nd) in codes.iter_mut().zip(nodata) {
                *c |= u8::from(nd) << 2;
            }
        }
        if self.range.is_some() {
            for (j, c) in codes.iter_mut().enumerate() {
                *c |= u8::from(self.out_of_range(first + j)) << 1;
            }
        }
        codes
    }

    /// Replaces every grid point of `mask` (1 where lit) by its value under
    /// `values`, in one parallel pass over the grid, and returns the lit
    /// count and the preview's colouring: by value where
    /// [`MaskClasses::preview_palette`] has a palette, else by indices made
    /// in a pass before. Each point's class is a three-bit code (no data,
    /// out of range, lit) looked up in a table of eight, so that the loops
    /// have no branches; the values overwrite the mask, which saves a grid.
    pub fn write_values(&self, mask: &mut [u8], values: &MaskValues) -> MaskRasters {
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
        let preview = match self.preview_palette(values) {
            Some(palette) => Preview::ByValue(palette),
            None => {
                let index: [u8; 8] = std::array::from_fn(|c| class(c).preview_index());
                let mut indices = vec![0u8; mask.len()];
                indices
                    .par_chunks_mut(CHUNK)
                    .zip(mask.par_chunks(CHUNK))
                    .enumerate()
                    .for_each(|(k, (out, cells))| {
                        for (p, c) in out.iter_mut().zip(self.codes(k * CHUNK, cells)) {
                            *p = index[c as usize];
                        }
                    });
                Preview::Indices(indices)
            }
        };
        let value: [u8; 8] = std::array::from_fn(|c| class(c).value(values));
        let lit = mask
            .par_chunks_mut(CHUNK)
            .enumerate()
            .map(|(k, cells)| {
                let codes = self.codes(k * CHUNK, cells);
                let mut lit = 0;
                for (o, &c) in cells.iter_mut().zip(&codes) {
                    lit += usize::from(c == 1);
                    *o = value[c as usize];
                }
                lit
            })
            .sum();
        MaskRasters { preview, lit }
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

    /// Classes, values, preview and lit count of a `width`-wide grid
    /// against the brute force, under `values`.
    fn check(width: usize, mask: &[u8], nodata: &[bool], range: &Range, values: &MaskValues) {
        let classes = MaskClasses {
            nodata: Some(nodata),
            width,
            range: Some(range),
        };
        let mut written = mask.to_vec();
        let rasters = classes.write_values(&mut written, values);
        let by_value = classes.preview_palette(values).is_some();
        assert_eq!(matches!(rasters.preview, Preview::ByValue(_)), by_value);
        let mut lit = 0;
        for i in 0..mask.len() {
            let want = expected(i, width, mask, nodata, range);
            assert_eq!(classes.at(mask, i), want, "cell {i}");
            assert_eq!(written[i], want.value(values), "cell {i}");
            let colour = match &rasters.preview {
                Preview::ByValue(palette) => palette[written[i] as usize],
                Preview::Indices(indices) => PREVIEW_PALETTE[indices[i] as usize],
            };
            assert_eq!(colour, want.preview(), "cell {i}");
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
        // Four different values: the values index the preview's palette.
        let distinct = MaskValues {
            visible: 7,
            invisible: 3,
            out_of_range: 9,
            nodata: 255,
        };
        // Out of range and shadow share a value (0, as by default), so the
        // preview needs its own indices.
        let shared = MaskValues {
            visible: 255,
            invisible: 0,
            out_of_range: 0,
            nodata: 1,
        };
        for values in [&distinct, &shared] {
            check(
                3,
                &[1, 0, 1, 1, 0, 0],
                &[false, false, false, true, false, false],
                &range,
                values,
            );
        }
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
        for values in [&distinct, &shared] {
            check(w, &mask, &nodata, &range, values);
        }
    }

    /// Values shared only by classes that cannot occur still index the
    /// palette: without a range, out of range may share shadow's value.
    #[test]
    fn preview_palette_needs_different_values_for_the_classes_present() {
        let values = MaskValues {
            visible: 1,
            invisible: 0,
            out_of_range: 0,
            nodata: 255,
        };
        let range = Range {
            light_grid: (0.0, 0.0),
            cell: (1.0, 1.0),
            max_distance: 1.0,
        };
        let nodata = [false];
        let classes = |nodata, range| MaskClasses {
            nodata,
            width: 1,
            range,
        };
        let lit_shadow = [MaskCell::Shadow.preview(), MaskCell::Lit.preview()];
        assert_eq!(
            classes(None, None).preview_palette(&values),
            Some(lit_shadow.to_vec())
        );
        let with_nodata = classes(Some(&nodata[..]), None)
            .preview_palette(&values)
            .unwrap();
        assert_eq!(with_nodata.len(), 256);
        assert_eq!(with_nodata[..2], lit_shadow);
        assert_eq!(with_nodata[255], MaskCell::NoData.preview());
        assert_eq!(classes(None, Some(&range)).preview_palette(&values), None);
    }
}
