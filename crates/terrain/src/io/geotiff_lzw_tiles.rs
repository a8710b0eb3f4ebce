//! LZW-compressed tiles, each decompressed whole. The `tiff` crate (0.11)
//! reads an edge tile row by row, skipping the padding between rows, and its
//! LZW reader stalls part way through some of the edge tiles GDAL writes
//! ("no lzw end code found", fixed upstream after 0.11.3): an SRTM tile of 1201²
//! samples in GDAL's default 256² tiles is refused, although every stream is
//! complete. Here each tile's stream is decompressed into a buffer of the
//! full tile (weezl, with TIFF's early code-size switch, Welch 1984 as TIFF
//! 6.0 section 13 adapts it), its predictor undone (TIFF 6.0 section 14;
//! Adobe's floating-point predictor, TIFF Technical Note 3), the samples
//! brought to this machine's byte order and the padding cut. Tiles are
//! independent, so rows of tiles are decoded in parallel.

use std::fs::File;
use std::path::Path;

use rayon::prelude::*;
use tiff::decoder::DecodingResult;

use super::file_at::read_at;
use super::DemError;

/// How a tile's samples are stored: bits per sample (8, 16, 32 or 64),
/// TIFF's SampleFormat (1 unsigned, 2 signed, 3 float), Predictor (1 none,
/// 2 horizontal differencing, 3 floating point) and the file's byte order.
#[derive(Clone, Copy, Debug)]
pub(super) struct TileSamples {
    pub bits: u16,
    pub format: u16,
    pub predictor: u16,
    pub little_endian: bool,
}

/// Where the tiles are and how large: their byte offsets and counts (one
/// each per tile, row-major from the top left; a count of 0 is a tile left
/// out, GDAL's sparse files) and the tile side in samples.
pub(super) struct TileLayout<'a> {
    pub offsets: &'a [u64],
    pub counts: &'a [u64],
    pub tile: (usize, usize),
}

/// The heights of a `width`×`height` image stored as LZW tiles. A tile left
/// out is `absent` throughout; the others are decompressed, their samples
/// converted by `to_heights` (which turns the nodata value into NaN).
pub(super) fn read_lzw_tiles(
    path: &Path,
    file: &File,
    layout: &TileLayout,
    (width, height): (usize, usize),
    samples: TileSamples,
    absent: f32,
    to_heights: impl Fn(DecodingResult) -> Vec<f32> + Sync,
) -> Result<Vec<f32>, DemError> {
    let (tw, th) = layout.tile;
    let across = width.div_ceil(tw);
    let blocks = across * height.div_ceil(th);
    if layout.offsets.len() != blocks || layout.counts.len() != blocks {
        return Err(DemError::new(
            path,
            "tag 324",
            format!(
                "{} tile offsets and {} byte counts; a {width}×{height} image in tiles of \
                 {tw}×{th} has {blocks}",
                layout.offsets.len(),
                layout.counts.len()
            ),
        ));
    }
    let mut heights = vec![absent; width * height];
    heights
        .par_chunks_mut(th * width)
        .enumerate()
        .try_for_each(|(tile_row, band)| {
            let bh = band.len() / width;
            for col in 0..across {
                let k = tile_row * across + col;
                if layout.counts[k] == 0 {
                    continue;
                }
                let x0 = col * tw;
                let bw = tw.min(width - x0);
                let tile = decode_tile(path, file, layout, k, samples)?;
                let values = to_heights(cropped(&tile, samples, tw, (bw, bh)));
                for (row, out) in band.chunks_exact_mut(width).enumerate() {
                    out[x0..x0 + bw].copy_from_slice(&values[row * bw..(row + 1) * bw]);
                }
            }
            Ok(())
        })?;
    Ok(heights)
}

/// Tile `k` decompressed and its predictor undone: the full tile's samples
/// in this machine's byte order.
fn decode_tile(
    path: &Path,
    file: &File,
    layout: &TileLayout,
    k: usize,
    samples: TileSamples,
) -> Result<Vec<u8>, DemError> {
    let (tw, th) = layout.tile;
    let bytes = (samples.bits / 8) as usize;
    let at = layout.offsets[k];
    let count = usize::try_from(layout.counts[k]).unwrap_or(usize::MAX);
    let need = tw * th * bytes;
    // An LZW code of at most 12 bits yields at least one byte, so a stream
    // that makes the tile fits in 1.5 times its size, clear codes aside;
    // bytes past twice that are never read.
    let count = count.min(need.saturating_mul(2) + 4096);
    let mut raw = vec![0u8; count];
    read_at(file, &mut raw, at)
        .map_err(|e| DemError::at_byte(path, at, format!("cannot read tile {k} there: {e}")))?;
    let mut out = vec![0u8; need];
    let mut lzw = weezl::decode::Decoder::with_tiff_size_switch(weezl::BitOrder::Msb, 8);
    let (mut input, mut filled) = (&raw[..], 0);
    while filled < need {
        let r = lzw.decode_bytes(input, &mut out[filled..]);
        input = &input[r.consumed_in..];
        filled += r.consumed_out;
        match r.status {
            Ok(weezl::LzwStatus::Ok) => {}
            Ok(weezl::LzwStatus::Done | weezl::LzwStatus::NoProgress) => break,
            Err(e) => {
                return Err(DemError::at_byte(
                    path,
                    at,
                    format!("tile {k}: corrupt LZW stream: {e}"),
                ))
            }
        }
    }
    if filled < need {
        return Err(DemError::at_byte(
            path,
            at,
            format!(
                "tile {k} decompresses to {filled} bytes; a {tw}×{th} tile of {bytes}-byte \
                 samples needs {need}"
            ),
        ));
    }
    for row in out.chunks_exact_mut(tw * bytes) {
        undo_predictor(row, samples);
    }
    Ok(out)
}

/// One row of a tile as stored, in place: the predictor undone and each
/// sample in this machine's byte order.
fn undo_predictor(row: &mut [u8], s: TileSamples) {
    let bytes = (s.bits / 8) as usize;
    if s.predictor == 3 {
        // Bytewise differences across the row, then the samples' bytes
        // gathered from planes that run most significant first.
        for i in 1..row.len() {
            row[i] = row[i].wrapping_add(row[i - 1]);
        }
        let planes = row.to_vec();
        let n = row.len() / bytes;
        for (i, sample) in row.chunks_exact_mut(bytes).enumerate() {
            for (j, b) in sample.iter_mut().enumerate() {
                let plane = if cfg!(target_endian = "little") {
                    bytes - 1 - j
                } else {
                    j
                };
                *b = planes[plane * n + i];
            }
        }
        return;
    }
    macro_rules! native {
        ($t:ty) => {{
            let mut prev: $t = 0;
            for sample in row.chunks_exact_mut(std::mem::size_of::<$t>()) {
                let b = sample.try_into().expect("sample width");
                let mut v = if s.little_endian {
                    <$t>::from_le_bytes(b)
                } else {
                    <$t>::from_be_bytes(b)
                };
                if s.predictor == 2 {
                    v = v.wrapping_add(prev);
                    prev = v;
                }
                sample.copy_from_slice(&v.to_ne_bytes());
            }
        }};
    }
    match bytes {
        1 => native!(u8),
        2 => native!(u16),
        4 => native!(u32),
        _ => native!(u64),
    }
}

/// The `bw`×`bh` samples at the top left of a decoded tile `tw` samples
/// wide, typed by the sample format.
fn cropped(tile: &[u8], s: TileSamples, tw: usize, (bw, bh): (usize, usize)) -> DecodingResult {
    let bytes = (s.bits / 8) as usize;
    let rows = || {
        tile.chunks_exact(tw * bytes)
            .take(bh)
            .flat_map(move |row| row[..bw * bytes].chunks_exact(bytes))
    };
    macro_rules! typed {
        ($variant:ident, $t:ty) => {
            DecodingResult::$variant(
                rows()
                    .map(|b| <$t>::from_ne_bytes(b.try_into().expect("sample width")))
                    .collect(),
            )
        };
    }
    match (s.format, s.bits) {
        (3, 32) => typed!(F32, f32),
        (3, _) => typed!(F64, f64),
        (2, 8) => typed!(I8, i8),
        (2, 16) => typed!(I16, i16),
        (2, _) => typed!(I32, i32),
        (_, 8) => typed!(U8, u8),
        (_, 16) => typed!(U16, u16),
        _ => typed!(U32, u32),
    }
}
