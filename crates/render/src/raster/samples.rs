//! The image positions of the pixels' own sample rays, computed once per
//! image so that coverage is tested where each ray really passes (a
//! hardware rasterizer samples one position per pixel; ours may be jittered).

use super::screen::{Screen, U};
use raykit_core::Ray;
use rayon::prelude::*;

/// Per pixel (row-major) the image position of its sample ray, and bounds
/// that make coverage tests at those positions conservative.
pub(crate) struct Samples {
    /// Image position of each pixel's ray ([`Screen::sample`]).
    pub pos: Vec<[f32; 2]>,
    /// Bound on the rounding of a position (once from `f64`) and of its
    /// difference with a nearby integer: `2·U` times the largest coordinate
    /// magnitude.
    pub err: f32,
    /// How far, at most, a position lies outside its own pixel's square
    /// `[x, x+1] × [y, y+1]` (measured, not assumed: rounding of the
    /// caller's rays against the view, or jitter beyond the pixel).
    pub stray: f32,
}

impl Samples {
    /// Positions of `sample(x, y)` for every pixel; `None` when one is not
    /// finite or strays a pixel or more (then coverage falls back to the
    /// whole-pixel test).
    pub fn new(
        screen: &Screen,
        width: u32,
        height: u32,
        sample: &(dyn Fn(u32, u32) -> Ray + Sync),
    ) -> Option<Samples> {
        let n = width as usize * height as usize;
        let mut pos = vec![[0.0f32; 2]; n];
        let (big, stray, finite) = pos
            .par_chunks_mut(width as usize)
            .enumerate()
            .map(|(y, row)| {
                let (mut big, mut stray, mut finite) = (0.0f32, 0.0f32, true);
                for (x, p) in row.iter_mut().enumerate() {
                    *p = screen.sample(&sample(x as u32, y as u32));
                    let (fx, fy) = (x as f32, y as f32);
                    finite &= p[0].is_finite() && p[1].is_finite();
                    big = big.max(p[0].abs()).max(p[1].abs());
                    stray = stray
                        .max(fx - p[0])
                        .max(p[0] - fx - 1.0)
                        .max(fy - p[1])
                        .max(p[1] - fy - 1.0);
                }
                (big, stray, finite)
            })
            .reduce(
                || (0.0, 0.0, true),
                |a, b| (a.0.max(b.0), a.1.max(b.1), a.2 && b.2),
            );
        (finite && big.is_finite() && stray < 1.0).then(|| Samples {
            pos,
            err: 2.0 * U * big,
            stray: stray.max(0.0),
        })
    }
}
