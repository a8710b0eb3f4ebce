//! Rendered images: linear radiance and its 8-bit encoding.

use raykit_core::glam::Vec3;
use std::io::{self, Write};

/// Transfer function from linear radiance in `[0, 1]` (clamped) to 8 bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Encoding {
    /// The sRGB transfer curve (IEC 61966-2-1).
    Srgb,
    /// A pure power law `x^(1/γ)`.
    Gamma(f32),
}

impl Encoding {
    /// Encode one linear channel value, rounding to nearest.
    pub fn encode(self, linear: f32) -> u8 {
        let x = if linear.is_nan() {
            0.0
        } else {
            linear.clamp(0.0, 1.0)
        };
        let y = match self {
            Encoding::Srgb if x <= 0.003_130_8 => 12.92 * x,
            Encoding::Srgb => 1.055 * x.powf(1.0 / 2.4) - 0.055,
            Encoding::Gamma(g) => x.powf(1.0 / g.max(1e-3)),
        };
        (y * 255.0).round() as u8
    }
}

/// A rendered image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Encoded 8-bit RGB, 3 bytes a pixel, row-major.
    pub rgb: Vec<u8>,
    /// Linear radiance after exposure (before clamping and encoding), one
    /// entry a pixel, row-major.
    pub linear: Vec<Vec3>,
}

impl Image {
    /// How far `other` (the same size) is from this image: the number of
    /// pixels whose 8-bit colour differs by more than 2 levels in some
    /// channel, and the RMSE of the linear radiance.
    pub fn difference(&self, other: &Image) -> (usize, f64) {
        let differing = self
            .rgb
            .chunks_exact(3)
            .zip(other.rgb.chunks_exact(3))
            .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > 2))
            .count();
        let se: f64 = self
            .linear
            .iter()
            .zip(&other.linear)
            .map(|(p, q)| (*p - *q).length_squared() as f64 / 3.0)
            .sum();
        (differing, (se / self.linear.len().max(1) as f64).sqrt())
    }

    /// 8-bit RGB of |self − other| × 4 per channel, for looking at where two
    /// renders differ.
    pub fn difference_rgb(&self, other: &Image) -> Vec<u8> {
        self.rgb
            .iter()
            .zip(&other.rgb)
            .map(|(x, y)| x.abs_diff(*y).saturating_mul(4))
            .collect()
    }

    /// An image from linear radiance, encoded with `encoding`.
    pub fn from_linear(width: u32, height: u32, linear: Vec<Vec3>, encoding: Encoding) -> Image {
        assert_eq!(linear.len(), width as usize * height as usize);
        let rgb = linear
            .iter()
            .flat_map(|c| c.to_array().map(|x| encoding.encode(x)))
            .collect();
        Image {
            width,
            height,
            rgb,
            linear,
        }
    }

    /// The encoded colour of pixel (`x`, `y`).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Write as binary PPM (P6).
    pub fn write_ppm(&self, mut out: impl Write) -> io::Result<()> {
        write!(out, "P6\n{} {}\n255\n", self.width, self.height)?;
        out.write_all(&self.rgb)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_curve_end_points_and_middle() {
        let e = Encoding::Srgb;
        assert_eq!((e.encode(0.0), e.encode(1.0), e.encode(7.0)), (0, 255, 255));
        assert_eq!((e.encode(-1.0), e.encode(f32::NAN)), (0, 0));
        assert_eq!(e.encode(0.5), 188);
        assert_eq!(e.encode(0.002), 7);
        assert_eq!(Encoding::Gamma(2.0).encode(0.25), 128);
    }

    #[test]
    fn ppm_has_header_and_pixels() {
        let img = Image::from_linear(2, 1, vec![Vec3::ZERO, Vec3::ONE], Encoding::Srgb);
        assert_eq!(img.pixel(1, 0), [255; 3]);
        let mut out = Vec::new();
        img.write_ppm(&mut out).unwrap();
        assert_eq!(out, b"P6\n2 1\n255\n\0\0\0\xff\xff\xff");
    }
}
