//! Binning: which set-up triangles overlap which horizontal band.

use rayon::prelude::*;

/// Triangles per binning task.
const CHUNK: usize = 1 << 14;

/// Triangle indices per band, kept as one list per (chunk of triangles,
/// band) so the binning runs in parallel without a merge; walking the
/// chunks in order visits a band's triangles in mesh order.
pub(crate) struct Bins {
    /// `chunks[c][band]`: indices of chunk `c`'s triangles overlapping `band`.
    chunks: Vec<Vec<Vec<u32>>>,
}

impl Bins {
    /// Bin `rows` (inclusive first and last image row of each triangle)
    /// into bands of `band_height` rows, `bands` in all.
    pub fn new(rows: &[(u32, u32)], band_height: u32, bands: usize) -> Bins {
        let band_height = band_height.max(1);
        let chunks = rows
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut lists = vec![Vec::new(); bands];
                for (i, &(y0, y1)) in chunk.iter().enumerate() {
                    let index = (c * CHUNK + i) as u32;
                    let last = ((y1 / band_height) as usize).min(bands.saturating_sub(1));
                    for list in &mut lists[(y0 / band_height) as usize..=last] {
                        list.push(index);
                    }
                }
                lists
            })
            .collect();
        Bins { chunks }
    }

    /// The triangles overlapping `band`, in order.
    pub fn band(&self, band: usize) -> impl Iterator<Item = u32> + '_ {
        self.chunks
            .iter()
            .flat_map(move |c| c[band].iter().copied())
    }
}
