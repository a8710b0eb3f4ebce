//! Colour textures in linear RGBA, sampled bilinearly with repeat wrapping
//! (glTF's default sampler), for the base colour of materials.

use glam::{Vec2, Vec4};

/// A texture image: linear RGBA texels, rows top to bottom (texture
/// coordinate `v = 0` is the top row, as in glTF).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from (file name, URI or `image N`), for messages.
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Linear RGBA texels, row-major.
    pub texels: Vec<Vec4>,
}

impl Texture {
    /// A texture from linear texels; `texels.len()` must be `width · height`.
    pub fn new(name: impl Into<String>, width: u32, height: u32, texels: Vec<Vec4>) -> Texture {
        assert_eq!(texels.len(), width as usize * height as usize);
        Texture {
            name: name.into(),
            width,
            height,
            texels,
        }
    }

    /// Bilinear sample at texture coordinates `uv`, wrapping with repeat.
    /// Texel centres lie at `(i + 0.5) / width`.
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        if self.texels.is_empty() {
            return Vec4::ONE;
        }
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        if !x.is_finite() || !y.is_finite() {
            return self.texels[0];
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |i: i64, j: i64| self.texels[(j.rem_euclid(h) * w + i.rem_euclid(w)) as usize];
        let (i, j) = (x0 as i64, y0 as i64);
        let top = texel(i, j).lerp(texel(i + 1, j), fx);
        let bottom = texel(i, j + 1).lerp(texel(i + 1, j + 1), fx);
        top.lerp(bottom, fy)
    }
}

/// The sRGB transfer curve inverted: an 8-bit-style encoded value in
/// `[0, 1]` to linear (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_sampling_matches_hand_interpolation_and_wraps() {
        let t = Texture::new(
            "t",
            2,
            1,
            vec![Vec4::new(0.0, 0.0, 0.0, 1.0), Vec4::new(1.0, 2.0, 4.0, 1.0)],
        );
        // Texel centres.
        assert_eq!(t.sample(Vec2::new(0.25, 0.5)).x, 0.0);
        assert_eq!(t.sample(Vec2::new(0.75, 0.5)).y, 2.0);
        // Half way between the centres.
        assert!((t.sample(Vec2::new(0.5, 0.5)).z - 2.0).abs() < 1e-6);
        // Repeat: u = 1.25 is u = 0.25, and u = 0 lies between texel 1
        // (wrapped) and texel 0.
        assert_eq!(
            t.sample(Vec2::new(1.25, 3.5)),
            t.sample(Vec2::new(0.25, 0.5))
        );
        assert!((t.sample(Vec2::new(0.0, 0.5)).x - 0.5).abs() < 1e-6);
    }

    #[test]
    fn srgb_decoding_inverts_the_encoding_curve() {
        for i in 0..=255u32 {
            let c = i as f64 / 255.0;
            let lin = srgb_to_linear(c as f32) as f64;
            let back = if lin <= 0.003_130_8 {
                12.92 * lin
            } else {
                1.055 * lin.powf(1.0 / 2.4) - 0.055
            };
            assert!((back - c).abs() < 1e-5, "{i}: {back}");
        }
    }
}
