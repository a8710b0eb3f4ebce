//! GeoTIFFs with blocks left out. GDAL writes a strip or tile whose samples
//! are all nodata (or all zero, when there is no nodata) as no bytes at all
//! when asked to (`SPARSE_OK=TRUE`), and reads such a block back as nodata
//! or zero. The `tiff` crate decodes whole images only where every block
//! has bytes, so an image with missing blocks is decoded block by block
//! here, the missing ones filled as GDAL fills them.

use std::io::{Read, Seek};
use std::path::Path;

use tiff::decoder::{ChunkType, Decoder, DecodingResult};
use tiff::tags::Tag;

use super::DemError;

/// The heights of a block left out: no data (NaN) where the file has a
/// nodata value, zero otherwise, as GDAL reads it.
pub(super) fn absent_height(nodata: Option<f64>) -> f32 {
    if nodata.is_some() {
        f32::NAN
    } else {
        0.0
    }
}

/// The byte counts of the image's blocks (strips or tiles), from the tag
/// that the layout names; none when the tag is missing.
pub(super) fn block_byte_counts<R: Read + Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
) -> Result<Option<Vec<u64>>, DemError> {
    let tag = match dec.get_chunk_type() {
        ChunkType::Strip => Tag::StripByteCounts,
        ChunkType::Tile => Tag::TileByteCounts,
    };
    let err = |e: String| DemError::new(path, format!("tag {}", tag.to_u16()), e);
    match dec.find_tag(tag).map_err(|e| err(e.to_string()))? {
        None => Ok(None),
        Some(v) => v.into_u64_vec().map(Some).map_err(|e| err(e.to_string())),
    }
}

/// The image decoded block by block, where some blocks have no bytes
/// (`counts[k] == 0`): those filled with [`absent_height`], the others
/// decoded and converted by `to_heights`. `counts` must hold one entry per
/// block of the layout (checked: an error names the tag otherwise).
pub(super) fn read_sparse<R: Read + Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
    counts: &[u64],
    (width, height): (usize, usize),
    nodata: Option<f64>,
    to_heights: impl Fn(DecodingResult, Option<f64>) -> Vec<f32>,
) -> Result<Vec<f32>, DemError> {
    let (cw, ch) = dec.chunk_dimensions();
    let (cw, ch) = (cw as usize, ch as usize);
    let (tag, across) = match dec.get_chunk_type() {
        ChunkType::Strip => (Tag::StripByteCounts, 1),
        ChunkType::Tile => (Tag::TileByteCounts, width.div_ceil(cw.max(1))),
    };
    let blocks = across * height.div_ceil(ch.max(1));
    if cw == 0 || ch == 0 || counts.len() != blocks {
        return Err(DemError::new(
            path,
            format!("tag {}", tag.to_u16()),
            format!(
                "{} blocks listed; a {width}×{height} image in blocks of {cw}×{ch} has {blocks}",
                counts.len()
            ),
        ));
    }
    let mut heights = vec![absent_height(nodata); width * height];
    for (k, &count) in counts.iter().enumerate() {
        if count == 0 {
            continue;
        }
        let (x0, y0) = ((k % across) * cw, (k / across) * ch);
        let (bw, bh) = (cw.min(width - x0), ch.min(height - y0));
        let block = dec.read_chunk(k as u32).map_err(|e| {
            DemError::new(
                path,
                "image data",
                format!("cannot decode block {k} (of {blocks}): {e}"),
            )
        })?;
        let block = to_heights(block, nodata);
        if block.len() != bw * bh {
            return Err(DemError::new(
                path,
                "image data",
                format!(
                    "block {k} decoded to {} samples; expected {bw}×{bh}",
                    block.len()
                ),
            ));
        }
        for (row, samples) in block.chunks_exact(bw).enumerate() {
            let at = (y0 + row) * width + x0;
            heights[at..at + bw].copy_from_slice(samples);
        }
    }
    Ok(heights)
}
