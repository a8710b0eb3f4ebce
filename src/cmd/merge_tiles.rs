//! `raykit merge-tiles`: assemble the PNG parts of `raykit render --tile`
//! into the whole image, refusing parts that overlap, leave pixels
//! uncovered or belong to pictures of different sizes or contents.

use anyhow::{Context, Result};
use clap::Args;
use raykit_io::{merge_png_parts, MergeError};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Arguments of `raykit merge-tiles`.
#[derive(Args)]
#[command(after_help = "Example (one band per process, then one merge):\n  \
for i in 0 1 2 3; do raykit render --tile $i/4 --out part$i.png; done\n  \
raykit merge-tiles render.png part0.png part1.png part2.png part3.png\n\n\
Each part names its place in the image (a PNG text chunk written by --tile),\n\
so the parts may be given in any order. Each also holds a fingerprint of the\n\
geometry, camera, lights and sampling it was rendered with: parts of another\n\
picture of the same size are refused. The merged image equals the one\n\
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
    crate::paths::ensure_output(&args.out, &inputs)?;
    crate::paths::ensure_extension(&args.out, "the output (a PNG)", &["png"])?;
    let (width, height, rgb) = merge_png_parts(&inputs).map_err(|e| match e {
        MergeError::Read(e) => anyhow::Error::from(e),
        MergeError::Parts(m) => anyhow::Error::msg(m),
    })?;
    raykit_io::write_png(&args.out, width, height, &rgb)
        .with_context(|| format!("writing {}", args.out.display()))?;
    eprintln!(
        "{} parts -> {} ({width}×{height})",
        args.parts.len(),
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
