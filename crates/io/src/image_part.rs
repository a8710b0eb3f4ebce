//! Parts of a split image: an 8-bit RGB PNG of one rectangle of a larger
//! picture, which carries its place in the picture in a `tEXt` chunk
//! (keyword [`PART_KEYWORD`]), so that parts rendered by separate processes
//! can be checked and assembled without any other file.

use crate::atomic::write_atomic;
use crate::error::{ErrorKind, LoadError, Location};
use std::io;
use std::path::Path;

/// `tEXt` keyword of a part's placement.
pub const PART_KEYWORD: &str = "raykit-part";

/// Longest side of a picture that raykit renders (and so of a picture its
/// parts may claim).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Where a part sits: a rectangle of a `full_width` × `full_height` picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImagePart {
    /// Left column in the picture.
    pub x: u32,
    /// Top row in the picture.
    pub y: u32,
    /// Width of the part.
    pub width: u32,
    /// Height of the part.
    pub height: u32,
    /// Width of the whole picture.
    pub full_width: u32,
    /// Height of the whole picture.
    pub full_height: u32,
    /// What the whole picture shows, as a fingerprint of the scene and
    /// settings it was rendered from (0: not recorded), so that parts of
    /// different pictures of one size are not merged.
    pub picture: u64,
}

impl ImagePart {
    /// The placement as the text chunk holds it:
    /// `x=X y=Y width=W height=H of FWxFH`, then ` picture=HEX` where the
    /// fingerprint is recorded.
    pub fn to_text(&self) -> String {
        let mut text = format!(
            "x={} y={} width={} height={} of {}x{}",
            self.x, self.y, self.width, self.height, self.full_width, self.full_height
        );
        if self.picture != 0 {
            text += &format!(" picture={:016x}", self.picture);
        }
        text
    }

    /// Parse [`ImagePart::to_text`]'s form; `None` if it is not that.
    pub fn parse(text: &str) -> Option<ImagePart> {
        let mut words = text.split_whitespace();
        let mut field = |name: &str| -> Option<u32> {
            words
                .next()?
                .strip_prefix(name)?
                .strip_prefix('=')?
                .parse()
                .ok()
        };
        let (x, y, width, height) = (field("x")?, field("y")?, field("width")?, field("height")?);
        if words.next()? != "of" {
            return None;
        }
        let (fw, fh) = words.next()?.split_once('x')?;
        let picture = match words.next() {
            None => 0,
            Some(w) => u64::from_str_radix(w.strip_prefix("picture=")?, 16).ok()?,
        };
        if words.next().is_some() {
            return None;
        }
        Some(ImagePart {
            x,
            y,
            width,
            height,
            full_width: fw.parse().ok()?,
            full_height: fh.parse().ok()?,
            picture,
        })
    }

    /// Whether the rectangle is non-empty and lies inside the picture, whose
    /// sides are at most [`MAX_IMAGE_SIDE`].
    pub fn fits(&self) -> bool {
        self.full_width <= MAX_IMAGE_SIDE
            && self.full_height <= MAX_IMAGE_SIDE
            && self.width > 0
            && self.height > 0
            && self.x as u64 + self.width as u64 <= self.full_width as u64
            && self.y as u64 + self.height as u64 <= self.full_height as u64
    }
}

/// Write `rgb8` (`part.width × part.height` pixels, row-major from the top,
/// 3 bytes each) as a PNG at `path` with `part` in its text chunk,
/// atomically.
pub fn write_png_part(path: &Path, part: &ImagePart, rgb8: &[u8]) -> io::Result<()> {
    let expected = part.width as u64 * part.height as u64 * 3;
    if !part.fits() || rgb8.len() as u64 != expected {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "{}: part {} needs {expected} bytes inside its picture, got {}",
                path.display(),
                part.to_text(),
                rgb8.len()
            ),
        ));
    }
    write_atomic(path, |w| {
        let mut encoder = ::png::Encoder::new(w, part.width, part.height);
        encoder.set_color(::png::ColorType::Rgb);
        encoder.set_depth(::png::BitDepth::Eight);
        encoder
            .add_text_chunk(PART_KEYWORD.to_string(), part.to_text())
            .map_err(io::Error::other)?;
        let mut writer = encoder.write_header().map_err(io::Error::other)?;
        writer.write_image_data(rgb8).map_err(io::Error::other)?;
        writer.finish().map_err(io::Error::other)
    })
}

/// Read a part written by [`write_png_part`]: its placement and its pixels
/// (3 bytes each, row-major). Errors name the file: a PNG that is not 8-bit
/// RGB, one without the placement chunk, or one whose size disagrees with
/// it.
pub fn read_png_part(path: &Path) -> Result<(ImagePart, Vec<u8>), LoadError> {
    let (part, mut reader) = open_png_part(path)?;
    let malformed = |m: String| LoadError::new(path, ErrorKind::Malformed, Location::File, m);
    let (width, height) = (part.width, part.height);
    let mut rgb = vec![0u8; reader.output_buffer_size().unwrap_or(0)];
    let frame = reader
        .next_frame(&mut rgb)
        .map_err(|e| malformed(format!("pixels: {e}")))?;
    rgb.truncate(frame.buffer_size());
    if rgb.len() as u64 != width as u64 * height as u64 * 3 {
        return Err(malformed(format!(
            "{} bytes of pixels for {width}x{height} RGB",
            rgb.len()
        )));
    }
    Ok((part, rgb))
}

/// The placement of the PNG part at `path`, checked as [`read_png_part`]
/// checks it, without decoding its pixels.
pub(crate) fn read_png_placement(path: &Path) -> Result<ImagePart, LoadError> {
    open_png_part(path).map(|(part, _)| part)
}

/// The placement of the PNG part at `path` and the reader positioned at its
/// pixels.
fn open_png_part(
    path: &Path,
) -> Result<(ImagePart, ::png::Reader<io::BufReader<std::fs::File>>), LoadError> {
    let file = std::fs::File::open(path).map_err(|e| LoadError::io(path, "open", e))?;
    let malformed = |m: String| LoadError::new(path, ErrorKind::Malformed, Location::File, m);
    let decoder = ::png::Decoder::new(io::BufReader::new(file));
    let reader = decoder
        .read_info()
        .map_err(|e| malformed(format!("not a readable PNG: {e}")))?;
    let info = reader.info();
    let (color, depth) = (info.color_type, info.bit_depth);
    if color != ::png::ColorType::Rgb || depth != ::png::BitDepth::Eight {
        return Err(malformed(format!(
            "a part must be 8-bit RGB, this PNG is {color:?} with {depth:?}-bit samples"
        )));
    }
    let (width, height) = (info.width, info.height);
    let text = info
        .uncompressed_latin1_text
        .iter()
        .find(|t| t.keyword == PART_KEYWORD)
        .map(|t| t.text.clone());
    let text = text.ok_or_else(|| {
        malformed(format!(
            "no '{PART_KEYWORD}' text chunk: not a part of a split render"
        ))
    })?;
    let part = ImagePart::parse(&text).ok_or_else(|| {
        malformed(format!(
            "'{PART_KEYWORD}' chunk '{text}' is not 'x=X y=Y width=W height=H of WxH'"
        ))
    })?;
    if !part.fits() || (part.width, part.height) != (width, height) {
        return Err(malformed(format!(
            "the image is {width}x{height}, but its placement says {text} (it must be that size and lie inside the picture, of sides at most {MAX_IMAGE_SIDE})"
        )));
    }
    Ok((part, reader))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A placement that claims a picture larger than raykit renders does
    /// not fit, however it lies inside it, so merging never allocates it.
    #[test]
    fn pictures_beyond_the_largest_side_do_not_fit() {
        let claim = |w: u32, h: u32| {
            ImagePart::parse(&format!("x=0 y=12 width=32 height=12 of {w}x{h}")).unwrap()
        };
        assert!(claim(32, 24).fits());
        assert!(claim(MAX_IMAGE_SIDE, 24).fits());
        assert!(!claim(MAX_IMAGE_SIDE + 1, 24).fits());
        assert!(!claim(32, u32::MAX).fits());
        assert!(!claim(u32::MAX, u32::MAX).fits());
    }

    #[test]
    fn a_part_round_trips_and_plain_pngs_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("part.png");
        let part = ImagePart {
            x: 3,
            y: 10,
            width: 5,
            height: 4,
            full_width: 9,
            full_height: 20,
            picture: 0xfeed_0123_4567_89ab,
        };
        let rgb: Vec<u8> = (0..5 * 4 * 3).map(|i| (i * 7 % 253) as u8).collect();
        write_png_part(&p, &part, &rgb).unwrap();
        // The `image` crate decodes the same pixels.
        let decoded = image::open(&p).unwrap().to_rgb8();
        assert_eq!(decoded.dimensions(), (5, 4));
        assert_eq!(decoded.as_raw(), &rgb);
        assert_eq!(read_png_part(&p).unwrap(), (part, rgb.clone()));

        let plain = dir.path().join("plain.png");
        crate::write_png(&plain, 5, 4, &rgb).unwrap();
        let e = read_png_part(&plain).unwrap_err().to_string();
        assert!(e.contains("plain.png") && e.contains(PART_KEYWORD), "{e}");

        let outside = ImagePart { x: 6, ..part };
        assert!(write_png_part(&dir.path().join("o.png"), &outside, &rgb).is_err());
        assert!(read_png_part(&dir.path().join("missing.png")).is_err());
    }

    #[test]
    fn placement_text_parses_back_and_rejects_other_text() {
        let part = ImagePart {
            x: 0,
            y: 7,
            width: 640,
            height: 120,
            full_width: 640,
            full_height: 480,
            picture: 0,
        };
        assert_eq!(ImagePart::parse(&part.to_text()), Some(part));
        let pictured = ImagePart {
            picture: 0x0123_4567_89ab_cdef,
            ..part
        };
        let text = pictured.to_text();
        assert!(text.ends_with(" picture=0123456789abcdef"), "{text}");
        assert_eq!(ImagePart::parse(&text), Some(pictured));
        for bad in [
            "",
            "x=1",
            "x=0 y=7 width=640 height=120 of 640",
            "x=0 y=7 width=640 height=120 of 640x480 extra",
            "x=0 y=7 width=640 height=120 of 640x480 picture=xyz",
            "x=0 y=7 width=640 height=120 of 640x480 picture=1 extra",
            "y=0 x=7 width=1 height=1 of 2x2",
        ] {
            assert_eq!(ImagePart::parse(bad), None, "{bad}");
        }
    }
}
