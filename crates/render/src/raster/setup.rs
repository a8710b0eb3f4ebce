//! Triangle setup: conservative edge functions and a screen bounding box.

use super::view::RasterView;
use raykit_core::glam::DVec3;
use raykit_core::tri::MAX_EDGE_TOLERANCE;
use raykit_core::Vec3;

/// How far outside a triangle, in barycentric units, a pixel still counts as
/// covered: four times the widest tolerance band of the triangle tests, so
/// that every hit the exact test can report lies inside the expanded
/// triangle with room for its rounding error.
pub(crate) const EXPANSION: f64 = 4.0 * MAX_EDGE_TOLERANCE as f64;

/// Relative slack for the `f32` evaluation of the edge functions and for the
/// difference between the view's directions and the sample rays.
const SLACK: f64 = 1e-5;

/// Edge functions and screen box of one triangle (the Purcell-style stream tracer: rasterization
/// setup). A pixel `(x, y)` is a candidate when `a[i]·(x+½) + b[i]·(y+½) +
/// c[i] >= 0` for all three edges, or, when `either` is set (triangle seen
/// edge-on, orientation unknown), when `-a[i]·(x+½) - b[i]·(y+½) + cm[i] >= 0`
/// for all three. The thresholds (half a pixel, the barycentric expansion,
/// rounding slack) are folded into `c` and `cm`, so every pixel some ray of
/// which may hit the triangle is a candidate.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeSetup {
    pub a: [f32; 3],
    pub b: [f32; 3],
    pub c: [f32; 3],
    pub cm: [f32; 3],
    pub either: bool,
    /// Inclusive pixel box.
    pub x0: u32,
    pub x1: u32,
    pub y0: u32,
    pub y1: u32,
}

impl EdgeSetup {
    /// Whether pixel (`x`, `y`) may be covered.
    #[inline(always)]
    pub fn covers(&self, x: u32, y: u32) -> bool {
        let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
        let e = |i: usize| self.a[i] * px + self.b[i] * py;
        let (e0, e1, e2) = (e(0), e(1), e(2));
        let pos = (e0 + self.c[0] >= 0.0) & (e1 + self.c[1] >= 0.0) & (e2 + self.c[2] >= 0.0);
        pos || (self.either
            && (self.cm[0] - e0 >= 0.0)
            && (self.cm[1] - e1 >= 0.0)
            && (self.cm[2] - e2 >= 0.0))
    }

    /// Set up the triangle `tri` for a `width` × `height` image of `view`;
    /// `None` when no pixel can see it (off screen, behind the eye, not
    /// finite).
    pub fn new(view: &RasterView, tri: [Vec3; 3], width: u32, height: u32) -> Option<EdgeSetup> {
        if width == 0 || height == 0 || tri.iter().any(|p| !p.is_finite()) {
            return None;
        }
        let (w, h) = (width as f64, height as f64);
        // Each edge function is affine in the image position: value at
        // (0, 0), change per pixel in x and in y, and a magnitude bounding
        // the terms it is summed from (for the rounding slack).
        let mut coef = [[0.0f64; 3]; 3];
        let mut mag = [0.0f64; 3];
        let sign: f64;
        let ambiguous: bool;
        match *view {
            RasterView::Perspective { eye, d0, dx, dy } => {
                let e = eye.as_dvec3();
                let v = tri.map(|p| p.as_dvec3() - e);
                let (d0, dx, dy) = (d0.as_dvec3(), dx.as_dvec3(), dy.as_dvec3());
                let dmax = d0.length() + dx.length() * w + dy.length() * h;
                for i in 0..3 {
                    let k = v[(i + 1) % 3].cross(v[(i + 2) % 3]);
                    coef[i] = [dx.dot(k), dy.dot(k), d0.dot(k)];
                    mag[i] = k.length() * dmax;
                }
                let det = v[0].dot(v[1].cross(v[2]));
                sign = det.signum();
                ambiguous =
                    det.abs() <= 1e-9 * v[0].length() * v[1].length() * v[2].length() || det == 0.0;
            }
            RasterView::Orthographic { dir, o0, ox, oy } => {
                let o = o0.as_dvec3();
                let v = tri.map(|p| p.as_dvec3() - o);
                let (dir, ox, oy) = (dir.as_dvec3(), ox.as_dvec3(), oy.as_dvec3());
                for i in 0..3 {
                    let (p, q) = (v[(i + 1) % 3], v[(i + 2) % 3]);
                    let k = p.cross(q);
                    let m = (p - q).cross(dir);
                    coef[i] = [ox.dot(m), oy.dot(m), dir.dot(k)];
                    mag[i] = k.length() * dir.length()
                        + m.length() * (ox.length() * w + oy.length() * h);
                }
                let n = (v[1] - v[0]).cross(v[2] - v[0]);
                let s = dir.dot(n);
                sign = s.signum();
                ambiguous = s.abs() <= 1e-9 * n.length() * dir.length() || s == 0.0;
            }
        }
        let sum: [f64; 3] = std::array::from_fn(|j| coef[0][j] + coef[1][j] + coef[2][j]);
        let mut setup = EdgeSetup {
            a: [0.0; 3],
            b: [0.0; 3],
            c: [0.0; 3],
            cm: [0.0; 3],
            either: ambiguous,
            x0: 0,
            x1: width - 1,
            y0: 0,
            y1: height - 1,
        };
        let sign = if ambiguous || sign == 0.0 { 1.0 } else { sign };
        for i in 0..3 {
            // Positive orientation: sign·(E_i + ε·S); negative: -(E_i) + ε·(-S).
            let f: [f64; 3] = std::array::from_fn(|j| sign * (coef[i][j] + EXPANSION * sum[j]));
            let g: [f64; 3] = std::array::from_fn(|j| -(coef[i][j] + EXPANSION * sum[j]));
            let slack = SLACK * (mag[i] * (1.0 + 3.0 * EXPANSION)) + f64::MIN_POSITIVE;
            let thr_f = 0.5 * (f[0].abs() + f[1].abs()) + slack;
            let thr_g = 0.5 * (g[0].abs() + g[1].abs()) + slack;
            setup.a[i] = f[0] as f32;
            setup.b[i] = f[1] as f32;
            setup.c[i] = (f[2] + thr_f) as f32;
            // `cm` pairs with -a, -b: only meaningful when `sign` is +1.
            setup.cm[i] = (g[2] + thr_g) as f32;
        }
        if [setup.a, setup.b, setup.c, setup.cm]
            .iter()
            .any(|row| row.iter().any(|x| !x.is_finite()))
        {
            return None;
        }
        // Screen box of the expanded triangle (all barycentrics >= -ε), one
        // pixel wider; the whole screen when it reaches behind the eye.
        let p = tri.map(|p| p.as_dvec3());
        let eps = EXPANSION * 1.5;
        let corners: [DVec3; 3] = std::array::from_fn(|i| {
            let (a, b, c) = (p[i], p[(i + 1) % 3], p[(i + 2) % 3]);
            a * (1.0 + 2.0 * eps) - (b + c) * eps
        });
        let mut proj = [(0.0, 0.0, 0.0); 3];
        let mut all_in_front = true;
        let mut all_behind = true;
        for (i, c) in corners.iter().enumerate() {
            match view.project_f64(*c) {
                Some(q) if q.0.is_finite() && q.1.is_finite() => {
                    proj[i] = q;
                    all_behind = false;
                }
                _ => all_in_front = false,
            }
        }
        if all_behind && matches!(view, RasterView::Perspective { .. }) {
            // Every corner of the expanded triangle lies on or behind the eye
            // plane: forward rays cannot reach it (the eye plane is convex).
            if behind_eye(view, &corners) {
                return None;
            }
        }
        if all_in_front {
            let lo_x = proj.iter().map(|q| q.0).fold(f64::INFINITY, f64::min);
            let hi_x = proj.iter().map(|q| q.0).fold(f64::NEG_INFINITY, f64::max);
            let lo_y = proj.iter().map(|q| q.1).fold(f64::INFINITY, f64::min);
            let hi_y = proj.iter().map(|q| q.1).fold(f64::NEG_INFINITY, f64::max);
            let (x0, x1) = ((lo_x - 1.0).floor(), (hi_x + 1.0).floor());
            let (y0, y1) = ((lo_y - 1.0).floor(), (hi_y + 1.0).floor());
            if x1 < 0.0 || y1 < 0.0 || x0 > w - 1.0 || y0 > h - 1.0 {
                return None;
            }
            setup.x0 = x0.clamp(0.0, w - 1.0) as u32;
            setup.x1 = x1.clamp(0.0, w - 1.0) as u32;
            setup.y0 = y0.clamp(0.0, h - 1.0) as u32;
            setup.y1 = y1.clamp(0.0, h - 1.0) as u32;
        }
        Some(setup)
    }
}

/// True when every point lies strictly behind the eye plane of a
/// perspective view.
fn behind_eye(view: &RasterView, points: &[DVec3; 3]) -> bool {
    match *view {
        RasterView::Perspective { eye, d0, dx, dy } => {
            let n = dx.as_dvec3().cross(dy.as_dvec3());
            let n = if d0.as_dvec3().dot(n) < 0.0 { -n } else { n };
            points.iter().all(|p| (*p - eye.as_dvec3()).dot(n) < 0.0)
        }
        RasterView::Orthographic { .. } => false,
    }
}
