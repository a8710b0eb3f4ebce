//! Two-dimensional gradient noise (Perlin 1985/2002) and its fractal sum
//! (fBm), with permutation and gradient tables drawn from [`Pcg32`] so that
//! the same seed gives the same terrain on every machine.

use raykit_core::glam::Vec2;
use raykit_core::rng::Pcg32;

const SIZE: usize = 256;

/// Perlin gradient noise on the integer lattice, values in about `[-0.7, 0.7]`,
/// zero at lattice points.
#[derive(Clone, Debug)]
pub struct GradientNoise {
    perm: [u8; SIZE],
    grads: [Vec2; SIZE],
}

impl GradientNoise {
    /// Tables drawn from `rng`: a shuffled permutation of `0..256` and 256
    /// unit gradients at uniformly random angles.
    pub fn new(rng: &mut Pcg32) -> Self {
        let mut perm: [u8; SIZE] = std::array::from_fn(|i| i as u8);
        for i in (1..SIZE).rev() {
            let j = rng.below(i as u32 + 1) as usize;
            perm.swap(i, j);
        }
        let grads = std::array::from_fn(|_| {
            let a = std::f32::consts::TAU * rng.next_f32();
            Vec2::new(a.cos(), a.sin())
        });
        GradientNoise { perm, grads }
    }

    #[inline]
    fn gradient(&self, ix: i32, iy: i32) -> Vec2 {
        let h = self.perm[(ix & 255) as usize] as usize;
        self.grads[self.perm[(h + (iy & 255) as usize) & 255] as usize]
    }

    /// Noise at `p`.
    pub fn sample(&self, p: Vec2) -> f32 {
        let cell = p.floor();
        let (ix, iy) = (cell.x as i32, cell.y as i32);
        let f = p - cell;
        let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let (sx, sy) = (fade(f.x), fade(f.y));
        let dot = |dx: i32, dy: i32| {
            self.gradient(ix + dx, iy + dy)
                .dot(f - Vec2::new(dx as f32, dy as f32))
        };
        let bottom = dot(0, 0) + sx * (dot(1, 0) - dot(0, 0));
        let top = dot(0, 1) + sx * (dot(1, 1) - dot(0, 1));
        bottom + sy * (top - bottom)
    }
}

/// Fractional Brownian motion: `octaves` layers of [`GradientNoise`], each at
/// twice the frequency (`lacunarity`) and `gain` times the amplitude of the
/// previous one, each shifted by its own random offset, the sum divided by
/// the sum of amplitudes.
#[derive(Clone, Debug)]
pub struct Fbm {
    noise: GradientNoise,
    offsets: Vec<Vec2>,
    /// Frequency factor between octaves.
    pub lacunarity: f32,
    /// Amplitude factor between octaves.
    pub gain: f32,
}

impl Fbm {
    /// An fBm of `octaves` octaves (lacunarity 2, gain 0.5) seeded from `seed`.
    pub fn new(seed: u64, octaves: usize) -> Self {
        let mut rng = Pcg32::with_stream(seed, 0x6e6f697365); // "noise"
        let noise = GradientNoise::new(&mut rng);
        let offsets = (0..octaves)
            .map(|_| Vec2::new(rng.range_f32(0.0, 256.0), rng.range_f32(0.0, 256.0)))
            .collect();
        Fbm {
            noise,
            offsets,
            lacunarity: 2.0,
            gain: 0.5,
        }
    }

    /// The normalised sum at `p` (about `[-0.7, 0.7]`, mostly `[-0.4, 0.4]`).
    pub fn sample(&self, p: Vec2) -> f32 {
        let (mut freq, mut amp) = (1.0, 1.0);
        let (mut sum, mut norm) = (0.0, 0.0);
        for &o in &self.offsets {
            sum += amp * self.noise.sample(p * freq + o);
            norm += amp;
            freq *= self.lacunarity;
            amp *= self.gain;
        }
        if norm > 0.0 {
            sum / norm
        } else {
            0.0
        }
    }
}
