//! One query answered for many inputs in parallel over the rayon pool: the
//! batch forms shared by the point and multi-hit ray queries.

use crate::accel::BATCH_GRAIN;
use glam::Vec3;
use rayon::prelude::*;

/// `out[i] = answer(&inputs[i])` for every `i`, in parallel, in chunks of at
/// least [`BATCH_GRAIN`] so that cheap queries do not drown in scheduling.
pub(crate) fn answer_each<I: Sync, O: Send>(
    inputs: &[I],
    out: &mut [O],
    answer: impl Fn(&I) -> O + Sync,
) {
    assert_eq!(inputs.len(), out.len(), "one result per input");
    inputs
        .par_iter()
        .zip(out.par_iter_mut())
        .with_min_len(BATCH_GRAIN)
        .for_each(|(i, o)| *o = answer(i));
}

/// Points answered in one task, one after another in Morton order.
pub(crate) const COHERENT_CHUNK: usize = 1024;

/// Bits per axis of the Morton codes that order the points.
const MORTON_BITS: u32 = 10;

/// Spread the low ten bits of `x` to every third bit.
fn spread3(x: u32) -> u32 {
    let mut x = x & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    (x | (x << 2)) & 0x0924_9249
}

/// The points' indices in Morton (Z-curve) order over the box of the finite
/// points; points that are not finite come last.
pub(crate) fn morton_order(points: &[Vec3]) -> Vec<u32> {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in points.iter().filter(|p| p.is_finite()) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let cells = ((1u32 << MORTON_BITS) - 1) as f32;
    let scale = Vec3::splat(cells) / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let code = |p: &Vec3| -> u32 {
        if !p.is_finite() {
            return u32::MAX;
        }
        let q = ((*p - lo) * scale).clamp(Vec3::ZERO, Vec3::splat(cells));
        (spread3(q.x as u32) << 2) | (spread3(q.y as u32) << 1) | spread3(q.z as u32)
    };
    let mut keyed: Vec<(u32, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| (code(p), i as u32))
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// `out[i] = answer(points[i], state)` for every `i`, where neighbouring
/// points share a `state`: the points are visited in Morton order, in
/// parallel chunks of [`COHERENT_CHUNK`], each chunk in order with one
/// state (for example the previous point's nearest triangle, whose distance
/// bounds the next search). The answers must not depend on the state, only
/// their cost.
pub(crate) fn answer_coherent<O: Send, S: Default>(
    points: &[Vec3],
    out: &mut [O],
    answer: impl Fn(Vec3, &mut S) -> O + Sync,
) {
    assert_eq!(points.len(), out.len(), "one result per point");
    if points.len() <= COHERENT_CHUNK {
        let mut state = S::default();
        for (p, o) in points.iter().zip(out.iter_mut()) {
            *o = answer(*p, &mut state);
        }
        return;
    }
    let order = morton_order(points);
    let answers: Vec<Vec<O>> = order
        .par_chunks(COHERENT_CHUNK)
        .map(|chunk| {
            let mut state = S::default();
            chunk
                .iter()
                .map(|&i| answer(points[i as usize], &mut state))
                .collect()
        })
        .collect();
    for (chunk, found) in order.chunks(COHERENT_CHUNK).zip(answers) {
        for (&i, o) in chunk.iter().zip(found) {
            out[i as usize] = o;
        }
    }
}
