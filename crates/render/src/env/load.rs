//! Reading [`EquirectMap`]s from OpenEXR (`exr` crate) and Radiance `.hdr`
//! (RGBE, `image` crate) files.

use super::equirect::EquirectMap;
use super::error::EnvError;
use std::fs::File;
use std::io::Read;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

/// Decoded texels: width, height, rows top to bottom.
type Decoded = (usize, usize, Vec<[f32; 3]>);

impl EquirectMap {
    /// Load an equirectangular map from an OpenEXR file (`.exr`: the R, G and B
    /// channels of its first layer, any sample type and compression the `exr`
    /// crate reads) or a Radiance RGBE file (`.hdr` or `.pic`), chosen by
    /// extension. Non-finite and negative texels are set to 0 and counted in
    /// [`clamped_texels`](Self::clamped_texels). Every error names the file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, EnvError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        let decode: fn(&Path) -> Result<Decoded, EnvError> = match ext.as_deref() {
            Some("exr") => decode_exr,
            Some("hdr") | Some("pic") => decode_hdr,
            _ => {
                return Err(EnvError::UnknownFormat {
                    path: path.to_path_buf(),
                })
            }
        };
        // The decoders are third-party code fed arbitrary bytes: should one of
        // them panic, report a decode error rather than take the caller down.
        let (w, h, texels) =
            catch_unwind(AssertUnwindSafe(|| decode(path))).unwrap_or_else(|_| {
                Err(EnvError::Decode {
                    path: path.to_path_buf(),
                    message: "the decoder failed on this file".into(),
                })
            })?;
        EquirectMap::from_texels(path, w, h, texels)
    }
}

fn open(path: &Path) -> Result<File, EnvError> {
    File::open(path).map_err(|source| EnvError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn decode_exr(path: &Path) -> Result<Decoded, EnvError> {
    use exr::prelude::{read_first_rgba_layer_from_file, Vec2 as ExrVec2};
    // Open first so a missing file is an I/O error, not a decode error.
    drop(open(path)?);
    let image = read_first_rgba_layer_from_file(
        path,
        |size: ExrVec2<usize>, _| (size.0, vec![[0.0f32; 3]; size.0 * size.1]),
        |(w, texels): &mut (usize, Vec<[f32; 3]>),
         pos: ExrVec2<usize>,
         (r, g, b, _a): (f32, f32, f32, f32)| {
            if let Some(t) = texels.get_mut(pos.1 * *w + pos.0) {
                *t = [r, g, b];
            }
        },
    )
    .map_err(|e| EnvError::Decode {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let size = image.layer_data.size;
    let (_, texels) = image.layer_data.channel_data.pixels;
    Ok((size.0, size.1, texels))
}

/// Decode a Radiance file read whole, so that an error can name the byte
/// the decoder had reached (and a truncated file say so).
fn decode_hdr(path: &Path) -> Result<Decoded, EnvError> {
    let mut bytes = Vec::new();
    open(path)?
        .read_to_end(&mut bytes)
        .map_err(|source| EnvError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    let mut cursor = std::io::Cursor::new(bytes.as_slice());
    let reader = image::ImageReader::with_format(&mut cursor, image::ImageFormat::Hdr);
    let decoded = reader.decode();
    let at = cursor.position();
    let img = decoded.map_err(|e| {
        let ended = matches!(&e, image::ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof);
        let message = if ended {
            format!("the file ends at byte {} before its pixels do (truncated?)", bytes.len())
        } else {
            format!("{e} (at byte {at})")
        };
        EnvError::Decode {
            path: path.to_path_buf(),
            message,
        }
    })?;
    let rgb = img.into_rgb32f();
    let (w, h) = (rgb.width() as usize, rgb.height() as usize);
    let texels = rgb.pixels().map(|p| p.0).collect();
    Ok((w, h, texels))
}
