//! Binning: set-up triangles grouped by the horizontal bands of rows they
//! overlap (the Purcell-style stream tracer's rasterizer works band by band in parallel).

use rayon::prelude::*;

/// Triangles per setup and binning task.
const CHUNK: usize = 1 << 13;

/// Set-up triangles of one chunk of the mesh, and per band the indices of
/// those overlapping it.
struct Chunk<P> {
    items: Vec<P>,
    bands: Vec<Vec<u32>>,
}

/// The set-up triangles, kept per chunk of the mesh with one index list
/// per (chunk, band), so setup and binning run in parallel without a
/// merge; walking the chunks in order visits a band's triangles in mesh
/// order.
pub(crate) struct Bins<P> {
    chunks: Vec<Chunk<P>>,
}

impl<P: Send + Sync> Bins<P> {
    /// Set up triangles `0..count` with `setup` (`None`: invisible) and bin
    /// them by `rows` (inclusive first and last image row) into `bands`
    /// bands of `band_height` rows.
    pub fn new(
        count: usize,
        band_height: u32,
        bands: usize,
        setup: impl Fn(usize) -> Option<P> + Sync,
        rows: impl Fn(&P) -> (u32, u32) + Sync,
    ) -> Bins<P> {
        let band_height = band_height.max(1);
        let chunks = (0..count.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let items: Vec<P> = (c * CHUNK..count.min((c + 1) * CHUNK))
                    .filter_map(&setup)
                    .collect();
                let mut lists = vec![Vec::new(); bands];
                for (i, item) in items.iter().enumerate() {
                    let (y0, y1) = rows(item);
                    let last = ((y1 / band_height) as usize).min(bands.saturating_sub(1));
                    for list in &mut lists[(y0 / band_height) as usize..=last] {
                        list.push(i as u32);
                    }
                }
                Chunk {
                    items,
                    bands: lists,
                }
            })
            .collect();
        Bins { chunks }
    }

    /// The triangles overlapping `band`, in mesh order.
    pub fn band(&self, band: usize) -> impl Iterator<Item = &P> + '_ {
        self.chunks
            .iter()
            .flat_map(move |c| c.bands[band].iter().map(|&i| &c.items[i as usize]))
    }
}
