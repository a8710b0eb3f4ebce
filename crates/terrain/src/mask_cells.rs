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

/// The class of every grid point of a `width`-wide grid (row-major): no
/// data where `nodata` is set, then out of range where `range` says so,
/// then lit where `mask` is 1, else in shadow (parallel).
pub fn classify(
    mask: &[u8],
    nodata: &[bool],
    width: usize,
    range: Option<&Range>,
) -> Vec<MaskCell> {
    let out_of_range = |i: usize| match range {
        Some(r) => {
            let (lc, lr) = r.light_grid;
            let (c, row) = ((i % width) as f64, (i / width) as f64);
            ((c - lc) * r.cell.0).hypot((row - lr) * r.cell.1) > r.max_distance
        }
        None => false,
    };
    use rayon::prelude::*;
    (0..mask.len())
        .into_par_iter()
        .map(|i| {
            if nodata[i] {
                MaskCell::NoData
            } else if out_of_range(i) {
                MaskCell::OutOfRange
            } else if mask[i] == 1 {
                MaskCell::Lit
            } else {
                MaskCell::Shadow
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_follow_nodata_then_range_then_mask() {
        // A 3x2 grid, light at column 0, row 0, 1 m cells, range 1.5 m.
        let mask = [1, 0, 1, 1, 0, 0];
        let nodata = [false, false, false, true, false, false];
        let range = Range {
            light_grid: (0.0, 0.0),
            cell: (1.0, 1.0),
            max_distance: 1.5,
        };
        let cells = classify(&mask, &nodata, 3, Some(&range));
        // Brute force: the distance of each cell from (0, 0).
        for (i, cell) in cells.iter().enumerate() {
            let (c, r) = ((i % 3) as f64, (i / 3) as f64);
            let expected = if nodata[i] {
                MaskCell::NoData
            } else if (c * c + r * r).sqrt() > 1.5 {
                MaskCell::OutOfRange
            } else if mask[i] == 1 {
                MaskCell::Lit
            } else {
                MaskCell::Shadow
            };
            assert_eq!(*cell, expected, "cell {i}");
        }
        let values = MaskValues {
            visible: 7,
            invisible: 3,
            out_of_range: 9,
            nodata: 255,
        };
        assert_eq!(MaskCell::OutOfRange.value(&values), 9);
        assert_eq!(MaskCell::NoData.value(&values), 255);
    }
}
