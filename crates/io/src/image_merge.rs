//! Assembling the PNG parts of a picture rendered in bands (each part
//! names its place, see [`crate::ImagePart`]) into the whole picture,
//! refusing parts that overlap, leave pixels uncovered or belong to
//! pictures of different sizes or, where the parts record it, to different
//! pictures.

use crate::error::LoadError;
use crate::image_part::{read_png_part, read_png_placement, ImagePart};
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
/// to a picture of one size; errors name the part at fault. The parts'
/// placements are checked before the picture is allocated, so a part that
/// claims a large picture costs nothing unless the parts fill it.
pub fn merge_png_parts(paths: &[&Path]) -> Result<(u32, u32, Vec<u8>), MergeError> {
    if paths.is_empty() {
        return Err(MergeError::Parts("no parts to merge".into()));
    }
    let placements = paths
        .iter()
        .map(|p| read_png_placement(p).map_err(MergeError::Read))
        .collect::<Result<Vec<_>, _>>()?;
    let (width, height) = (placements[0].full_width, placements[0].full_height);
    for (part, path) in placements.iter().zip(paths) {
        if (part.full_width, part.full_height) != (width, height) {
            return Err(MergeError::Parts(format!(
                "{}: a part of a {}×{} image, but {} is a part of a {width}×{height} image",
                path.display(),
                part.full_width,
                part.full_height,
                paths[0].display()
            )));
        }
    }
    // Parts that record what their picture shows must show one picture.
    let mut recorded = placements.iter().zip(paths).filter(|(p, _)| p.picture != 0);
    if let Some((first, first_path)) = recorded.next() {
        if let Some((_, path)) = recorded.find(|(p, _)| p.picture != first.picture) {
            return Err(MergeError::Parts(format!(
                "{}: a part of another picture than {} (rendered from another scene, camera, \
                 lights or settings)",
                path.display(),
                first_path.display()
            )));
        }
    }
    check_tiling(&placements, paths)?;
    let mut rgb = vec![0u8; width as usize * height as usize * 3];
    for (placed, path) in placements.iter().zip(paths) {
        let (part, pixels) = read_png_part(path).map_err(MergeError::Read)?;
        if part != *placed {
            return Err(MergeError::Parts(format!(
                "{}: changed while the parts were merged",
                path.display()
            )));
        }
        paste(&part, &pixels, &mut rgb);
    }
    Ok((width, height, rgb))
}

/// Check that the parts, all of one picture, cover each of its pixels
/// exactly once, row by row over the parts' column ranges; the first
/// overlap (in row order, naming the later of the two parts) is reported
/// before any gap.
fn check_tiling(parts: &[ImagePart], paths: &[&Path]) -> Result<(), MergeError> {
    let (width, height) = (parts[0].full_width, parts[0].full_height);
    let mut gap: Option<(u32, u32)> = None;
    let mut missing = 0u64;
    let mut row: Vec<(u32, u32, usize)> = Vec::new();
    for y in 0..height {
        row.clear();
        row.extend(
            parts
                .iter()
                .enumerate()
                .filter(|(_, p)| p.y <= y && y - p.y < p.height)
                .map(|(i, p)| (p.x, p.x + p.width, i)),
        );
        row.sort_unstable();
        // Covered up to column `end`, by part `owner` at the far end.
        let (mut end, mut owner) = (0u32, usize::MAX);
        for &(x0, x1, i) in &row {
            if x0 < end {
                let (later, earlier) = (i.max(owner), i.min(owner));
                return Err(MergeError::Parts(overlap(
                    paths[later],
                    paths[earlier],
                    x0,
                    y,
                )));
            }
            if x0 > end {
                gap.get_or_insert((end, y));
                missing += u64::from(x0 - end);
            }
            (end, owner) = (x1, i);
        }
        if end < width {
            gap.get_or_insert((end, y));
            missing += u64::from(width - end);
        }
    }
    match gap {
        None => Ok(()),
        Some((x, y)) => Err(MergeError::Parts(format!(
            "the parts leave {missing} of the {width}×{height} pixels uncovered, the first at column {x}, row {y}: a part is missing"
        ))),
    }
}

/// Copy `pixels` into `rgb` at `part`'s place.
fn paste(part: &ImagePart, pixels: &[u8], rgb: &mut [u8]) {
    let w = part.full_width as usize;
    let row_bytes = part.width as usize * 3;
    for row in 0..part.height as usize {
        let at = ((part.y as usize + row) * w + part.x as usize) * 3;
        rgb[at..at + row_bytes].copy_from_slice(&pixels[row * row_bytes..(row + 1) * row_bytes]);
    }
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
                    picture: 7,
                };
                let path = dir.join(format!("p{i}.png"));
                write_png_part(&path, &part, &rgb).unwrap();
                path
            })
            .collect()
    }

    /// Parts that record different pictures are refused by name; a part
    /// that records none (written before the record existed) merges with
    /// the others.
    #[test]
    fn parts_of_another_picture_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let paths = write_bands(dir.path(), &[(0, 2), (2, 4)]);
        let (mut part, rgb) = read_png_part(&paths[1]).unwrap();
        part.picture = 8;
        write_png_part(&paths[1], &part, &rgb).unwrap();
        let refs: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
        let e = merge_png_parts(&refs).unwrap_err().to_string();
        assert!(
            e.contains("p1.png") && e.contains("p0.png") && e.contains("another picture"),
            "{e}"
        );
        part.picture = 0;
        write_png_part(&paths[1], &part, &rgb).unwrap();
        let (w, h, _) = merge_png_parts(&refs).unwrap();
        assert_eq!((w, h), (3, 4));
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

    /// Rectangles of a 7×5 picture (a guillotine cut, then one rectangle
    /// dropped, repeated or moved, or none) merged, against a count of the
    /// parts over each pixel: the first pixel in row order that two cover
    /// or none covers is the one named, and whole covers give the pixels.
    #[test]
    fn rectangles_are_checked_pixel_by_pixel() {
        let (w, h) = (7u32, 5u32);
        let dir = tempfile::tempdir().unwrap();
        let mut rng = raykit_core::rng::Pcg32::new(3);
        for round in 0..200 {
            let mut rects = vec![(0u32, 0u32, w, h)];
            for _ in 0..rng.below(6) {
                let k = rng.below(rects.len() as u32) as usize;
                let (x, y, rw, rh) = rects[k];
                if rw > 1 && (rng.below(2) == 0 || rh == 1) {
                    let cut = 1 + rng.below(rw - 1);
                    rects[k] = (x, y, cut, rh);
                    rects.push((x + cut, y, rw - cut, rh));
                } else if rh > 1 {
                    let cut = 1 + rng.below(rh - 1);
                    rects[k] = (x, y, rw, cut);
                    rects.push((x, y + cut, rw, rh - cut));
                }
            }
            let k = rng.below(rects.len() as u32) as usize;
            match rng.below(4) {
                0 if rects.len() > 1 => {
                    rects.remove(k);
                }
                1 => rects.push(rects[k]),
                2 => {
                    let (x, y, rw, rh) = rects[k];
                    rects[k] = (x.saturating_sub(1), y, rw, rh);
                }
                _ => {}
            }
            let mut count = vec![0u32; (w * h) as usize];
            let mut paths = Vec::new();
            for (i, &(x, y, rw, rh)) in rects.iter().enumerate() {
                let mut rgb = Vec::new();
                for py in y..y + rh {
                    for px in x..x + rw {
                        count[(py * w + px) as usize] += 1;
                        rgb.extend([px as u8, py as u8, (px * py) as u8]);
                    }
                }
                let part = ImagePart {
                    x,
                    y,
                    width: rw,
                    height: rh,
                    full_width: w,
                    full_height: h,
                    picture: 0,
                };
                let path = dir.path().join(format!("r{round}-{i}.png"));
                write_png_part(&path, &part, &rgb).unwrap();
                paths.push(path);
            }
            let refs: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
            let at = |i: usize| format!("column {}, row {}", i as u32 % w, i as u32 / w);
            let result = merge_png_parts(&refs);
            if let Some(i) = count.iter().position(|&c| c > 1) {
                let m = result.err().map(|e| e.to_string()).unwrap_or_default();
                assert!(m.contains("overlaps") && m.contains(&at(i)), "{round}: {m}");
            } else if let Some(i) = count.iter().position(|&c| c == 0) {
                let m = result.err().map(|e| e.to_string()).unwrap_or_default();
                let missing = count.iter().filter(|&&c| c == 0).count();
                assert!(
                    m.contains("uncovered") && m.contains(&at(i)),
                    "{round}: {m}"
                );
                assert!(m.contains(&format!("leave {missing} of")), "{round}: {m}");
            } else {
                let (_, _, rgb) = result.unwrap();
                for (i, px) in rgb.chunks(3).enumerate() {
                    let (x, y) = (i as u32 % w, i as u32 / w);
                    assert_eq!(px, [x as u8, y as u8, (x * y) as u8], "{round}");
                }
            }
        }
    }

    /// A part claiming a picture it does not fill is refused by its
    /// placement, before a picture of that size is allocated.
    #[test]
    fn a_part_claiming_a_large_picture_is_refused_as_missing_parts() {
        let dir = tempfile::tempdir().unwrap();
        let part = ImagePart {
            x: 0,
            y: 0,
            width: 1,
            height: 1,
            full_width: 16384,
            full_height: 16384,
            picture: 0,
        };
        let path = dir.path().join("one.png");
        write_png_part(&path, &part, &[1, 2, 3]).unwrap();
        let m = merge_png_parts(&[path.as_path()]).unwrap_err().to_string();
        assert!(m.contains("leave 268435455 of the 16384×16384"), "{m}");
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
