//! Frames of a camera path: an orbit about the camera's target, any
//! range of its frames computed from the frame number alone (so that
//! independent processes render the frames of one animation), and the
//! file each frame is written to.

use raykit_core::glam::{DQuat, DVec3};
use raykit_core::{Camera, Vec3};
use std::fmt;
use std::path::{Path, PathBuf};

/// Frames `start` up to but not including `end`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame.
    pub start: u32,
    /// One past the last frame.
    pub end: u32,
}

/// One frame to render.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationFrame {
    /// The frame number (`None` for a single image).
    pub number: Option<u32>,
    /// Its camera.
    pub camera: Camera,
    /// The file it is written to.
    pub out: PathBuf,
}

/// Why no frames can be rendered; displayed in the words of the command
/// line (`--orbit`, `--frames`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimationError {
    /// A range of frames without a camera path.
    RangeWithoutPath,
    /// A camera path of no frames.
    NoFrames,
    /// The range reaches past the path's frames.
    PastEnd {
        /// The range asked for.
        range: FrameRange,
        /// Frames of the path.
        count: u32,
    },
}

impl fmt::Display for AnimationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AnimationError::RangeWithoutPath => {
                write!(f, "--frames needs a camera path: add --orbit FRAMES")
            }
            AnimationError::NoFrames => write!(f, "--orbit needs at least one frame"),
            AnimationError::PastEnd { range, count } => write!(
                f,
                "--frames {}..{} reaches past the {count} frames of --orbit {count} (frames 0..{count})",
                range.start, range.end
            ),
        }
    }
}

impl std::error::Error for AnimationError {}

/// Frame `index` of `count` of the orbit around `camera.target`: the eye
/// turned about the axis through the target along `camera.up` by
/// `360° · index / count` (counter-clockwise seen from above), at the
/// eye's distance and height; frame 0 is `camera` itself. Computed in f64
/// from the frame number alone, so any process renders the same frame.
pub fn orbit_camera(camera: &Camera, index: u32, count: u32) -> Camera {
    let up = DVec3::from(camera.up.to_array().map(f64::from)).normalize_or_zero();
    let target = DVec3::from(camera.target.to_array().map(f64::from));
    let eye = DVec3::from(camera.eye.to_array().map(f64::from));
    let angle = std::f64::consts::TAU * index as f64 / count.max(1) as f64;
    let turned = target + DQuat::from_axis_angle(up, angle) * (eye - target);
    Camera {
        eye: Vec3::new(turned.x as f32, turned.y as f32, turned.z as f32),
        ..*camera
    }
}

/// The file of frame `index` of an animation written to `out`:
/// `STEM.NNNN.EXT` beside it (at least four digits).
pub fn frame_path(out: &Path, index: u32) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match out.extension() {
        Some(ext) => format!("{stem}.{index:04}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{index:04}"),
    };
    out.with_file_name(name)
}

/// The frames to render: one frame, `camera` to `out`, without an `orbit`
/// of that many frames; else the frames of `range` (all by default) of
/// the orbit, each to its [`frame_path`].
pub fn animation_frames(
    camera: &Camera,
    out: &Path,
    orbit: Option<u32>,
    range: Option<FrameRange>,
) -> Result<Vec<AnimationFrame>, AnimationError> {
    let Some(count) = orbit else {
        if range.is_some() {
            return Err(AnimationError::RangeWithoutPath);
        }
        return Ok(vec![AnimationFrame {
            number: None,
            camera: *camera,
            out: out.to_path_buf(),
        }]);
    };
    if count == 0 {
        return Err(AnimationError::NoFrames);
    }
    let r = range.unwrap_or(FrameRange {
        start: 0,
        end: count,
    });
    if r.end > count {
        return Err(AnimationError::PastEnd { range: r, count });
    }
    Ok((r.start..r.end)
        .map(|k| AnimationFrame {
            number: Some(k),
            camera: orbit_camera(camera, k, count),
            out: frame_path(out, k),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbit_keeps_distance_and_height_and_closes_the_circle() {
        let cam = Camera {
            eye: Vec3::new(3.0, 2.0, 4.0),
            target: Vec3::new(1.0, 0.5, -1.0),
            up: Vec3::Y,
            vfov_deg: 40.0,
        };
        assert_eq!(orbit_camera(&cam, 0, 8).eye, cam.eye);
        let radius = |e: Vec3| ((e.x - 1.0).hypot(e.z + 1.0)) as f64;
        for k in 1..8 {
            let e = orbit_camera(&cam, k, 8).eye;
            assert!((radius(e) - radius(cam.eye)).abs() < 1e-5);
            assert_eq!(e.y, cam.eye.y);
        }
        // A quarter turn about +y maps (dx, dz) = (2, 5) to (5, -2).
        let q = orbit_camera(&cam, 2, 8).eye;
        assert!((q.x - 6.0).abs() < 1e-5 && (q.z + 3.0).abs() < 1e-5, "{q}");
    }

    #[test]
    fn frame_paths_number_the_frames_beside_the_output() {
        assert_eq!(
            frame_path(Path::new("a/b.png"), 7),
            Path::new("a/b.0007.png")
        );
        assert_eq!(
            frame_path(Path::new("b.exr"), 12345),
            Path::new("b.12345.exr")
        );
        let cam = Camera {
            eye: Vec3::Z,
            target: Vec3::ZERO,
            up: Vec3::Y,
            vfov_deg: 40.0,
        };
        let f = animation_frames(
            &cam,
            Path::new("o.png"),
            Some(10),
            Some(FrameRange { start: 4, end: 6 }),
        )
        .unwrap();
        assert_eq!(
            f.iter().map(|x| x.number).collect::<Vec<_>>(),
            vec![Some(4), Some(5)]
        );
        assert!(animation_frames(
            &cam,
            Path::new("o.png"),
            Some(5),
            Some(FrameRange { start: 4, end: 6 })
        )
        .is_err());
        assert!(animation_frames(
            &cam,
            Path::new("o.png"),
            None,
            Some(FrameRange { start: 0, end: 1 })
        )
        .is_err());
        assert_eq!(
            animation_frames(&cam, Path::new("o.png"), None, None)
                .unwrap()
                .len(),
            1
        );
    }
}
