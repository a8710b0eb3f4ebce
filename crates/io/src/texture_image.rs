//! Decoding PNG and JPEG images into linear [`Texture`]s for base colours.
//!
//! Colour channels are taken as sRGB-encoded and converted to linear with
//! [`srgb_to_linear`]; alpha is linear already and only scaled to `[0, 1]`.
//! 8-bit images are divided by 255, 16-bit ones by 65535.

use raykit_core::glam::Vec4;
use raykit_core::texture::srgb_to_linear;
use raykit_core::Texture;
use std::io::Cursor;

/// The most memory the decoder may allocate (an 8-bit RGBA image of 64 Mi
/// texels, which becomes 1 GiB of linear texels); larger images are an error.
const MAX_DECODED_BYTES: u64 = 256 << 20;

/// Row order of the decoded texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rows {
    /// Rows as stored in the image, top first: `v = 0` is the top (glTF).
    TopFirst,
    /// Rows flipped, bottom first: `v = 0` is the bottom (OBJ/MTL).
    BottomFirst,
}

/// Decode the PNG or JPEG image `bytes` (format recognised from its
/// signature) into a texture called `name`. The error says why it could not
/// be decoded.
pub(crate) fn decode_texture(name: &str, bytes: &[u8], rows: Rows) -> Result<Texture, String> {
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(MAX_DECODED_BYTES);
    reader.limits(limits);
    if reader.format().is_none() {
        return Err("not a PNG or JPEG image (unrecognised signature)".into());
    }
    let img = reader.decode().map_err(|e| e.to_string())?;
    let (w, h) = (img.width(), img.height());
    let sixteen = img.color().bytes_per_pixel() / img.color().channel_count().max(1) >= 2;
    // Reserved fallibly: the linear texels take four times the decoder's
    // bytes, and several textures may be held at once.
    let mut texels: Vec<Vec4> = Vec::new();
    texels
        .try_reserve_exact(w as usize * h as usize)
        .map_err(|_| format!("no memory for its {w}×{h} texels"))?;
    if sixteen {
        let img = img.into_rgba16();
        texels.extend(img.pixels().map(|p| texel(p.0.map(|c| c as f32 / 65535.0))));
    } else {
        let img = img.into_rgba8();
        texels.extend(img.pixels().map(|p| texel(p.0.map(|c| c as f32 / 255.0))));
    }
    if rows == Rows::BottomFirst && w > 0 {
        // In place: the top and bottom rows swapped pairwise.
        let (w, h) = (w as usize, h as usize);
        for r in 0..h / 2 {
            let (top, bottom) = texels.split_at_mut((h - 1 - r) * w);
            top[r * w..(r + 1) * w].swap_with_slice(&mut bottom[..w]);
        }
    }
    if texels.len() != w as usize * h as usize {
        return Err(format!("decoded {} texels for {w}x{h}", texels.len()));
    }
    Ok(Texture {
        name: name.to_string(),
        width: w,
        height: h,
        texels,
    })
}

/// One texel: sRGB colour to linear, alpha kept.
fn texel(c: [f32; 4]) -> Vec4 {
    Vec4::new(
        srgb_to_linear(c[0]),
        srgb_to_linear(c[1]),
        srgb_to_linear(c[2]),
        c[3],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(w: u32, h: u32, px: &[[u8; 4]]) -> Vec<u8> {
        let mut out = Vec::new();
        let img = image::RgbaImage::from_fn(w, h, |x, y| image::Rgba(px[(y * w + x) as usize]));
        img.write_to(&mut Cursor::new(&mut out), image::ImageFormat::Png)
            .unwrap();
        out
    }

    #[test]
    fn rows_keep_or_flip_and_alpha_stays_linear() {
        let bytes = png(1, 2, &[[255, 0, 0, 128], [0, 0, 255, 255]]);
        let t = decode_texture("t", &bytes, Rows::TopFirst).unwrap();
        assert_eq!((t.width, t.height), (1, 2));
        assert_eq!(t.texels[0], Vec4::new(1.0, 0.0, 0.0, 128.0 / 255.0));
        let f = decode_texture("t", &bytes, Rows::BottomFirst).unwrap();
        assert_eq!(f.texels[0], t.texels[1]);
        assert_eq!(f.texels[1], t.texels[0]);
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        assert!(decode_texture("t", b"", Rows::TopFirst).is_err());
        assert!(decode_texture("t", b"hello world", Rows::TopFirst).is_err());
        let bytes = png(4, 4, &[[9; 4]; 16]);
        for cut in [8, 20, 33, bytes.len() - 5] {
            assert!(decode_texture("t", &bytes[..cut], Rows::TopFirst).is_err());
        }
    }
}
