//! A pinhole camera over a terrain, its per-frame ray basis, and where
//! cameras stand by default and along a fly-through path.

use crate::heightfield::{GridRay, HeightField};
use glam::DVec3;
use std::fmt;

/// A pinhole camera in world metres (x east, y north, z up), z up on screen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainCamera {
    /// Eye position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Vertical field of view, degrees.
    pub vfov_deg: f64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// Dot product.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

impl TerrainCamera {
    /// Orthonormal (right, up, forward); up is world z made orthogonal.
    pub fn basis(&self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let f = normalize(sub(self.target, self.eye));
        let mut r = cross(f, [0.0, 0.0, 1.0]);
        if dot(r, r) < 1e-18 {
            r = cross(f, [0.0, 1.0, 0.0]);
        }
        let r = normalize(r);
        (r, cross(r, f), f)
    }

    /// tan of half the vertical and horizontal fields of view.
    pub fn tan_half(&self) -> (f64, f64) {
        let tv = (self.vfov_deg.to_radians() * 0.5).tan();
        (tv, tv * self.width as f64 / self.height.max(1) as f64)
    }

    /// The per-image constants of [`TerrainCamera::direction`].
    pub fn frame(&self) -> CameraFrame {
        let (right, up, forward) = self.basis();
        let (tan_v, tan_h) = self.tan_half();
        CameraFrame {
            camera: *self,
            right,
            up,
            forward,
            tan_v,
            tan_h,
        }
    }

    /// Unit world direction through the centre of pixel (`x`, `y`), rows
    /// from the top.
    pub fn direction(&self, x: u32, y: u32) -> [f64; 3] {
        self.frame().direction(x, y)
    }

    /// Pixel (`x`, `y`)'s ray in grid units; `t` is metres from the eye.
    pub fn ray(&self, field: &HeightField, x: u32, y: u32) -> GridRay {
        self.frame().ray(field, x, y)
    }
}

/// A camera with its basis and field-of-view tangents computed once.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    /// The camera.
    pub camera: TerrainCamera,
    /// Right axis.
    pub right: [f64; 3],
    /// Up axis.
    pub up: [f64; 3],
    /// View direction.
    pub forward: [f64; 3],
    /// tan of half the vertical field of view.
    pub tan_v: f64,
    /// tan of half the horizontal field of view.
    pub tan_h: f64,
}

impl CameraFrame {
    /// Unit world direction through the centre of pixel (`x`, `y`).
    pub fn direction(&self, x: u32, y: u32) -> [f64; 3] {
        let (r, u, f, tv, th) = (self.right, self.up, self.forward, self.tan_v, self.tan_h);
        let c = &self.camera;
        let sx = (2.0 * (x as f64 + 0.5) / c.width as f64 - 1.0) * th;
        let sy = (1.0 - 2.0 * (y as f64 + 0.5) / c.height as f64) * tv;
        normalize([
            f[0] + r[0] * sx + u[0] * sy,
            f[1] + r[1] * sx + u[1] * sy,
            f[2] + r[2] * sx + u[2] * sy,
        ])
    }

    /// Pixel (`x`, `y`)'s ray in grid units.
    pub fn ray(&self, field: &HeightField, x: u32, y: u32) -> GridRay {
        field.grid_ray(self.camera.eye, self.direction(x, y))
    }
}

/// Pitch of the default camera below the horizontal, degrees (less than
/// half the default 50° field of view, so the top rows see the sky).
pub const DEFAULT_PITCH_DEG: f64 = 20.0;
/// How far the default eye sits from the DEM's centre, as a fraction of the
/// way to the south-west corner.
pub const DEFAULT_EYE_FRACTION: f64 = 0.75;
/// How far below the path's direction a fly-through camera looks, degrees.
pub const PATH_PITCH_DEG: f64 = 10.0;

/// The surface point at the DEM's centre, world metres: what a camera
/// without a target looks at.
pub fn centre(field: &HeightField) -> [f64; 3] {
    let (gx, gy) = (
        (field.width - 1) as f64 * 0.5,
        (field.height - 1) as f64 * 0.5,
    );
    [gx * field.sx, -gy * field.sy, field.height_at(gx, gy)]
}

/// The default view (eye, target) in world metres, so that any DEM renders
/// without coordinates: the eye stands [`DEFAULT_EYE_FRACTION`] of the way
/// from the DEM's centre to its south-west corner, above the highest point,
/// and looks north-east towards the centre [`DEFAULT_PITCH_DEG`] below the
/// horizontal.
pub fn default_camera(field: &HeightField) -> EyeTarget {
    let c = centre(field);
    let (w, h) = (
        (field.width - 1) as f64 * field.sx,
        (field.height - 1) as f64 * field.sy,
    );
    let sw = [0.0, -h];
    let ex = c[0] + DEFAULT_EYE_FRACTION * (sw[0] - c[0]);
    let ey = c[1] + DEFAULT_EYE_FRACTION * (sw[1] - c[1]);
    let d = (c[0] - ex).hypot(c[1] - ey).max(1e-9);
    let slope = DEFAULT_PITCH_DEG.to_radians().tan();
    let margin = 0.02 * w.hypot(h);
    let ez = (c[2] + d * slope).max(field.zmax as f64 + margin);
    // Look towards the centre horizontally, DEFAULT_PITCH_DEG down.
    let target = [c[0], c[1], ez - d * slope];
    ([ex, ey, ez], target)
}

/// A camera's eye and the point it looks at, world metres.
pub type EyeTarget = ([f64; 3], [f64; 3]);

/// Why a fly-through path gives no cameras.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathError {
    /// Every point is the same: there is no direction to follow.
    Degenerate,
    /// The path runs straight up or down at this frame: no horizontal
    /// direction to look along.
    Vertical {
        /// The frame, from 0.
        frame: u32,
    },
}

impl fmt::Display for PathError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PathError::Degenerate => {
                write!(
                    f,
                    "all points are the same; the camera needs a path to follow"
                )
            }
            PathError::Vertical { frame } => write!(
                f,
                "the path is vertical at frame {frame}; the camera needs a horizontal \
                 direction to look along"
            ),
        }
    }
}

impl std::error::Error for PathError {}

/// Eyes and targets (world metres) of `frames` frames of a fly-through along
/// the polyline `points` (world metres), evenly spaced by distance so the
/// camera moves at a constant speed; each looks along the path (a central
/// difference over 2% of its length), [`PATH_PITCH_DEG`] down, at a target
/// a tenth of `diag` (the DEM's diagonal) ahead.
pub fn path_cameras(
    points: &[[f64; 3]],
    frames: u32,
    diag: f64,
) -> Result<Vec<EyeTarget>, PathError> {
    let points: Vec<DVec3> = points.iter().map(|&p| DVec3::from_array(p)).collect();
    if points.len() < 2 {
        return Err(PathError::Degenerate);
    }
    let mut cum = vec![0.0];
    for w in points.windows(2) {
        let d = (w[1] - w[0]).length();
        cum.push(cum.last().copied().unwrap_or(0.0) + d);
    }
    let total = cum[cum.len() - 1];
    if total <= 0.0 {
        return Err(PathError::Degenerate);
    }
    let at = |s: f64| -> DVec3 {
        let s = s.clamp(0.0, total);
        let k = cum
            .windows(2)
            .position(|c| s <= c[1])
            .unwrap_or(points.len() - 2);
        let len = cum[k + 1] - cum[k];
        let a = if len > 0.0 { (s - cum[k]) / len } else { 0.0 };
        let (p, q) = (points[k], points[k + 1]);
        p + (q - p) * a
    };
    let delta = 0.02 * total;
    let look = 0.1 * diag.max(1.0);
    (0..frames)
        .map(|i| {
            let s = if frames > 1 {
                total * i as f64 / (frames - 1) as f64
            } else {
                0.0
            };
            let eye = at(s);
            let t = at(s + delta) - at(s - delta);
            let horiz = t.x.hypot(t.y);
            if horiz <= 1e-9 * total {
                return Err(PathError::Vertical { frame: i });
            }
            let el = (t.z.atan2(horiz).to_degrees() - PATH_PITCH_DEG)
                .clamp(-80.0, 80.0)
                .to_radians();
            let dir = DVec3::new(t.x / horiz * el.cos(), t.y / horiz * el.cos(), el.sin());
            Ok((eye.to_array(), (eye + dir * look).to_array()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::Dem;

    /// A 9 × 5 field with 3 m × 2 m cells and a bump, heights from a formula.
    fn field() -> HeightField {
        let heights = (0..45)
            .map(|i| {
                let (c, r) = ((i % 9) as f32, (i / 9) as f32);
                10.0 + c * 0.5 - r + if (c, r) == (4.0, 2.0) { 7.0 } else { 0.0 }
            })
            .collect();
        let mut dem = Dem::from_heights(9, 5, heights);
        dem.georef.pixel_width = 3.0;
        dem.georef.pixel_height = -2.0;
        HeightField::new(&dem).unwrap()
    }

    #[test]
    fn centre_is_the_surface_at_the_middle_grid_point() {
        let f = field();
        // The middle grid point of a 9 × 5 grid is (4, 2): world (12, −4),
        // on the bump, 10 + 2 − 2 + 7 m high.
        assert_eq!(centre(&f), [12.0, -4.0, 17.0]);
    }

    #[test]
    fn default_camera_stands_south_west_and_looks_at_the_centre() {
        let f = field();
        let (eye, target) = default_camera(&f);
        let c = centre(&f);
        // The south-west corner is grid point (0, 4): world (0, −8).
        let sw = [0.0, -8.0];
        for k in 0..2 {
            let expect = c[k] + 0.75 * (sw[k] - c[k]);
            assert!((eye[k] - expect).abs() < 1e-9, "axis {k}");
        }
        assert!(eye[2] > f.zmax as f64);
        // Horizontally the view runs from the eye through the centre.
        let (v, to_c) = (
            [target[0] - eye[0], target[1] - eye[1]],
            [c[0] - eye[0], c[1] - eye[1]],
        );
        assert!((v[0] * to_c[1] - v[1] * to_c[0]).abs() < 1e-9);
        assert!(v[0] * to_c[0] + v[1] * to_c[1] > 0.0);
        // 20° below the horizontal.
        let down = (eye[2] - target[2]).atan2(v[0].hypot(v[1])).to_degrees();
        assert!((down - DEFAULT_PITCH_DEG).abs() < 1e-9);
        // The image's middle column looks at the centre; the top row sees
        // the sky at a 50° field of view.
        let cam = TerrainCamera {
            eye,
            target,
            vfov_deg: 50.0,
            width: 15,
            height: 9,
        };
        let d = cam.direction(7, 4);
        assert!((d[0] * to_c[1] - d[1] * to_c[0]).abs() < 1e-9);
        assert!(cam.direction(7, 0)[2] > 0.0);
    }

    #[test]
    fn path_cameras_pass_through_the_points_at_even_spacing() {
        // Legs of 30 m and 60 m (a 3-4-5 triangle scaled by 12): 4 frames
        // at 0, 30, 60 and 90 m land on both points, the second leg's
        // middle and the end.
        let p = [[0.0, 0.0, 50.0], [30.0, 0.0, 50.0], [30.0, 36.0, 98.0]];
        let cams = path_cameras(&p, 4, 100.0).unwrap();
        let mid = [30.0, 18.0, 74.0];
        for (cam, want) in cams.iter().zip([p[0], p[1], mid, p[2]]) {
            for k in 0..3 {
                assert!((cam.0[k] - want[k]).abs() < 1e-9, "{cam:?} vs {want:?}");
            }
        }
        // On the level first leg the camera looks east, 10° down, a tenth
        // of the diagonal ahead.
        let (e, t) = cams[0];
        let v = [t[0] - e[0], t[1] - e[1], t[2] - e[2]];
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        assert!((len - 10.0).abs() < 1e-9 && v[1].abs() < 1e-9 && v[0] > 0.0);
        let down = (-v[2]).atan2(v[0]).to_degrees();
        assert!((down - PATH_PITCH_DEG).abs() < 1e-9);
        // On the second leg (rising 48 m over 36 m) it looks north, pitched
        // by the leg's slope less 10°.
        let (e, t) = cams[2];
        let v = [t[0] - e[0], t[1] - e[1], t[2] - e[2]];
        let slope = 48f64.atan2(36.0).to_degrees();
        let up = v[2].atan2(v[0].hypot(v[1])).to_degrees();
        assert!(v[0].abs() < 1e-9 && v[1] > 0.0);
        assert!((up - (slope - PATH_PITCH_DEG)).abs() < 1e-9);
    }

    #[test]
    fn degenerate_and_vertical_paths_are_refused() {
        let same = [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]];
        assert_eq!(path_cameras(&same, 2, 1.0), Err(PathError::Degenerate));
        let up = [[0.0, 0.0, 0.0], [0.0, 0.0, 5.0]];
        assert_eq!(
            path_cameras(&up, 2, 1.0),
            Err(PathError::Vertical { frame: 0 })
        );
    }
}
