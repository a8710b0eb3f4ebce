//! `raykit merge-tiles`: assemble the PNG parts of `raykit render --tile`
//! into the whole image, refusing parts that overlap, leave pixels
//! uncovered or belong to pictures of different sizes.

use anyhow::{bail, Context, Result};
use clap::Args;
use raykit_io::ImagePart;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Arguments of `raykit merge-tiles`.
#[derive(Args)]
#[command(after_help = "Example (one band per process, then one merge):\n  \
for i in 0 1 2 3; do raykit render --tile $i/4 --out part$i.png; done\n  \
raykit merge-tiles render.png part0.png part1.png part2.png part3.png\n\n\
Each part names its place in the image (a PNG text chunk written by --tile),\n\
so the parts may be given in any order. The merged image equals the one\n\
`raykit render` writes in one process with the same options, bit for bit.")]
pub struct MergeTilesArgs {
    /// The whole image to write (`.png`), atomically.
    out: PathBuf,
    /// The parts written by `raykit render --tile I/N`.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
}

/// Read, check and assemble the parts.
pub fn run(args: MergeTilesArgs) -> Result<ExitCode> {
    let inputs: Vec<&Path> = args.parts.iter().map(PathBuf::as_path).collect();
    crate::paths::ensure_not_input(&args.out, &inputs)?;
    let (width, height, rgb) = merge(&inputs)?;
    raykit_io::write_png(&args.out, width, height, &rgb)
        .with_context(|| format!("writing {}", args.out.display()))?;
    eprintln!(
        "{} parts -> {} ({width}×{height})",
        args.parts.len(),
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// The picture the parts at `paths` cover: width, height and RGB bytes.
/// Errors name the part at fault.
pub fn merge(paths: &[&Path]) -> Result<(u32, u32, Vec<u8>)> {
    let mut size: Option<(u32, u32, &Path)> = None;
    let mut rgb = Vec::new();
    // The part covering each pixel so far (index into `paths`).
    let mut owner: Vec<u32> = Vec::new();
    const NONE: u32 = u32::MAX;
    for (i, path) in paths.iter().enumerate() {
        let (part, pixels) = raykit_io::read_png_part(path)?;
        match size {
            None => {
                size = Some((part.full_width, part.full_height, path));
                let n = part.full_width as usize * part.full_height as usize;
                rgb = vec![0u8; n * 3];
                owner = vec![NONE; n];
            }
            Some((w, h, first)) if (w, h) != (part.full_width, part.full_height) => bail!(
                "{}: a part of a {}×{} image, but {} is a part of a {w}×{h} image",
                path.display(),
                part.full_width,
                part.full_height,
                first.display()
            ),
            Some(_) => {}
        }
        paste(&part, &pixels, i as u32, &mut rgb, &mut owner)
            .map_err(|(x, y, other)| overlap(path, paths[other as usize], x, y))?;
    }
    let (width, height, _) = size.expect("at least one part");
    let missing = owner.iter().filter(|&&o| o == NONE).count();
    if let Some(first) = owner.iter().position(|&o| o == NONE) {
        let (x, y) = (first % width as usize, first / width as usize);
        bail!(
            "the parts leave {missing} of the {width}×{height} pixels uncovered, the first at column {x}, row {y}: a part is missing"
        );
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

fn overlap(path: &Path, other: &Path, x: u32, y: u32) -> anyhow::Error {
    anyhow::anyhow!(
        "{}: overlaps {} at column {x}, row {y} (each pixel must come from one part)",
        path.display(),
        other.display()
    )
}
