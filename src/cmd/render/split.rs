//! Splitting `raykit render` over independent processes, for batch
//! schedulers (a Slurm job array, a Kubernetes Indexed Job): `--tile I/N`
//! renders horizontal band I of N as a PNG part that `raykit merge-tiles`
//! assembles, and `--orbit FRAMES` with `--frames A..B` renders a range of
//! the frames of a camera path. Every pixel is rendered as in the whole
//! image (the renderer's crop window), so the assembled image equals a
//! one-process render bit for bit.

use anyhow::{bail, Result};
pub use raykit_render::animation::FrameRange;
use raykit_render::Tile;

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
    if count == 0 {
        return Err(format!("'{s}': the count N must be at least 1"));
    }
    if index >= count {
        return Err(format!(
            "'{s}': the band index must be below the count (0 to {})",
            count.saturating_sub(1)
        ));
    }
    Ok(TileArg { index, count })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_and_frame_arguments_parse_and_refuse_nonsense() {
        assert_eq!(parse_tile("2/5"), Ok(TileArg { index: 2, count: 5 }));
        for bad in ["5/5", "1/0", "a/2", "3", "-1/2"] {
            assert!(parse_tile(bad).is_err(), "{bad}");
        }
        // A zero count is named as such, not as an index out of 0 to 0.
        let zero = parse_tile("0/0").unwrap_err();
        assert!(
            zero.contains("at least 1") && !zero.contains("0 to"),
            "{zero}"
        );
        assert_eq!(parse_frames("3..7"), Ok(FrameRange { start: 3, end: 7 }));
        assert_eq!(parse_frames("3..=7"), Ok(FrameRange { start: 3, end: 8 }));
        for bad in ["7..3", "3..3", "3", "a..4"] {
            assert!(parse_frames(bad).is_err(), "{bad}");
        }
    }
}
