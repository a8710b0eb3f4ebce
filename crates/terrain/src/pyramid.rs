//! The maximum mipmap of Tevs et al. (2008), as paper 004 uses it: a
//! quadtree stored as an image pyramid whose level 0 holds each cell's
//! highest corner and each higher texel the maximum of its (up to) four
//! children. A minimum pyramid is kept beside it, so a node's box spans
//! `[min, max]` of its surface.

use crate::heightfield::HeightField;
use rayon::prelude::*;

/// One level of the pyramid.
#[derive(Clone, Debug)]
pub struct Level {
    /// Texels along x.
    pub width: usize,
    /// Texels along y.
    pub height: usize,
    /// Highest surface point below each texel.
    pub max: Vec<f32>,
    /// Lowest surface point below each texel.
    pub min: Vec<f32>,
}

/// Levels from the cells (level 0) up to a single texel.
#[derive(Clone, Debug)]
pub struct MaxMipmap {
    /// `levels[0]` is per cell; the last level is 1 × 1.
    pub levels: Vec<Level>,
}

impl MaxMipmap {
    /// Build the pyramid of `field` (parallel over rows).
    pub fn new(field: &HeightField) -> MaxMipmap {
        let (cw, ch) = field.cells();
        let mut max = vec![0.0f32; cw * ch];
        let mut min = vec![0.0f32; cw * ch];
        max.par_chunks_mut(cw)
            .zip(min.par_chunks_mut(cw))
            .enumerate()
            .for_each(|(r, (mx, mn))| {
                for c in 0..cw {
                    let h = [
                        field.at(c, r),
                        field.at(c + 1, r),
                        field.at(c, r + 1),
                        field.at(c + 1, r + 1),
                    ];
                    mx[c] = h.iter().copied().fold(f32::MIN, f32::max);
                    mn[c] = h.iter().copied().fold(f32::MAX, f32::min);
                }
            });
        let mut levels = vec![Level {
            width: cw,
            height: ch,
            max,
            min,
        }];
        while levels.last().is_some_and(|l| l.width > 1 || l.height > 1) {
            let prev = levels.last().expect("a level exists");
            let (w, h) = (prev.width.div_ceil(2), prev.height.div_ceil(2));
            let mut max = vec![0.0f32; w * h];
            let mut min = vec![0.0f32; w * h];
            max.par_chunks_mut(w)
                .zip(min.par_chunks_mut(w))
                .enumerate()
                .for_each(|(j, (mx, mn))| {
                    for i in 0..w {
                        let (mut a, mut b) = (f32::MIN, f32::MAX);
                        for (ci, cj) in [
                            (2 * i, 2 * j),
                            (2 * i + 1, 2 * j),
                            (2 * i, 2 * j + 1),
                            (2 * i + 1, 2 * j + 1),
                        ] {
                            if ci < prev.width && cj < prev.height {
                                a = a.max(prev.max[cj * prev.width + ci]);
                                b = b.min(prev.min[cj * prev.width + ci]);
                            }
                        }
                        mx[i] = a;
                        mn[i] = b;
                    }
                });
            levels.push(Level {
                width: w,
                height: h,
                max,
                min,
            });
        }
        MaxMipmap { levels }
    }

    /// Index of the top level (1 × 1).
    pub fn top(&self) -> usize {
        self.levels.len() - 1
    }

    /// Cells covered by node (`i`, `j`) of `level`, clipped to the grid:
    /// columns `[x0, x1)` and rows `[y0, y1)`.
    pub fn extent(&self, level: usize, i: usize, j: usize) -> (usize, usize, usize, usize) {
        let l0 = &self.levels[0];
        let s = 1usize << level;
        (
            i * s,
            ((i + 1) * s).min(l0.width),
            j * s,
            ((j + 1) * s).min(l0.height),
        )
    }

    /// Bytes held by all levels.
    pub fn bytes(&self) -> usize {
        self.levels.iter().map(|l| 8 * l.max.len()).sum()
    }
}
