//! [`EquirectMap`]: a latitude-longitude environment map of linear RGB
//! texels, sampled bilinearly by direction.

use super::error::EnvError;
use super::mapping::dir_to_uv;
use raykit_core::glam::Vec3;
use std::path::Path;

/// The source name given to maps built in memory.
const MEMORY: &str = "<memory>";

/// An equirectangular environment map: `width × height` linear RGB `f32`
/// texels, rows top (`+Y`) to bottom (`-Y`), with an optional rotation about
/// `+Y` and an intensity scale applied by [`lookup`](Self::lookup).
///
/// Every texel is finite and `≥ 0`: construction replaces non-finite and
/// negative components by 0 and counts the texels it changed
/// ([`clamped_texels`](Self::clamped_texels)).
#[derive(Clone, Debug, PartialEq)]
pub struct EquirectMap {
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
    /// Rotation as a fraction of a turn in `[0, 1)`, added to `u`.
    turn: f32,
    rotation_deg: f32,
    intensity: f32,
    clamped: usize,
    source: String,
}

impl EquirectMap {
    /// A map from texels in memory (rows top to bottom). Fails when a side is
    /// zero or `texels.len() != width × height`.
    pub fn new(width: usize, height: usize, texels: Vec<[f32; 3]>) -> Result<Self, EnvError> {
        Self::from_texels(Path::new(MEMORY), width, height, texels)
    }

    /// [`new`](Self::new) with errors and [`source`](Self::source) naming `path`.
    pub(crate) fn from_texels(
        path: &Path,
        width: usize,
        height: usize,
        mut texels: Vec<[f32; 3]>,
    ) -> Result<Self, EnvError> {
        let invalid = |message: String| EnvError::Invalid {
            path: path.to_path_buf(),
            message,
        };
        if width == 0 || height == 0 {
            return Err(invalid(format!(
                "an environment map needs texels, this one is {width}x{height}"
            )));
        }
        if width.checked_mul(height) != Some(texels.len()) {
            return Err(invalid(format!(
                "a {width}x{height} map needs {} texels, got {}",
                width.saturating_mul(height),
                texels.len()
            )));
        }
        let mut clamped = 0;
        for t in &mut texels {
            let mut bad = false;
            for c in t.iter_mut() {
                if !(c.is_finite() && *c >= 0.0) {
                    *c = 0.0;
                    bad = true;
                }
            }
            clamped += bad as usize;
        }
        Ok(EquirectMap {
            width,
            height,
            texels,
            turn: 0.0,
            rotation_deg: 0.0,
            intensity: 1.0,
            clamped,
            source: path.display().to_string(),
        })
    }

    /// The same map turned by `degrees` about `+Y`, right-handed: after
    /// `+90°` what was seen along `-Z` is seen along `-X`. A non-finite angle
    /// counts as 0.
    pub fn with_rotation_deg(mut self, degrees: f32) -> Self {
        let degrees = if degrees.is_finite() { degrees } else { 0.0 };
        self.rotation_deg = degrees;
        // Turning the map by +θ shows at `u` what was at `u + θ/360`.
        self.turn = (degrees / 360.0).rem_euclid(1.0);
        self
    }

    /// The same map with every lookup scaled by `intensity`; a negative or
    /// non-finite scale counts as 0 (radiance stays finite and `≥ 0`).
    pub fn with_intensity(mut self, intensity: f32) -> Self {
        self.intensity = if intensity.is_finite() && intensity > 0.0 {
            intensity
        } else {
            0.0
        };
        self
    }

    /// Width in texels (longitude).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels (latitude).
    pub fn height(&self) -> usize {
        self.height
    }

    /// All texels, row-major, top row first.
    pub fn texels(&self) -> &[[f32; 3]] {
        &self.texels
    }

    /// The texel in column `x`, row `y` (row 0 at the top), if inside.
    pub fn texel(&self, x: usize, y: usize) -> Option<[f32; 3]> {
        (x < self.width && y < self.height).then(|| self.texels[y * self.width + x])
    }

    /// How many texels had a non-finite or negative component set to 0.
    pub fn clamped_texels(&self) -> usize {
        self.clamped
    }

    /// The rotation about `+Y` in degrees.
    pub fn rotation_deg(&self) -> f32 {
        self.rotation_deg
    }

    /// The intensity scale.
    pub fn intensity(&self) -> f32 {
        self.intensity
    }

    /// Where the map came from: its file, or `<memory>`.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The radiance seen along `dir` (any length): the bilinearly filtered
    /// map at [`dir_to_uv`](super::dir_to_uv)`(dir)` shifted by the rotation,
    /// times the intensity. Black for a zero or non-finite direction.
    pub fn lookup(&self, dir: Vec3) -> Vec3 {
        match dir_to_uv(dir) {
            Some((u, v)) => self.sample_uv(u + self.turn, v) * self.intensity,
            None => Vec3::ZERO,
        }
    }

    /// The image itself filtered bilinearly at texture coordinates `(u, v)`,
    /// ignoring rotation and intensity. Texel `(i, j)` has its centre at
    /// `((i + ½)/width, (j + ½)/height)`, where the texel is returned exactly;
    /// `u` wraps around (the first and last columns blend across the seam),
    /// `v` is clamped to the top and bottom rows. Black for non-finite input.
    pub fn sample_uv(&self, u: f32, v: f32) -> Vec3 {
        if !(u.is_finite() && v.is_finite()) {
            return Vec3::ZERO;
        }
        let (w, h) = (self.width as i64, self.height as i64);
        let x = u.rem_euclid(1.0) * self.width as f32 - 0.5;
        let y = v.clamp(0.0, 1.0) * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let i0 = (x0 as i64).rem_euclid(w);
        let i1 = (i0 + 1) % w;
        let j0 = (y0 as i64).clamp(0, h - 1);
        let j1 = (y0 as i64 + 1).clamp(0, h - 1);
        let t = |i: i64, j: i64| Vec3::from_array(self.texels[(j * w + i) as usize]);
        let top = t(i0, j0) * (1.0 - fx) + t(i1, j0) * fx;
        let bottom = t(i0, j1) * (1.0 - fx) + t(i1, j1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(w: usize, h: usize) -> EquirectMap {
        let texels = (0..w * h)
            .map(|k| [k as f32, (k % w) as f32, (k / w) as f32])
            .collect();
        EquirectMap::new(w, h, texels).unwrap()
    }

    #[test]
    fn texel_centres_are_exact_and_midpoints_average() {
        let m = ramp(8, 4);
        for j in 0..4 {
            for i in 0..8 {
                let got = m.sample_uv((i as f32 + 0.5) / 8.0, (j as f32 + 0.5) / 4.0);
                assert_eq!(got.to_array(), m.texel(i, j).unwrap());
            }
        }
        // Halfway between columns 2 and 3 of row 1.
        let got = m.sample_uv(3.0 / 8.0, 1.5 / 4.0);
        let a = Vec3::from_array(m.texel(2, 1).unwrap());
        let b = Vec3::from_array(m.texel(3, 1).unwrap());
        assert!((got - (a + b) * 0.5).abs().max_element() < 1e-5);
    }

    #[test]
    fn bad_texels_are_clamped_and_counted() {
        let t = vec![[1.0, -2.0, 0.5], [f32::NAN, 1.0, f32::INFINITY], [0.0; 3]];
        let m = EquirectMap::new(3, 1, t).unwrap();
        assert_eq!(m.clamped_texels(), 2);
        assert_eq!(m.texels(), &[[1.0, 0.0, 0.5], [0.0, 1.0, 0.0], [0.0; 3]]);
    }

    #[test]
    fn bad_shapes_are_errors_not_panics() {
        assert!(EquirectMap::new(0, 0, vec![]).is_err());
        assert!(EquirectMap::new(2, 2, vec![[0.0; 3]; 3]).is_err());
        let e = EquirectMap::new(usize::MAX, 2, vec![]).unwrap_err();
        assert!(e.to_string().contains("<memory>"), "{e}");
    }

    #[test]
    fn odd_inputs_give_finite_black_or_clamped_results() {
        let m = ramp(4, 2)
            .with_intensity(f32::NAN)
            .with_rotation_deg(f32::INFINITY);
        assert_eq!(m.intensity(), 0.0);
        assert_eq!(m.rotation_deg(), 0.0);
        let m = ramp(4, 2);
        assert_eq!(m.lookup(Vec3::ZERO), Vec3::ZERO);
        assert_eq!(m.sample_uv(f32::NAN, 0.5), Vec3::ZERO);
        assert!(m.sample_uv(-1e30, 1e30).is_finite());
        assert!(m.sample_uv(-1e-12, -3.0).is_finite());
    }
}
