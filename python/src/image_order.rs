//! The order in which the rays of a batch are traced: the rays of an image
//! in 4 × 4 pixel blocks, a band of blocks per task.
//!
//! The wide BVHs trace eight or sixteen consecutive rays of a batch
//! together as a packet (Wald et al. 2001); in 4 × 4 blocks a packet is a
//! square of pixels, whose rays stay together deeper in the tree than a
//! strip of one row does. raykit-render traces its primary rays in the same
//! blocks. A band of four rows holds whole blocks, so each band is traced
//! by one task that reads its rays straight from the caller's array and
//! writes its answers straight into the result columns: no array of all
//! the rays or of all the hits in traced order is made.

use crate::hit_arrays::{HitColumns, INVALID_ID};
use crate::threads::{inline_or_interruptible, Stop};
use pyo3::prelude::*;
use raykit_core::accel::BATCH_GRAIN;
use raykit_core::{Ray, Vec3};
use rayon::prelude::*;
use std::borrow::Cow;

/// Side of a block, pixels.
const BLOCK: usize = 4;

/// Rays per task when the rays do not form an image.
const GRAIN: usize = 4096;

/// How a batch of `n` rays is cut into bands and ordered within each.
pub struct Bands {
    /// Rays per band (the last may hold fewer).
    pub len: usize,
    /// Image width, when the rays are traced in blocks.
    width: Option<usize>,
    /// The traced order of a full band.
    full: Vec<u32>,
}

impl Bands {
    /// Bands of four rows of blocks when `n` rays form rows of `width`
    /// (at least one block); otherwise runs of consecutive rays.
    pub fn new(n: usize, width: usize) -> Bands {
        let (len, width) = layout(n, width);
        let full = order_of(width, len);
        Bands { len, width, full }
    }

    /// The positions within a band of `len` rays in the order they are
    /// traced (the full bands' order is made once).
    pub fn order(&self, len: usize) -> Cow<'_, [u32]> {
        if len == self.full.len() {
            Cow::Borrowed(&self.full)
        } else {
            Cow::Owned(order_of(self.width, len))
        }
    }
}

/// Rays per band of a batch of `n` rays, and the image width when they
/// form rows of `width` (at least one block); a batch smaller than a band
/// is one band of its own length.
fn layout(n: usize, width: usize) -> (usize, Option<usize>) {
    let image =
        width >= BLOCK && n.is_multiple_of(width) && n / width >= BLOCK && n <= u32::MAX as usize;
    if image {
        (BLOCK * width, Some(width))
    } else {
        (GRAIN.min(n).max(1), None)
    }
}

/// Run `work` on a batch of `n` rays (rows of `width`) to be traced band by
/// band over a structure already `built`: a batch of one band of at most
/// [`BATCH_GRAIN`] rays is a single task (the structures split their
/// batches no finer), run on the caller's thread; others, and every batch
/// that builds the structure first, are interruptible
/// ([`inline_or_interruptible`]).
pub fn banded<R, F>(
    py: Python<'_>,
    threads: i64,
    (n, width): (usize, usize),
    built: bool,
    work: F,
) -> PyResult<R>
where
    F: FnOnce(&Stop) -> R + Send,
    R: Send,
{
    let single = built && n <= BATCH_GRAIN && layout(n, width).0 >= n;
    inline_or_interruptible(py, threads, n, single, work)
}

/// The traced order of a band of `len` rays: block by block, each block row
/// by row, in an image of `width` (the last band of an image may have fewer
/// than four rows); as they come otherwise.
fn order_of(width: Option<usize>, len: usize) -> Vec<u32> {
    let Some(width) = width else {
        return (0..len as u32).collect();
    };
    let rows = len / width;
    let mut order = Vec::with_capacity(len);
    for bx in (0..width).step_by(BLOCK) {
        for y in 0..rows {
            for x in bx..(bx + BLOCK).min(width) {
                order.push((y * width + x) as u32);
            }
        }
    }
    order
}

/// The ray in row `r` of `[ox, oy, oz, dx, dy, dz]` over `[tnear, tfar]`.
fn ray(r: &[f32], tnear: f32, tfar: f32) -> Ray {
    Ray::segment(
        Vec3::new(r[0], r[1], r[2]),
        Vec3::new(r[3], r[4], r[5]),
        tnear,
        tfar,
    )
}

/// The rays of a band starting at ray `start` of the rows of `rays`, in
/// the band's traced `order`, over `[tnear, tfar]`; with `moved`, ray `k`'s
/// interval less `moved[k]` (a ray moved that far along itself).
pub fn band_rays(
    rays: &[f32],
    start: usize,
    order: &[u32],
    (tnear, tfar): (f32, f32),
    moved: Option<&[f64]>,
) -> Vec<Ray> {
    order
        .iter()
        .map(|&i| {
            let k = start + i as usize;
            let at = 6 * k;
            let (near, far) = match moved {
                Some(m) if m[k] != 0.0 => {
                    ((tnear as f64 - m[k]) as f32, (tfar as f64 - m[k]) as f32)
                }
                _ => (tnear, tfar),
            };
            ray(&rays[at..at + 6], near, far)
        })
        .collect()
}

/// Per row of `rays` (`n` rows of `[ox, oy, oz, dx, dy, dz]` over
/// `[tnear, tfar]`, less `moved[k]` for ray `k` when given): whether
/// `occluded` finds it blocked, traced band by
/// band ([`Bands`], in image blocks when the rows form rows of `width`);
/// bands not begun when `stop` is raised are left out.
pub fn occlusion_by_bands(
    rays: &[f32],
    n: usize,
    width: usize,
    interval: (f32, f32),
    moved: Option<&[f64]>,
    stop: &Stop,
    occluded: impl Fn(&[Ray], &mut [bool]) + Sync,
) -> Vec<bool> {
    let mut out = vec![false; n];
    let bands = Bands::new(n, width);
    out.par_chunks_mut(bands.len)
        .enumerate()
        .for_each(|(b, out)| {
            if stop.raised() {
                return;
            }
            let order = bands.order(out.len());
            let traced = band_rays(rays, b * bands.len, &order, interval, moved);
            let mut hit = vec![false; traced.len()];
            occluded(&traced, &mut hit);
            for (&i, h) in order.iter().zip(hit) {
                out[i as usize] = h;
            }
        });
    out
}

/// One ray's nearest hit as the result columns hold it.
#[derive(Clone, Copy, Debug)]
pub struct HitRow {
    pub t: f32,
    pub geometry: u32,
    pub instance: u32,
    pub prim: u32,
    pub uv: [f32; 2],
    pub normal: [f32; 3],
}

/// Nearest hits of the `n` rows of `rays` (`[ox, oy, oz, dx, dy, dz]` over
/// `[0, ∞)`) as result columns, traced band by band ([`Bands`], in image
/// blocks when the rows form rows of `width`): `nearest` answers a band's
/// rays in traced order, and each band writes its own part of the columns.
/// The columns start zeroed, which costs nothing until a band writes them;
/// misses are written with the hits. Bands not begun when `stop` is raised
/// are left out.
pub fn nearest_by_bands(
    rays: &[f32],
    n: usize,
    width: usize,
    stop: &Stop,
    nearest: impl Fn(&[Ray]) -> Vec<Option<HitRow>> + Sync,
) -> HitColumns {
    let mut c = HitColumns::zeroed(n);
    let bands = Bands::new(n, width);
    let len = bands.len;
    c.t.par_chunks_mut(len)
        .zip(c.geometry.par_chunks_mut(len))
        .zip(c.instance.par_chunks_mut(len))
        .zip(c.prim.par_chunks_mut(len))
        .zip(c.uv.par_chunks_mut(2 * len))
        .zip(c.normal.par_chunks_mut(3 * len))
        .enumerate()
        .for_each(|(b, (((((t, g), inst), p), uv), nrm))| {
            if stop.raised() {
                return;
            }
            let order = bands.order(t.len());
            let traced = band_rays(rays, b * len, &order, (0.0, f32::INFINITY), None);
            for (&i, h) in order.iter().zip(nearest(&traced)) {
                let i = i as usize;
                let Some(h) = h else {
                    (t[i], g[i], inst[i], p[i]) =
                        (f32::INFINITY, INVALID_ID, INVALID_ID, INVALID_ID);
                    continue;
                };
                (t[i], g[i], inst[i], p[i]) = (h.t, h.geometry, h.instance, h.prim);
                uv[2 * i..2 * i + 2].copy_from_slice(&h.uv);
                nrm[3 * i..3 * i + 3].copy_from_slice(&h.normal);
            }
        });
    c
}

/// The distance each of `n` rays was moved along itself (see
/// `near_rays.rs`), as a slice: none when not given.
pub fn moved_per_ray<'a>(
    moved: &'a Option<numpy::PyReadonlyArray1<'_, f64>>,
    n: usize,
) -> pyo3::PyResult<Option<&'a [f64]>> {
    let Some(m) = moved else {
        return Ok(None);
    };
    let m = crate::arrays::c_order(m, "moved")?;
    if m.len() != n {
        return Err(crate::errors::value_error(format!(
            "moved has {} entries for {n} rays",
            m.len()
        )));
    }
    Ok(Some(m))
}
