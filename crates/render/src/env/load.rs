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

/// Most texels an environment map may have: 2^28, a 16384 × 16384 map or
/// twice a 16K (16384 × 8192) panorama; 3 GiB decoded. A file whose header
/// claims more is refused before anything is allocated.
pub const MAX_TEXELS: usize = 1 << 28;

/// Refuse a `width` × `height` map of more than [`MAX_TEXELS`].
fn check_size(path: &Path, width: usize, height: usize) -> Result<(), EnvError> {
    match width.checked_mul(height) {
        Some(n) if n <= MAX_TEXELS => Ok(()),
        _ => Err(EnvError::Invalid {
            path: path.to_path_buf(),
            message: format!(
                "{width}×{height} texels; an environment map has at most {MAX_TEXELS} (16384 × 16384)"
            ),
        }),
    }
}

/// Whether the memory a `width`×`height` map needs while it is decoded
/// (the decoder's RGB f32 image and our copy of it, 24 bytes a texel) can
/// be had, asked for before decoding: the decoder allocates its image
/// before it reads a pixel, and an allocation that fails there aborts the
/// process, where a header that claims more than the process may use
/// should be an error naming the file.
fn check_memory(path: &Path, width: usize, height: usize) -> Result<(), EnvError> {
    let bytes = width.saturating_mul(height).saturating_mul(24);
    let mut probe: Vec<u8> = Vec::new();
    probe
        .try_reserve_exact(bytes)
        .map_err(|_| EnvError::Invalid {
            path: path.to_path_buf(),
            message: format!(
                "{width}×{height} texels need {:.1} GiB while decoding, more than this process \
                 can allocate",
                bytes as f64 / (1u64 << 30) as f64
            ),
        })
}

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
    let decode_error = |e: exr::error::Error| EnvError::Decode {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    // Open first so a missing file is an I/O error, not a decode error.
    drop(open(path)?);
    // The layers' sizes from the headers, before the decoder allocates
    // any of them.
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(decode_error)?;
    for header in &meta.headers {
        check_size(path, header.layer_size.0, header.layer_size.1)?;
    }
    let image = read_first_rgba_layer_from_file(
        path,
        |size: ExrVec2<usize>, _| {
            // Left empty where memory cannot be had; found below.
            let mut texels = Vec::new();
            if texels.try_reserve_exact(size.0 * size.1).is_ok() {
                texels.resize(size.0 * size.1, [0.0f32; 3]);
            }
            (size.0, texels)
        },
        |(w, texels): &mut (usize, Vec<[f32; 3]>),
         pos: ExrVec2<usize>,
         (r, g, b, _a): (f32, f32, f32, f32)| {
            if let Some(t) = texels.get_mut(pos.1 * *w + pos.0) {
                *t = [r, g, b];
            }
        },
    )
    .map_err(decode_error)?;
    let size = image.layer_data.size;
    let (_, texels) = image.layer_data.channel_data.pixels;
    if texels.len() != size.0 * size.1 {
        return Err(EnvError::Invalid {
            path: path.to_path_buf(),
            message: format!("no memory for its {}×{} texels", size.0, size.1),
        });
    }
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
    let hdr = image::ImageFormat::Hdr;
    if let Ok((w, h)) = image::ImageReader::with_format(std::io::Cursor::new(bytes.as_slice()), hdr)
        .into_dimensions()
    {
        check_size(path, w as usize, h as usize)?;
        check_memory(path, w as usize, h as usize)?;
    }
    let mut cursor = std::io::Cursor::new(bytes.as_slice());
    let mut reader = image::ImageReader::with_format(&mut cursor, hdr);
    // The image crate's default bound (512 MiB) refused maps of more than
    // about 11 million texels; `check_size` is the bound here.
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(16 * MAX_TEXELS as u64);
    reader.limits(limits);
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
