//! Assembling the PNG parts of a picture rendered in bands (each part
//! names its place, see [`crate::ImagePart`]) into the whole picture,
//! refusing parts that overlap, leave pixels uncovered or belong to
//! pictures of different sizes.

use crate::error::LoadError;
use crate::image_part::{read_png_part, ImagePart};
use std::path::Path;

/// Why parts do not make a picture.
#[derive(Debug)]
pub enum MergeError {
    /// A part could not be read.
    Read(LoadError),
    /// The parts do not fit together (overlap, gap, sizes); the message
    /// names the part at fault.
    Parts(String),
}

impl std::fmt::Display for MergeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MergeError::Read(e) => write!(f, "{e}"),
            MergeError::Parts(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for MergeError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            MergeError::Read(e) => e.source(),
            MergeError::Parts(_) => None,
        }
    }
}

/// The picture the parts at `paths` cover: width, height and RGB bytes.
/// Every pixel must come from exactly one part, and all parts must belong
/// to a picture of one size; errors name the part at fault.
pub fn merge_png_parts(paths: &[&Path]) -> Result<(u32, u32, Vec<u8>), MergeError> {
    if paths.is_empty() {
        return Err(MergeError::Parts("no parts to merge".into()));
    }
    let mut size: Option<(u32, u32, &Path)> = None;
    let mut rgb = Vec::new();
    // The part covering each pixel so far (index into `paths`).
    let mut owner: Vec<u32> = Vec::new();
    const NONE: u32 = u32::MAX;
    for (i, path) in paths.iter().enumerate() {
        let (part, pixels) = read_png_part(path).map_err(MergeError::Read)?;
        match size {
            None => {
                size = Some((part.full_width, part.full_height, path));
                let n = part.full_width as usize * part.full_height as usize;
                rgb = vec![0u8; n * 3];
                owner = vec![NONE; n];
            }
            Some((w, h, first)) if (w, h) != (part.full_width, part.full_height) => {
                return Err(MergeError::Parts(format!(
                    "{}: a part of a {}×{} image, but {} is a part of a {w}×{h} image",
                    path.display(),
                    part.full_width,
                    part.full_height,
                    first.display()
                )))
            }
            Some(_) => {}
        }
        paste(&part, &pixels, i as u32, &mut rgb, &mut owner).map_err(|(x, y, other)| {
            MergeError::Parts(overlap(path, paths[other as usize], x, y))
        })?;
    }
    let (width, height, _) = size.expect("at least one part");
    let missing = owner.iter().filter(|&&o| o == NONE).count();
    if let Some(first) = owner.iter().position(|&o| o == NONE) {
        let (x, y) = (first % width as usize, first / width as usize);
        return Err(MergeError::Parts(format!(
            "the parts leave {missing} of the {width}×{height} pixels uncovered, the first at column {x}, row {y}: a part is missing"
        )));
    }
    Ok((width, height, rgb))
}

/// Copy `pixels` into `rgb` at `part`'s place, marking the pixels as
/// `index`'s; on a pixel already covered, its position and owner.
fn paste(
    part: &ImagePart,
    pixels: &[u8],
    index: u32,
    rgb: &mut [u8],
    owner: &mut [u32],
) -> Result<(), (u32, u32, u32)> {
    let w = part.full_width as usize;
    for row in 0..part.height {
        let y = part.y + row;
        for col in 0..part.width {
            let x = part.x + col;
            let at = y as usize * w + x as usize;
            if owner[at] != u32::MAX {
                return Err((x, y, owner[at]));
            }
            owner[at] = index;
            let src = (row as usize * part.width as usize + col as usize) * 3;
            rgb[at * 3..at * 3 + 3].copy_from_slice(&pixels[src..src + 3]);
        }
    }
    Ok(())
}

/// The error of two parts covering one pixel.
fn overlap(path: &Path, other: &Path, x: u32, y: u32) -> String {
    format!(
        "{}: overlaps {} at column {x}, row {y} (each pixel must come from one part)",
        path.display(),
        other.display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image_part::write_png_part;

    /// A 3×4 picture whose pixel (x, y) is (x, y, x + y), cut in `bands`.
    fn write_bands(dir: &Path, bands: &[(u32, u32)]) -> Vec<std::path::PathBuf> {
        let (w, h) = (3u32, 4u32);
        bands
            .iter()
            .enumerate()
            .map(|(i, &(y0, y1))| {
                let mut rgb = Vec::new();
                for y in y0..y1 {
                    for x in 0..w {
                        rgb.extend([x as u8, y as u8, (x + y) as u8]);
                    }
                }
                let part = ImagePart {
                    x: 0,
                    y: y0,
                    width: w,
                    height: y1 - y0,
                    full_width: w,
                    full_height: h,
                };
                let path = dir.join(format!("p{i}.png"));
                write_png_part(&path, &part, &rgb).unwrap();
                path
            })
            .collect()
    }

    #[test]
    fn bands_in_any_order_give_the_whole_picture() {
        let dir = tempfile::tempdir().unwrap();
        let paths = write_bands(dir.path(), &[(2, 4), (0, 1), (1, 2)]);
        let refs: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
        let (w, h, rgb) = merge_png_parts(&refs).unwrap();
        assert_eq!((w, h), (3, 4));
        for y in 0..4u32 {
            for x in 0..3u32 {
                let at = ((y * 3 + x) * 3) as usize;
                assert_eq!(rgb[at..at + 3], [x as u8, y as u8, (x + y) as u8]);
            }
        }
    }

    #[test]
    fn gaps_and_overlaps_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let paths = write_bands(dir.path(), &[(0, 2), (1, 3)]);
        let refs: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
        let message = |r: Result<_, MergeError>| match r {
            Err(MergeError::Parts(m)) => m,
            other => panic!("{:?}", other.map(|_| ())),
        };
        assert!(message(merge_png_parts(&refs)).contains("overlaps"));
        assert!(message(merge_png_parts(&refs[..1])).contains("uncovered"));
        let missing = dir.path().join("none.png");
        assert!(matches!(
            merge_png_parts(&[missing.as_path()]),
            Err(MergeError::Read(_))
        ));
    }
}
