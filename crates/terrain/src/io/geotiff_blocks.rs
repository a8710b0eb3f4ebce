//! A compressed or tiled TIFF image, written by hand (the `tiff` crate's
//! encoder writes strips only, and GDAL 3.6 cannot decode its DEFLATE
//! strips): the samples cut into blocks, each compressed on its own, then
//! the directory's image tags. Tiles (TIFF 6.0, section 15) have the
//! layout's size, row-major from the top-left, those of the last row and
//! column padded with a fill sample; strips are runs of whole rows, about
//! 64 KiB each, the last one shorter.

use std::io::{Seek, Write};

use tiff::encoder::colortype::ColorType;
use tiff::encoder::compression::{CompressionAlgorithm, Deflate, DeflateLevel, Lzw, Packbits};
use tiff::encoder::{DirectoryEncoder, TiffKind, TiffValue};
use tiff::tags::Tag;
use tiff::TiffResult;

use super::geotiff_layout::TiffCompression;

/// A sample type the tiled writer can lay out as bytes (in the machine's
/// byte order, which the `tiff` crate's header declares).
pub trait TileSample: Copy {
    /// Append the bytes of `samples` to `out`.
    fn put_all(samples: impl Iterator<Item = Self>, out: &mut Vec<u8>);
}

impl TileSample for u8 {
    #[inline]
    fn put_all(samples: impl Iterator<Item = Self>, out: &mut Vec<u8>) {
        out.extend(samples);
    }
}

impl TileSample for f32 {
    #[inline]
    fn put_all(samples: impl Iterator<Item = Self>, out: &mut Vec<u8>) {
        out.reserve(4 * samples.size_hint().0);
        for s in samples {
            out.extend_from_slice(&s.to_ne_bytes());
        }
    }
}

/// `bytes` compressed by `compression` (the input itself for none).
fn compress(compression: TiffCompression, bytes: &[u8]) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::with_capacity(bytes.len() / 2);
    match compression {
        TiffCompression::None => out.extend_from_slice(bytes),
        TiffCompression::Deflate => {
            Deflate::with_level(DeflateLevel::Fast).write_to(&mut out, bytes)?;
        }
        TiffCompression::Lzw => {
            Lzw.write_to(&mut out, bytes)?;
        }
        TiffCompression::Packbits => {
            Packbits.write_to(&mut out, bytes)?;
        }
    }
    Ok(out)
}

/// Blocks `0..count`, each laid out by `block(index, bytes)` and compressed
/// on its own, in parallel, in order.
fn packed_blocks(
    count: usize,
    compression: TiffCompression,
    block: impl Fn(usize, &mut Vec<u8>) + Sync,
) -> std::io::Result<Vec<Vec<u8>>> {
    use rayon::prelude::*;
    (0..count)
        .into_par_iter()
        .map_init(Vec::new, |raw, k| {
            raw.clear();
            block(k, raw);
            compress(compression, raw)
        })
        .collect()
}

/// Offsets and byte counts of written blocks, for a directory's tags.
type BlockPlaces<K> = (
    Vec<<K as TiffKind>::OffsetType>,
    Vec<<K as TiffKind>::OffsetType>,
);

/// Writes `blocks` in order into directory `d`'s data.
fn write_blocks<W, K>(
    d: &mut DirectoryEncoder<'_, W, K>,
    blocks: &[Vec<u8>],
) -> TiffResult<BlockPlaces<K>>
where
    W: Write + Seek,
    K: TiffKind,
{
    let mut offsets = Vec::with_capacity(blocks.len());
    let mut counts = Vec::with_capacity(blocks.len());
    for packed in blocks {
        offsets.push(K::convert_offset(d.write_data(&packed[..])?)?);
        counts.push(K::convert_offset(packed.len() as u64)?);
    }
    Ok((offsets, counts))
}

/// The tags that describe one band of samples of type `C`.
fn write_sample_tags<W, K, C>(
    d: &mut DirectoryEncoder<'_, W, K>,
    width: usize,
    height: usize,
    compression: TiffCompression,
) -> TiffResult<()>
where
    W: Write + Seek,
    K: TiffKind,
    C: ColorType,
{
    d.write_tag(Tag::ImageWidth, u32::try_from(width)?)?;
    d.write_tag(Tag::ImageLength, u32::try_from(height)?)?;
    d.write_tag(Tag::BitsPerSample, C::BITS_PER_SAMPLE)?;
    d.write_tag(Tag::Compression, compression.tag_value())?;
    d.write_tag(Tag::PhotometricInterpretation, C::TIFF_VALUE.to_u16())?;
    d.write_tag(Tag::SamplesPerPixel, 1u16)?;
    d.write_tag(Tag::PlanarConfiguration, 1u16)?;
    let formats: Vec<u16> = C::SAMPLE_FORMAT.iter().map(|f| f.to_u16()).collect();
    d.write_tag(Tag::SampleFormat, &formats[..])?;
    Ok(())
}

/// Write the strips of `data` (`width` × `height`, rows from the top, each
/// sample through `fix`) and the image tags into directory `d`; the caller
/// adds its own tags and finishes the directory.
pub fn write_strips<W, K, C>(
    d: &mut DirectoryEncoder<'_, W, K>,
    width: usize,
    height: usize,
    data: &[C::Inner],
    compression: TiffCompression,
    fix: &(impl Fn(C::Inner) -> C::Inner + Sync),
) -> TiffResult<()>
where
    W: Write + Seek,
    K: TiffKind,
    C: ColorType,
    C::Inner: TileSample + Sync,
    [C::Inner]: TiffValue,
{
    let row_bytes = width * std::mem::size_of::<C::Inner>();
    let rows = (65536 / row_bytes.max(1)).clamp(1, height);
    let strips = packed_blocks(height.div_ceil(rows), compression, |k, raw| {
        let first = k * rows;
        let end = (first + rows).min(height);
        C::Inner::put_all(
            data[first * width..end * width].iter().map(|&s| fix(s)),
            raw,
        );
    })?;
    let (offsets, counts) = write_blocks(d, &strips)?;
    write_sample_tags::<W, K, C>(d, width, height, compression)?;
    d.write_tag(Tag::RowsPerStrip, u32::try_from(rows)?)?;
    d.write_tag(Tag::StripOffsets, K::convert_slice(&offsets))?;
    d.write_tag(Tag::StripByteCounts, K::convert_slice(&counts))?;
    Ok(())
}

/// Write the tiles of `data` (`width` × `height`, rows from the top, each
/// sample through `fix`) and the image tags into directory `d`; the caller
/// adds its own tags and finishes the directory.
#[allow(clippy::too_many_arguments)]
pub fn write_tiles<W, K, C>(
    d: &mut DirectoryEncoder<'_, W, K>,
    width: usize,
    height: usize,
    data: &[C::Inner],
    tile: (u32, u32),
    compression: TiffCompression,
    pad: C::Inner,
    fix: &(impl Fn(C::Inner) -> C::Inner + Sync),
) -> TiffResult<()>
where
    W: Write + Seek,
    K: TiffKind,
    C: ColorType,
    C::Inner: TileSample + Sync,
    [C::Inner]: TiffValue,
{
    let (tw, th) = (tile.0 as usize, tile.1 as usize);
    let (across, down) = (width.div_ceil(tw), height.div_ceil(th));
    let tiles = packed_blocks(across * down, compression, |k, raw| {
        let (tx, ty) = (k % across, k / across);
        let (col, inside) = (tx * tw, tw.min(width - tx * tw));
        for r in 0..th {
            let row = ty * th + r;
            // The tile's part of the row, then padding past the grid.
            let part = if row < height {
                &data[row * width + col..row * width + col + inside]
            } else {
                &[]
            };
            let samples = part.iter().map(|&s| fix(s));
            C::Inner::put_all(
                samples.chain(std::iter::repeat_n(pad, tw - part.len())),
                raw,
            );
        }
    })?;
    let (offsets, counts) = write_blocks(d, &tiles)?;
    write_sample_tags::<W, K, C>(d, width, height, compression)?;
    d.write_tag(Tag::TileWidth, tile.0)?;
    d.write_tag(Tag::TileLength, tile.1)?;
    d.write_tag(Tag::TileOffsets, K::convert_slice(&offsets))?;
    d.write_tag(Tag::TileByteCounts, K::convert_slice(&counts))?;
    Ok(())
}
