//! 8-bit RGB PNG output through the `image` crate, and palette PNG output
//! through the `png` crate, written atomically.

use crate::atomic::write_atomic;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};
use std::io;
use std::path::Path;

/// Write `rgb8` (`width × height` pixels, row-major from the top, 3 bytes per
/// pixel) as a PNG file at `path`, atomically.
pub fn write_png(path: &Path, width: u32, height: u32, rgb8: &[u8]) -> io::Result<()> {
    let expected = width as u64 * height as u64 * 3;
    if rgb8.len() as u64 != expected || width == 0 || height == 0 {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "{}: {width}x{height} RGB image needs {expected} bytes, got {}",
                path.display(),
                rgb8.len()
            ),
        ));
    }
    write_atomic(path, |w| {
        PngEncoder::new(w)
            .write_image(rgb8, width, height, ExtendedColorType::Rgb8)
            .map_err(io::Error::other)
    })
}

/// Write `pixels` (`width × height` palette indices, row-major from the
/// top) with `palette` (at most 256 RGB colours) as an 8-bit palette PNG at
/// `path`, atomically: a third of the RGB image's bytes for images of a few
/// colours, such as class maps.
pub fn write_png_indexed(
    path: &Path,
    width: u32,
    height: u32,
    palette: &[[u8; 3]],
    pixels: &[u8],
) -> io::Result<()> {
    let expected = width as u64 * height as u64;
    let bad = |what: String| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: {what}", path.display()),
        )
    };
    if pixels.len() as u64 != expected || width == 0 || height == 0 {
        return Err(bad(format!(
            "{width}x{height} palette image needs {expected} bytes, got {}",
            pixels.len()
        )));
    }
    if palette.is_empty() || palette.len() > 256 {
        return Err(bad(format!(
            "a palette has 1 to 256 colours, got {}",
            palette.len()
        )));
    }
    // The largest index first (a loop that compiles to vector operations),
    // the offending pixel only when there is one.
    let largest = pixels.iter().fold(0u8, |m, &p| m.max(p));
    if let Some(i) = (largest as usize >= palette.len())
        .then(|| pixels.iter().position(|&p| p as usize >= palette.len()))
        .flatten()
    {
        return Err(bad(format!(
            "pixel {i} is colour {} of a {}-colour palette",
            pixels[i],
            palette.len()
        )));
    }
    write_atomic(path, |w| {
        let mut encoder = ::png::Encoder::new(w, width, height);
        encoder.set_color(::png::ColorType::Indexed);
        encoder.set_depth(::png::BitDepth::Eight);
        encoder.set_palette(palette.concat());
        encoder.set_compression(::png::Compression::Fast);
        let mut writer = encoder.write_header().map_err(io::Error::other)?;
        writer.write_image_data(pixels).map_err(io::Error::other)?;
        writer.finish().map_err(io::Error::other)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn palette_png_reads_back_as_its_colours() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        let (w, h) = (9u32, 4u32);
        let palette = [[10, 20, 30], [200, 0, 5], [7, 7, 250]];
        let px: Vec<u8> = (0..w * h).map(|i| (i * 7 % 3) as u8).collect();
        write_png_indexed(&p, w, h, &palette, &px).unwrap();
        let img = image::open(&p).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (w, h));
        let want: Vec<u8> = px.iter().flat_map(|&i| palette[i as usize]).collect();
        assert_eq!(img.into_raw(), want);
        let q = dir.path().join("b.png");
        assert!(write_png_indexed(&q, w, h, &palette[..2], &px).is_err());
        assert!(write_png_indexed(&q, w, h + 1, &palette, &px).is_err());
        assert!(write_png_indexed(&q, w, h, &[], &px).is_err());
        assert!(!q.exists());
    }

    #[test]
    fn png_round_trips_through_the_decoder() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        let (w, h) = (7u32, 5u32);
        let px: Vec<u8> = (0..w * h * 3).map(|i| (i * 13 % 251) as u8).collect();
        write_png(&p, w, h, &px).unwrap();
        let img = image::open(&p).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (w, h));
        assert_eq!(img.into_raw(), px);
        assert!(write_png(&p, 2, 2, &px).is_err());
        assert!(write_png(&dir.path().join("b.png"), 0, 0, &[]).is_err());
        assert!(!dir.path().join("b.png").exists());
    }
}
