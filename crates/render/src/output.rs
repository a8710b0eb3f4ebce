//! Writing rendered images: PNG (8-bit sRGB) or OpenEXR (linear float), and
//! AOV files next to them.

use crate::aov::{AovKind, Aovs};
use crate::whitted::Frame;
use crate::Image;
use raykit_core::Camera;
use raykit_core::TriangleMesh;
use std::io;
use std::path::{Path, PathBuf};

/// Output image format, from the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB PNG.
    Png,
    /// Linear float OpenEXR.
    Exr,
}

impl ImageFormat {
    /// The format of `path` by its extension; the error names the file.
    pub fn of(path: &Path) -> Result<ImageFormat, String> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") => Ok(ImageFormat::Png),
            Some("exr") => Ok(ImageFormat::Exr),
            _ => Err(format!(
                "{}: the output must end in .png or .exr",
                path.display()
            )),
        }
    }
}

/// Write `image` to `path` (atomically).
pub fn write_image(path: &Path, format: ImageFormat, image: &Image) -> io::Result<()> {
    match format {
        ImageFormat::Png => raykit_io::write_png(path, image.width, image.height, &image.rgb)?,
        ImageFormat::Exr => {
            let rgb: Vec<[f32; 3]> = image.linear.iter().map(|c| c.to_array()).collect();
            raykit_io::write_exr_rgb(path, image.width, image.height, &rgb)?
        }
    }
    Ok(())
}

/// `out` with `.KIND.EXT` in place of its extension.
fn sibling(out: &Path, kind: AovKind, ext: &str) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    out.with_file_name(format!("{stem}.{}.{ext}", kind.name()))
}

/// The files [`write_aov`] writes for `out` and `kind`: `STEM.KIND.exr`
/// and `STEM.KIND.png`.
pub fn aov_paths(out: &Path, kind: AovKind) -> [PathBuf; 2] {
    [sibling(out, kind, "exr"), sibling(out, kind, "png")]
}

/// Write AOV `kind` of `frame` as EXR and a PNG preview next to `out`
/// (`STEM.KIND.exr` and `STEM.KIND.png`); the paths written.
pub fn write_aov(
    out: &Path,
    kind: AovKind,
    mesh: &TriangleMesh,
    camera: &Camera,
    frame: &Frame,
) -> io::Result<(PathBuf, PathBuf)> {
    let (w, h) = (frame.image.width, frame.image.height);
    let aovs = Aovs::from_hits(mesh, camera, w, h, &frame.first_hits);
    let channels = aovs.channels(kind);
    let refs: Vec<(&str, &[f32])> = channels.iter().map(|(n, c)| (*n, c.as_slice())).collect();
    let exr = sibling(out, kind, "exr");
    raykit_io::write_exr_channels(&exr, w, h, &refs)?;
    let png = sibling(out, kind, "png");
    raykit_io::write_png(&png, w, h, &aovs.preview(kind))?;
    Ok((exr, png))
}
