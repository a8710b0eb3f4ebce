//! OpenEXR output of float images (renders and AOVs such as depth, normals or
//! ids) through the `exr` crate: 32-bit float channels, ZIP (16 scanlines)
//! compression, one layer, top row first, written atomically.

use crate::atomic::write_atomic_file;
use ::exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec, Text,
    WritableImage,
};
use std::io;
use std::path::Path;

/// Write `rgb` (`width × height` pixels, row-major from the top) as an
/// OpenEXR file with 32-bit float `R`, `G` and `B` channels, atomically.
/// Errors name the file.
pub fn write_exr_rgb(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) -> io::Result<()> {
    let channel = |k: usize| rgb.iter().map(|p| p[k]).collect::<Vec<f32>>();
    let (r, g, b) = (channel(0), channel(1), channel(2));
    write_exr_channels(path, width, height, &[("R", &r), ("G", &g), ("B", &b)])
}

/// Write arbitrary named 32-bit float channels of a `width × height` image
/// (each row-major from the top) as one OpenEXR layer, atomically. Channel
/// names must be non-empty printable ASCII of at most 255 bytes and distinct;
/// readers list them in alphabetical order. Errors name the file.
pub fn write_exr_channels(
    path: &Path,
    width: u32,
    height: u32,
    channels: &[(&str, &[f32])],
) -> io::Result<()> {
    let invalid = |msg: String| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: {msg}", path.display()),
        )
    };
    let pixels = width as u64 * height as u64;
    if width == 0 || height == 0 {
        return Err(invalid(format!(
            "cannot write a {width}x{height} EXR image"
        )));
    }
    if channels.is_empty() {
        return Err(invalid("an EXR image needs at least one channel".into()));
    }
    let mut list = SmallVec::<[AnyChannel<FlatSamples>; 4]>::new();
    for (i, (name, samples)) in channels.iter().enumerate() {
        let printable = name.bytes().all(|b| (0x20..0x7f).contains(&b));
        let text = Text::new_or_none(name).filter(|_| printable);
        let text = match text {
            Some(t) if !name.is_empty() && name.len() <= 255 => t,
            _ => {
                return Err(invalid(format!(
                    "bad EXR channel name {name:?} (need 1 to 255 printable ASCII characters)"
                )))
            }
        };
        if channels[..i].iter().any(|(other, _)| other == name) {
            return Err(invalid(format!("EXR channel {name:?} given twice")));
        }
        if samples.len() as u64 != pixels {
            return Err(invalid(format!(
                "EXR channel {name:?} of a {width}x{height} image needs {pixels} samples, got {}",
                samples.len()
            )));
        }
        list.push(AnyChannel::new(text, FlatSamples::F32(samples.to_vec())));
    }
    let layer = Layer::new(
        (width as usize, height as usize),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let image = Image::from_layer(layer);
    let with_path = |e: io::Error| io::Error::new(e.kind(), format!("{}: {e}", path.display()));
    write_atomic_file(
        path,
        |w| {
            image
                .write()
                .to_buffered(w)
                .map_err(|e| io::Error::other(format!("{}: EXR encoding: {e}", path.display())))
        },
        with_path,
    )
}
