//! Tight triangle setup in `f32` (the Purcell-style stream tracer's rasterization setup): edge
//! functions of the projected triangle, widened only by a bound on rounding
//! error, tested at each pixel's own sample position.
//!
//! The guarantee is the one of the conservative setup ([`super::setup`]):
//! every ray the exact triangle test can report a hit for is a candidate.
//! A reported hit lies in the triangle expanded by [`EXPANSION`]
//! (barycentric units, four times the tests' widest tolerance band), so we
//! project the expanded corners. When all three lie in front of the eye the
//! expanded triangle projects to the triangle of their images, and a ray
//! meets it exactly when its image position lies inside. What remains is
//! rounding, bounded here with generous constants (all in pixels):
//!
//! - corners: `q = p - base` is one correctly rounded subtraction, the
//!   expanded corner a few more operations on `q`, and each frame
//!   coordinate a 3-term dot product with a row of `B⁻¹` rounded to `f32`;
//!   together at most `12·U·(|row|·|q|max)` (`U = 2⁻²⁴`, `|q|max` the
//!   componentwise largest corner), and the division by `Z` (perspective)
//!   turns that into `8/7·(eX + |x|·eZ)/Z + U·|x|` once `Z > 8·eZ`.
//!   Typically 10⁻⁴ to 10⁻³ pixel.
//! - samples: [`Samples::err`] (`f64` projection of the `f32` ray, rounded
//!   once).
//! - the edge function `E(p) = (k - j) × (p - j)` moves by at most
//!   `(|A| + |B|)·(δs + δv) + 2·δv·‖p - j‖₁` when the corners move by `δv`
//!   and the sample by `δs` (∞-norm), and its `f32` evaluation in
//!   coordinates local to the triangle (magnitudes `≤ L`) errs by at most
//!   `16·U·L·(|A| + |B|)`.
//!
//! The sum, times 1.5, is the tolerance folded into each edge's constant:
//! about 10⁻³ pixel instead of the half pixel a whole-pixel test needs, so a
//! sub-pixel triangle has about as many candidates as samples it covers.
//! A triangle whose signed area does not clearly exceed the edges' error
//! (seen nearly edge-on) accepts either orientation. Triangles this cannot
//! serve (a corner near or behind the eye plane, rounding bound above a
//! quarter pixel) fall back to the conservative whole-pixel setup.
//!
//! Each set-up triangle also carries a lower bound on the distance of any
//! hit it can give ([`TightSetup::tmin`]), so pixels already holding a
//! nearer hit skip the exact test.

use super::samples::Samples;
use super::screen::{Screen, U};
use super::setup::EXPANSION;
use raykit_core::Vec3;

/// Pixels a triangle's box may hold for setup to test its samples at once,
/// rejecting it when it covers none and shrinking its box to those it
/// covers (most triangles of a mesh finer than the image).
const PROBE_PIXELS: u32 = 16;

/// Relative margin on the depth bound: far above the `f32` error of the
/// tests' `t` for any ray not grazing the triangle.
const DEPTH_MARGIN: f32 = 1.0 / 128.0;

/// A triangle set up for tight coverage: with `(x, y) = (sx - ox, sy -
/// oy)` the local sample position, `a[i]·x + b[i]·y + c[i] >= 0` for all
/// three edges (tolerance folded into `c`); an inclusive pixel box; and a
/// lower bound on the distance of any hit along any sample ray.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TightSetup {
    pub a: [f32; 3],
    pub b: [f32; 3],
    pub c: [f32; 3],
    /// With `either`: also covered where `cm[i] - a[i]·x - b[i]·y >= 0`
    /// for all three (the other orientation).
    pub cm: [f32; 3],
    pub either: bool,
    pub ox: f32,
    pub oy: f32,
    pub x0: u32,
    pub x1: u32,
    pub y0: u32,
    pub y1: u32,
    /// No sample ray meets the triangle nearer than this.
    pub tmin: f32,
}

/// Outcome of tight setup.
pub(crate) enum Tight {
    /// Set up.
    Setup(TightSetup),
    /// No sample can see the triangle.
    Hidden,
    /// Use the conservative whole-pixel setup.
    Fallback,
}

impl TightSetup {
    /// Whether the sample at image position `s` may hit the triangle.
    #[inline(always)]
    pub fn covers(&self, s: [f32; 2]) -> bool {
        let (x, y) = (s[0] - self.ox, s[1] - self.oy);
        let e = |i: usize| self.a[i] * x + self.b[i] * y;
        let (e0, e1, e2) = (e(0), e(1), e(2));
        (e0 + self.c[0] >= 0.0) & (e1 + self.c[1] >= 0.0) & (e2 + self.c[2] >= 0.0)
            || (self.either
                && (self.cm[0] - e0 >= 0.0)
                && (self.cm[1] - e1 >= 0.0)
                && (self.cm[2] - e2 >= 0.0))
    }
}

impl Tight {
    /// Set up `tri` against the samples of a `width` × `height` image.
    pub fn new(
        screen: &Screen,
        samples: &Samples,
        tri: [Vec3; 3],
        width: u32,
        height: u32,
    ) -> Tight {
        let q = tri.map(|p| screen.relative(p));
        let e = EXPANSION as f32;
        let qe: [Vec3; 3] = std::array::from_fn(|i| {
            let (a, b, c) = (q[i], q[(i + 1) % 3], q[(i + 2) % 3]);
            a * (1.0 + 2.0 * e) - (b + c) * e
        });
        // Componentwise bound on the corners, expanded ones included.
        let qmax = q[0].abs().max(q[1].abs()).max(q[2].abs()) * (1.0 + 4.0 * e);
        let err: [f32; 3] = std::array::from_fn(|k| 12.0 * U * screen.row_abs(k).dot(qmax));
        let f = qe.map(|v| screen.frame(v));
        let (mut x, mut y) = ([0.0f32; 3], [0.0f32; 3]);
        let mut dv = 0.0f32;
        let mut zmin = f32::INFINITY;
        for i in 0..3 {
            let [z, xx, yy] = f[i];
            zmin = zmin.min(z);
            if screen.perspective() {
                if z.is_nan() || z <= 8.0 * err[0] {
                    return Tight::Fallback;
                }
                (x[i], y[i]) = (xx / z, yy / z);
                // |X/Z - X̃/Z̃| <= (eX + |x|·eZ) / (Z̃ - eZ), Z̃ - eZ >= 7/8·Z̃.
                let ex = 8.0 / 7.0 * (err[1] + x[i].abs() * err[0]) / z + U * x[i].abs();
                let ey = 8.0 / 7.0 * (err[2] + y[i].abs() * err[0]) / z + U * y[i].abs();
                dv = dv.max(ex).max(ey);
            } else {
                (x[i], y[i]) = (xx, yy);
                dv = dv.max(err[1]).max(err[2]);
            }
        }
        if dv.is_nan() || dv > 0.25 || !x.iter().chain(&y).all(|v| v.is_finite()) {
            return Tight::Fallback;
        }
        let (lo_x, hi_x) = (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]));
        let (lo_y, hi_y) = (y[0].min(y[1]).min(y[2]), y[0].max(y[1]).max(y[2]));
        // Pixels whose sample may lie within `margin` of the box: a sample
        // lies within `stray` of its pixel's square.
        let margin = dv + samples.err + samples.stray + 1.0 / 1024.0;
        let (fx0, fx1) = ((lo_x - margin - 1.0).ceil(), (hi_x + margin).floor());
        let (fy0, fy1) = ((lo_y - margin - 1.0).ceil(), (hi_y + margin).floor());
        let (w, h) = (width as f32, height as f32);
        if fx1 < 0.0 || fy1 < 0.0 || fx0 > w - 1.0 || fy0 > h - 1.0 {
            return Tight::Hidden;
        }
        // Edge functions in coordinates local to the box.
        let (ox, oy) = (lo_x.floor(), lo_y.floor());
        let (lx, ly) = (x.map(|v| v - ox), y.map(|v| v - oy));
        let extent = (hi_x - lo_x).max(hi_y - lo_y) + 2.0 * margin + 1.0;
        let reach = extent + 2.0;
        let ds = samples.err + U * reach;
        let dv = dv + U * reach;
        let mut setup = TightSetup {
            a: [0.0; 3],
            b: [0.0; 3],
            c: [0.0; 3],
            cm: [0.0; 3],
            either: false,
            ox,
            oy,
            x0: fx0.max(0.0) as u32,
            x1: fx1.min(w - 1.0) as u32,
            y0: fy0.max(0.0) as u32,
            y1: fy1.min(h - 1.0) as u32,
            tmin: 0.0,
        };
        let tol: [f32; 3] = std::array::from_fn(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let (a, b) = (ly[j] - ly[k], lx[k] - lx[j]);
            setup.a[i] = a;
            setup.b[i] = b;
            setup.c[i] = -(a * lx[j] + b * ly[j]);
            1.5 * ((a.abs() + b.abs()) * (ds + dv + 16.0 * U * reach)
                + 4.0 * dv * extent
                + 4.0 * (ds + dv) * (ds + dv))
        });
        // Twice the signed area: its sign is the orientation when it
        // clearly exceeds the edges' error bounds; otherwise (seen nearly
        // edge-on) either orientation is accepted.
        let area2 = (lx[1] - lx[0]) * (ly[2] - ly[0]) - (ly[1] - ly[0]) * (lx[2] - lx[0]);
        setup.either = area2.is_nan() || area2.abs() <= 2.0 * (tol[0] + tol[1] + tol[2]);
        let sign = if area2 < 0.0 { -1.0 } else { 1.0 };
        for (i, tol) in tol.into_iter().enumerate() {
            (setup.a[i], setup.b[i]) = (sign * setup.a[i], sign * setup.b[i]);
            let c = sign * setup.c[i];
            (setup.c[i], setup.cm[i]) = (c + tol, tol - c);
        }
        // A probe of the samples of a small box: reject or shrink.
        let (nx, ny) = (setup.x1 - setup.x0 + 1, setup.y1 - setup.y0 + 1);
        if nx * ny <= PROBE_PIXELS {
            let (mut bx0, mut bx1, mut by0, mut by1) = (u32::MAX, 0, u32::MAX, 0);
            for py in setup.y0..=setup.y1 {
                let row = &samples.pos[(py * width) as usize..][..width as usize];
                for px in setup.x0..=setup.x1 {
                    if setup.covers(row[px as usize]) {
                        (bx0, bx1) = (bx0.min(px), bx1.max(px));
                        (by0, by1) = (by0.min(py), by1.max(py));
                    }
                }
            }
            if bx0 == u32::MAX {
                return Tight::Hidden;
            }
            (setup.x0, setup.x1, setup.y0, setup.y1) = (bx0, bx1, by0, by1);
        }
        let d = screen.distance_at_least(zmin - err[0]);
        setup.tmin = d - d.abs() * DEPTH_MARGIN;
        if !setup.tmin.is_finite() {
            setup.tmin = f32::NEG_INFINITY;
        }
        Tight::Setup(setup)
    }
}
