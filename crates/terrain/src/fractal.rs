//! A deterministic fractal terrain for tests and benchmarks: diamond-square
//! midpoint displacement on a (2^k + 1)² grid, cropped to the size asked
//! for, rescaled to 0..2000 m, with 10 m pixels.
//!
//! The random displacement of every point comes from a [`Pcg32`] seeded by
//! the seed on a stream named by (level, pass, row), so the result depends
//! only on the arguments, not on how rayon splits the rows over threads.

use raykit_core::rng::Pcg32;
use rayon::prelude::*;

use crate::dem::{Dem, GeoRef};

/// Highest height of a [`fractal`] DEM, in metres (the lowest is 0).
pub const FRACTAL_MAX_HEIGHT_M: f32 = 2000.0;

/// Pixel size of a [`fractal`] DEM, in metres.
pub const FRACTAL_PIXEL_M: f64 = 10.0;

/// A `size` × `size` fractal DEM from `seed`.
///
/// `roughness` is the factor by which the displacement shrinks at each
/// halving of the step: 0.5 gives smooth hills (fractal dimension 2), 0.6 to
/// 0.7 rugged mountains; it is clamped to 0..=1 (NaN counts as 0.5).
/// Heights span exactly 0..[`FRACTAL_MAX_HEIGHT_M`] (all 0 for `size` 1;
/// `size` 0 gives an empty DEM). Pixels are [`FRACTAL_PIXEL_M`] metres with
/// the top-left corner at (0, size × 10 m), not geographic.
///
/// Works in place on one `f32` grid of (2^k + 1)² samples, the smallest
/// holding `size`² (16385² = 1 GiB for `size` 16384), in parallel over
/// rows; the crop reuses the same allocation.
pub fn fractal(size: usize, seed: u64, roughness: f32) -> Dem {
    let roughness = if roughness.is_nan() {
        0.5
    } else {
        roughness.clamp(0.0, 1.0)
    };
    let n = size.max(2).saturating_sub(1).next_power_of_two() + 1;
    let mut grid = vec![0f32; n * n];

    let mut rng = Pcg32::with_stream(seed, u64::MAX >> 2);
    for i in [0, n - 1, n * (n - 1), n * n - 1] {
        grid[i] = rng.range_f32(-1.0, 1.0);
    }
    let mut amp = 1.0f32;
    let mut step = n - 1;
    let mut level = 0u64;
    while step >= 2 {
        let h = step / 2;
        let stream = |pass: u64, row: usize| (level << 34) | (pass << 32) | row as u64;
        // Square step: centres of the step × step squares from their corners.
        rows_pass(
            &mut grid,
            n,
            |r| r % step == h,
            |r, row, reads| {
                let (up, down) = (reads[r - h].unwrap_or(&[]), reads[r + h].unwrap_or(&[]));
                let mut rng = Pcg32::with_stream(seed, stream(0, r));
                for c in (h..n).step_by(step) {
                    let avg = 0.25 * (up[c - h] + up[c + h] + down[c - h] + down[c + h]);
                    row[c] = avg + amp * rng.range_f32(-1.0, 1.0);
                }
            },
        );
        // Diamond step, rows through the corners: edge midpoints between
        // two corners of the same row and the centres above and below.
        rows_pass(
            &mut grid,
            n,
            |r| r % step == 0,
            |r, row, reads| {
                let mut rng = Pcg32::with_stream(seed, stream(1, r));
                for c in (h..n).step_by(step) {
                    let (mut sum, mut cnt) = (row[c - h] + row[c + h], 2.0);
                    if let Some(up) = r.checked_sub(h).and_then(|i| reads[i]) {
                        sum += up[c];
                        cnt += 1.0;
                    }
                    if let Some(down) = reads.get(r + h).copied().flatten() {
                        sum += down[c];
                        cnt += 1.0;
                    }
                    row[c] = sum / cnt + amp * rng.range_f32(-1.0, 1.0);
                }
            },
        );
        // Diamond step, rows through the centres: edge midpoints between
        // two corners above and below and the centres left and right.
        rows_pass(
            &mut grid,
            n,
            |r| r % step == h,
            |r, row, reads| {
                let (up, down) = (reads[r - h].unwrap_or(&[]), reads[r + h].unwrap_or(&[]));
                let mut rng = Pcg32::with_stream(seed, stream(2, r));
                for c in (0..n).step_by(step) {
                    let (mut sum, mut cnt) = (up[c] + down[c], 2.0);
                    if c >= h {
                        sum += row[c - h];
                        cnt += 1.0;
                    }
                    if c + h < n {
                        sum += row[c + h];
                        cnt += 1.0;
                    }
                    row[c] = sum / cnt + amp * rng.range_f32(-1.0, 1.0);
                }
            },
        );
        amp *= roughness;
        step = h;
        level += 1;
    }

    // Crop to size × size in place (rows only move towards the start).
    for r in 1..size {
        grid.copy_within(r * n..r * n + size, r * size);
    }
    grid.truncate(size * size);
    grid.shrink_to_fit();

    let (lo, hi) = grid
        .par_chunks(1 << 16)
        .map(|c| {
            c.iter()
                .fold((f32::MAX, f32::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)))
        })
        .reduce(|| (f32::MAX, f32::MIN), |a, b| (a.0.min(b.0), a.1.max(b.1)));
    let k = if hi > lo {
        FRACTAL_MAX_HEIGHT_M / (hi - lo)
    } else {
        0.0
    };
    grid.par_iter_mut()
        .for_each(|v| *v = ((*v - lo) * k).clamp(0.0, FRACTAL_MAX_HEIGHT_M));

    Dem {
        width: size,
        height: size,
        heights: grid,
        nodata: None,
        georef: GeoRef {
            origin_x: 0.0,
            origin_y: size as f64 * FRACTAL_PIXEL_M,
            pixel_width: FRACTAL_PIXEL_M,
            pixel_height: -FRACTAL_PIXEL_M,
            ..GeoRef::default()
        },
    }
}

/// Runs `f(row index, row, other rows)` in parallel on every row `r` of the
/// `n`-wide `grid` with `write(r)`; the other rows are readable (as `Some`)
/// and the written ones are `None`, so passes that read only rows they do not
/// write need no locking.
fn rows_pass(
    grid: &mut [f32],
    n: usize,
    write: impl Fn(usize) -> bool,
    f: impl Fn(usize, &mut [f32], &[Option<&[f32]>]) + Sync,
) {
    let mut writes: Vec<(usize, &mut [f32])> = Vec::new();
    let mut reads: Vec<Option<&[f32]>> = vec![None; n];
    for (r, row) in grid.chunks_mut(n).enumerate() {
        if write(r) {
            writes.push((r, row));
        } else {
            reads[r] = Some(row);
        }
    }
    writes
        .into_par_iter()
        .for_each(|(r, row)| f(r, row, &reads));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(v: &[f32]) -> (f64, f64) {
        let n = v.len() as f64;
        let mean = v.iter().map(|&x| x as f64).sum::<f64>() / n;
        let var = v.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / n;
        (mean, var.sqrt())
    }

    #[test]
    fn same_seed_same_terrain_on_any_thread_count() {
        let a = fractal(257, 42, 0.55);
        let b = fractal(257, 42, 0.55);
        assert_eq!(a, b);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let c = one.install(|| fractal(257, 42, 0.55));
        assert_eq!(a, c);
        let d = fractal(257, 43, 0.55);
        let differ = a
            .heights
            .iter()
            .zip(&d.heights)
            .filter(|(x, y)| x != y)
            .count();
        assert!(
            differ > a.heights.len() * 9 / 10,
            "only {differ} samples differ"
        );
    }

    #[test]
    fn heights_span_the_range_and_are_spatially_coherent() {
        let mut relative_steps = Vec::new();
        for (seed, roughness) in [(1, 0.5), (2, 0.6), (3, 0.7)] {
            let dem = fractal(513, seed, roughness);
            assert_eq!(
                (dem.width, dem.height, dem.heights.len()),
                (513, 513, 513 * 513)
            );
            assert_eq!(dem.range(), Some((0.0, FRACTAL_MAX_HEIGHT_M)));
            let (mean, sd) = stats(&dem.heights);
            assert!((200.0..1800.0).contains(&mean), "seed {seed}: mean {mean}");
            assert!(sd > 100.0, "seed {seed}: sd {sd}");
            // Neighbours are far closer than random pairs would be.
            let steps: Vec<f32> = dem
                .heights
                .chunks(513)
                .flat_map(|r| r.windows(2).map(|w| (w[1] - w[0]).abs()))
                .collect();
            let (mean_step, _) = stats(&steps);
            assert!(
                mean_step < sd * 0.2,
                "seed {seed}: mean step {mean_step}, sd {sd}"
            );
            println!("roughness {roughness}: mean {mean:.0} sd {sd:.0} mean step {mean_step:.2} m");
            relative_steps.push(mean_step / sd);
        }
        // Rougher terrain has relatively bigger steps.
        assert!(
            relative_steps.windows(2).all(|w| w[0] < w[1]),
            "{relative_steps:?}"
        );
        assert_eq!(fractal(65, 9, 0.5).georef.pixel_width, FRACTAL_PIXEL_M);
    }

    #[test]
    fn crop_is_the_corner_of_the_full_grid() {
        // 300 and 513 share the 513² grid; only the rescaling differs.
        let full = fractal(513, 5, 0.6);
        let part = fractal(300, 5, 0.6);
        assert_eq!(part.heights.len(), 300 * 300);
        let crop: Vec<f32> = (0..300)
            .flat_map(|r| full.heights[r * 513..r * 513 + 300].to_vec())
            .collect();
        let (lo, hi) = crop
            .iter()
            .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
        for (p, c) in part.heights.iter().zip(&crop) {
            let expected = (c - lo) / (hi - lo) * FRACTAL_MAX_HEIGHT_M;
            assert!((p - expected).abs() < 0.05, "{p} vs {expected}");
        }
        assert_eq!(part.georef.origin_y, 3000.0);
    }

    #[test]
    fn tiny_sizes() {
        assert_eq!(fractal(0, 1, 0.5).heights.len(), 0);
        assert_eq!(fractal(1, 1, 0.5).heights, vec![0.0]);
        assert_eq!(
            fractal(2, 1, f32::NAN).range(),
            Some((0.0, FRACTAL_MAX_HEIGHT_M))
        );
        assert_eq!(fractal(3, 1, 7.0).heights.len(), 9);
    }

    #[test]
    #[ignore = "allocates 1 GiB; run with --ignored --release to time the largest size"]
    fn largest_size_in_reasonable_time() {
        let t = std::time::Instant::now();
        let dem = fractal(16384, 7, 0.55);
        println!("16384²: {:?}", t.elapsed());
        assert_eq!(dem.heights.len(), 16384 * 16384);
        assert_eq!(dem.range(), Some((0.0, FRACTAL_MAX_HEIGHT_M)));
    }
}
