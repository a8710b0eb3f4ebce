//! Splitting `raykit render` over independent processes, for batch
//! schedulers (a Slurm job array, a Kubernetes Indexed Job): `--tile I/N`
//! renders horizontal band I of N as a PNG part that `raykit merge-tiles`
//! assembles, and `--orbit FRAMES` with `--frames A..B` renders a range of
//! the frames of a camera path. Every pixel is rendered as in the whole
//! image (the renderer's crop window), so the assembled image equals a
//! one-process render bit for bit.

use anyhow::{bail, Result};
use raykit_core::glam::{DQuat, DVec3};
use raykit_core::{Camera, Vec3};
use raykit_render::Tile;
use std::path::{Path, PathBuf};

/// `--tile I/N`: band `index` (0-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileArg {
    /// The band rendered, 0-based.
    pub index: u32,
    /// Number of bands.
    pub count: u32,
}

impl TileArg {
    /// The band's rectangle of a `width` × `height` image ([`Tile::band`]).
    pub fn window(&self, width: u32, height: u32) -> Result<Tile> {
        if self.count > height {
            bail!(
                "--tile {}/{}: {} bands of a {height}-row image would leave some empty; use at most {height}",
                self.index,
                self.count,
                self.count
            );
        }
        Tile::band(self.index, self.count, width, height).ok_or_else(|| {
            anyhow::anyhow!(
                "--tile {}/{}: the index must be below the count",
                self.index,
                self.count
            )
        })
    }
}

/// Parse `I/N` with `0 ≤ I < N`.
pub fn parse_tile(s: &str) -> Result<TileArg, String> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("'{s}' is not I/N (band I of N, from 0)"))?;
    let index: u32 = i
        .trim()
        .parse()
        .map_err(|_| format!("'{i}' in '{s}' is not a whole number ≥ 0"))?;
    let count: u32 = n
        .trim()
        .parse()
        .map_err(|_| format!("'{n}' in '{s}' is not a whole number ≥ 1"))?;
    if count == 0 || index >= count {
        return Err(format!(
            "'{s}': the band index must be below the count (0 to {})",
            count.saturating_sub(1)
        ));
    }
    Ok(TileArg { index, count })
}

/// `--frames A..B`: frames `A` up to but not including `B`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame.
    pub start: u32,
    /// One past the last frame.
    pub end: u32,
}

/// Parse `A..B` (B excluded) or `A..=B` (B included), with at least one frame.
pub fn parse_frames(s: &str) -> Result<FrameRange, String> {
    let (a, b, inclusive) = if let Some((a, b)) = s.split_once("..=") {
        (a, b, true)
    } else if let Some((a, b)) = s.split_once("..") {
        (a, b, false)
    } else {
        return Err(format!(
            "'{s}' is not A..B (frames A to B, B excluded) or A..=B"
        ));
    };
    let num = |t: &str| -> Result<u32, String> {
        t.trim()
            .parse()
            .map_err(|_| format!("'{t}' in '{s}' is not a whole number ≥ 0"))
    };
    let (start, last) = (num(a)?, num(b)?);
    let end = if inclusive {
        last.checked_add(1).ok_or("frame number too large")?
    } else {
        last
    };
    if end <= start {
        return Err(format!("'{s}' holds no frames"));
    }
    Ok(FrameRange { start, end })
}

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

/// The frames to render: `(frame number, camera, output path)`; one frame,
/// `camera` to `out`, without `--orbit`.
pub fn frames(
    camera: &Camera,
    out: &Path,
    orbit: Option<u32>,
    range: Option<FrameRange>,
) -> Result<Vec<(Option<u32>, Camera, PathBuf)>> {
    let Some(count) = orbit else {
        if range.is_some() {
            bail!("--frames needs a camera path: add --orbit FRAMES");
        }
        return Ok(vec![(None, *camera, out.to_path_buf())]);
    };
    if count == 0 {
        bail!("--orbit needs at least one frame");
    }
    let r = range.unwrap_or(FrameRange {
        start: 0,
        end: count,
    });
    if r.end > count {
        bail!(
            "--frames {}..{} reaches past the {count} frames of --orbit {count} (frames 0..{count})",
            r.start,
            r.end
        );
    }
    Ok((r.start..r.end)
        .map(|k| (Some(k), orbit_camera(camera, k, count), frame_path(out, k)))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_and_frame_arguments_parse_and_refuse_nonsense() {
        assert_eq!(parse_tile("2/5"), Ok(TileArg { index: 2, count: 5 }));
        for bad in ["5/5", "1/0", "a/2", "3", "-1/2"] {
            assert!(parse_tile(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_frames("3..7"), Ok(FrameRange { start: 3, end: 7 }));
        assert_eq!(parse_frames("3..=7"), Ok(FrameRange { start: 3, end: 8 }));
        for bad in ["7..3", "3..3", "3", "a..4"] {
            assert!(parse_frames(bad).is_err(), "{bad}");
        }
    }

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
        let f = frames(
            &cam,
            Path::new("o.png"),
            Some(10),
            Some(FrameRange { start: 4, end: 6 }),
        )
        .unwrap();
        assert_eq!(
            f.iter().map(|x| x.0).collect::<Vec<_>>(),
            vec![Some(4), Some(5)]
        );
        assert!(frames(
            &cam,
            Path::new("o.png"),
            Some(5),
            Some(FrameRange { start: 4, end: 6 })
        )
        .is_err());
        assert!(frames(
            &cam,
            Path::new("o.png"),
            None,
            Some(FrameRange { start: 0, end: 1 })
        )
        .is_err());
        assert_eq!(
            frames(&cam, Path::new("o.png"), None, None).unwrap().len(),
            1
        );
    }
}
