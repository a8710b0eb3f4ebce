//! glTF images for base-colour textures: read from a file next to the
//! `.gltf` (URI relative to it, percent-decoded), a `data:` URI, or a buffer
//! view (GLB), decoded once per image on first use and shared between the
//! materials that use it. An image that cannot be read or decoded gives a
//! warning naming the file, the image index and its URI, and no texture.

use crate::texture_image::{decode_texture, Rows};
use crate::uri::{data_uri_payload, external_file, read_external};

/// Most bytes read of an image file a glTF file names.
const MAX_IMAGE_FILE: u64 = 1 << 30;
use ::gltf::json::Root;
use raykit_core::Texture;
use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

/// Decoded images by glTF image index, filled on first use, and by source
/// (the URI or buffer view), so that images that share their bytes are
/// decoded once.
pub(crate) struct ImageCache {
    /// `None`: not tried yet; `Some(None)`: failed (already warned).
    slots: Vec<Option<Option<Arc<Texture>>>>,
    by_source: std::collections::HashMap<String, Option<Arc<Texture>>>,
}

impl ImageCache {
    /// An empty cache for a document with `count` images.
    pub(crate) fn new(count: usize) -> Self {
        ImageCache {
            slots: vec![None; count],
            by_source: Default::default(),
        }
    }

    /// The texture of image `index` of `root`, decoding it on first use;
    /// failures are reported once in `warnings`.
    pub(crate) fn get(
        &mut self,
        path: &Path,
        root: &Root,
        buffers: &[Cow<'_, [u8]>],
        index: usize,
        warnings: &mut Vec<String>,
    ) -> Option<Arc<Texture>> {
        let slot = self.slots.get_mut(index)?;
        if let Some(done) = slot {
            return done.clone();
        }
        let source = root
            .images
            .get(index)
            .map(|img| match (&img.uri, &img.buffer_view) {
                (Some(uri), _) => format!("uri {uri}"),
                (None, Some(v)) => format!("view {}", v.value()),
                (None, None) => format!("image {index}"),
            });
        if let Some(done) = source.as_ref().and_then(|k| self.by_source.get(k)) {
            *slot = Some(done.clone());
            return done.clone();
        }
        let result = load_image(path, root, buffers, index);
        let tex = match result {
            Ok(t) => Some(Arc::new(t)),
            Err(why) => {
                warnings.push(format!(
                    "{}: base-colour texture not loaded: {why}",
                    describe(root, index)
                ));
                None
            }
        };
        *slot = Some(tex.clone());
        if let Some(k) = source {
            self.by_source.insert(k, tex.clone());
        }
        tex
    }
}

/// `images[N]` plus its URI (data URIs abbreviated) or buffer view.
fn describe(root: &Root, index: usize) -> String {
    let Some(img) = root.images.get(index) else {
        return format!("images[{index}]");
    };
    match (&img.uri, &img.buffer_view) {
        (Some(u), _) if u.starts_with("data:") => {
            let head = u.split(',').next().unwrap_or("data:");
            format!("images[{index}] ({head},…)")
        }
        (Some(u), _) => format!("images[{index}] (uri \"{u}\")"),
        (None, Some(v)) => format!("images[{index}] (bufferView {})", v.value()),
        (None, None) => format!("images[{index}]"),
    }
}

/// Read and decode image `index`; the error says what went wrong.
fn load_image(
    path: &Path,
    root: &Root,
    buffers: &[Cow<'_, [u8]>],
    index: usize,
) -> Result<Texture, String> {
    let img = root
        .images
        .get(index)
        .ok_or_else(|| format!("there is no image {index}"))?;
    let name = img.name.clone();
    let (bytes, name): (Cow<'_, [u8]>, String) = match (&img.uri, &img.buffer_view) {
        (Some(uri), _) => match data_uri_payload(uri) {
            Some(Ok(b)) => (Cow::Owned(b), name.unwrap_or(format!("image {index}"))),
            Some(Err(at)) => {
                return Err(format!("invalid base64 at character {at} of the data URI"))
            }
            None => {
                let dir = path.parent().unwrap_or(Path::new(""));
                let file = external_file(dir, uri)?;
                let b = read_external(&file, MAX_IMAGE_FILE)?;
                (Cow::Owned(b), file.display().to_string())
            }
        },
        (None, Some(v)) => (
            Cow::Borrowed(view_bytes(root, buffers, v.value())?),
            name.unwrap_or(format!("image {index}")),
        ),
        (None, None) => return Err("the image has neither a uri nor a bufferView".into()),
    };
    decode_texture(&name, &bytes, Rows::TopFirst).map_err(|e| format!("cannot decode {name}: {e}"))
}

/// The bytes of buffer view `v`, checked against its buffer.
pub(crate) fn view_bytes<'a>(
    root: &Root,
    buffers: &'a [Cow<'_, [u8]>],
    v: usize,
) -> Result<&'a [u8], String> {
    let view = root
        .buffer_views
        .get(v)
        .ok_or_else(|| format!("bufferView {v} does not exist"))?;
    let b = view.buffer.value();
    let data = buffers
        .get(b)
        .ok_or_else(|| format!("bufferViews[{v}] refers to missing buffer {b}"))?;
    let start = view.byte_offset.map_or(0, |o| o.0);
    let end = start.checked_add(view.byte_length.0);
    match end {
        Some(end) if end <= data.len() as u64 => Ok(&data[start as usize..end as usize]),
        _ => Err(format!(
            "bufferViews[{v}] (bytes {start}+{}) runs past the end of buffer {b} ({} bytes)",
            view.byte_length.0,
            data.len()
        )),
    }
}
