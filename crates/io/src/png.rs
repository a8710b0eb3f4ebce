//! 8-bit RGB PNG output through the `image` crate, written atomically.

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

#[cfg(test)]
mod tests {
    use super::*;

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
