//! Image coordinates of sample rays and of triangle corners, in the frame
//! of a [`RasterView`], for the Purcell-style stream tracer's rasterizer to test coverage where
//! each pixel's ray actually passes rather than over a whole pixel.

use super::view::RasterView;
use raykit_core::glam::DVec3;
use raykit_core::{Ray, Vec3};

/// Unit roundoff of `f32`.
pub(crate) const U: f32 = f32::EPSILON * 0.5;

/// The view's frame: with `c0` the direction at (0, 0) (perspective) or the
/// common direction (orthographic) and `dx`, `dy` the per-pixel changes, a
/// point `p` is `base + Z·c0 + X·dx + Y·dy` with `(Z, X, Y)` the rows of
/// `B⁻¹ = [c0 dx dy]⁻¹` applied to `p - base`. Its image position is
/// `(X/Z, Y/Z)` (perspective) or `(X, Y)` (orthographic); any axes that are
/// not parallel work, orthogonal or not.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Screen {
    perspective: bool,
    base: Vec3,
    /// Rows of `B⁻¹`, rounded to `f32` (triangle corners).
    rows: [Vec3; 3],
    /// Rows of `B⁻¹` in `f64` (sample rays).
    rows64: [DVec3; 3],
    /// Componentwise magnitudes of the rows (rounding bounds).
    row_abs: [Vec3; 3],
    /// A ray's distance to a point of depth `Z` is at least `Z·depth_unit`
    /// (perspective: `|q| >= q·n̂ = Z·(c0·n̂)`, `n̂` the unit normal of the
    /// image plane; orthographic: the distance along the unit direction).
    depth_unit: f32,
    /// Absolute error of that bound from rounding of the rays' origins
    /// (orthographic views; zero for a common eye).
    depth_slack: f32,
}

impl Screen {
    /// The frame of `view` for a `width` × `height` image; `None` when its
    /// axes are degenerate or not finite.
    pub fn new(view: &RasterView, width: u32, height: u32) -> Option<Screen> {
        let (perspective, base, c0, dx, dy) = match *view {
            RasterView::Perspective { eye, d0, dx, dy } => (true, eye, d0, dx, dy),
            RasterView::Orthographic { dir, o0, ox, oy } => (false, o0, dir, ox, oy),
        };
        let (c, x, y) = (c0.as_dvec3(), dx.as_dvec3(), dy.as_dvec3());
        let n = x.cross(y);
        let det = c.dot(n);
        let rows64 = [n / det, y.cross(c) / det, c.cross(x) / det];
        let rows = rows64.map(|r| r.as_vec3());
        let row_abs = rows.map(|r| r.abs() * (1.0 + 4.0 * U));
        let (depth_unit, depth_slack) = if perspective {
            ((det / n.length()).abs(), 0.0)
        } else {
            let reach = base.abs().max_element()
                + (dx.abs().max_element() * width as f32)
                + (dy.abs().max_element() * height as f32);
            (1.0, 64.0 * U * reach)
        };
        let screen = Screen {
            perspective,
            base,
            rows,
            rows64,
            row_abs,
            depth_unit: depth_unit as f32,
            depth_slack,
        };
        let finite = rows.iter().all(|r| r.is_finite())
            && rows64.iter().all(|r| r.is_finite())
            && screen.depth_unit.is_finite()
            && screen.depth_unit > 0.0
            && depth_slack.is_finite();
        finite.then_some(screen)
    }

    /// Image position where `ray` crosses the image (perspective: of its
    /// direction; orthographic: of its origin), computed in `f64` from the
    /// `f32` ray, so the only error is the final rounding to `f32` (at most
    /// `U·|x|`). Not finite for a ray that does not point into the image.
    pub fn sample(&self, ray: &Ray) -> [f32; 2] {
        let v = if self.perspective {
            ray.dir().as_dvec3()
        } else {
            ray.origin.as_dvec3() - self.base.as_dvec3()
        };
        let [z, x, y] = self.rows64.map(|r| r.dot(v));
        if self.perspective {
            if z > 0.0 {
                [(x / z) as f32, (y / z) as f32]
            } else {
                [f32::NAN; 2]
            }
        } else {
            [x as f32, y as f32]
        }
    }

    /// Frame coordinates `(Z, X, Y)` of `q = p - base`, in `f32`.
    #[inline(always)]
    pub fn frame(&self, q: Vec3) -> [f32; 3] {
        self.rows.map(|r| r.dot(q))
    }

    /// `p - base`, rounded once (`f32` subtraction is correctly rounded, so
    /// each component is within `U` of its own magnitude).
    #[inline(always)]
    pub fn relative(&self, p: Vec3) -> Vec3 {
        p - self.base
    }

    /// Whether image positions are `X/Z, Y/Z`.
    #[inline(always)]
    pub fn perspective(&self) -> bool {
        self.perspective
    }

    /// Componentwise magnitude of row `k` of `B⁻¹`, rounded up a little:
    /// `row_abs(k)·|q|` bounds the terms of the dot product `rows[k]·q`.
    #[inline(always)]
    pub fn row_abs(&self, k: usize) -> Vec3 {
        self.row_abs[k]
    }

    /// Lower bound on the distance along any sample ray to a point of
    /// depth at least `z` (see the field docs), before the caller's margin.
    #[inline(always)]
    pub fn distance_at_least(&self, z: f32) -> f32 {
        z * self.depth_unit - self.depth_slack
    }
}
