//! `EXT_meshopt_compression` (and its ratified twin
//! `KHR_meshopt_compression`): buffer views stored compressed with
//! meshoptimizer's vertex and index codecs, as glTF-Transform's `optimize`
//! and `meshopt` and gltfpack's `-cc` write them. Decoded with the
//! `meshopt` crate (meshoptimizer itself).
//!
//! A compressed view points at a "fallback" buffer that holds no data; its
//! extension names where the compressed bytes are and how to decode them.
//! Before the document is validated, each such view is pointed at a buffer
//! of its own, appended to the document, which is filled with the decoded
//! bytes once the buffers are loaded, so that accessors read it as any
//! other view.

use crate::error::{ErrorKind, LoadError, Location};
use ::gltf::json::validation::USize64;
use ::gltf::json::{Index, Root};
use meshopt::{decode_filter_color, decode_filter_exp, decode_filter_oct, decode_filter_quat};
use std::borrow::Cow;
use std::path::Path;

/// The extension's names.
pub(crate) const EXTENSIONS: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// How a view's bytes were encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Attributes,
    Triangles,
    Indices,
}

/// What is applied to decoded attributes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
    Color,
}

/// One compressed view.
struct Compressed {
    /// The view, for error messages.
    view: usize,
    /// The extension's name as the file spells it.
    name: &'static str,
    /// Where the compressed bytes are: buffer, offset, length.
    source: (usize, usize, usize),
    stride: usize,
    count: usize,
    mode: Mode,
    filter: Filter,
    /// The buffer appended for the decoded bytes.
    target: usize,
}

/// The compressed views of a document, and which buffers load as no bytes
/// (the fallback buffers and the ones appended for decoded views).
#[derive(Default)]
pub(crate) struct MeshoptViews {
    compressed: Vec<Compressed>,
    /// Per buffer index, whether it is loaded as no bytes.
    pub(crate) empty: Vec<bool>,
}

impl MeshoptViews {
    /// Find the compressed views of `root`, check what they claim (modes,
    /// filters and strides meshoptimizer decodes, and at most `memory`
    /// bytes decoded in all), and point each at a buffer appended for its
    /// decoded bytes.
    pub(crate) fn plan(path: &Path, root: &mut Root, memory: u64) -> Result<Self, LoadError> {
        let mut plan = MeshoptViews {
            compressed: Vec::new(),
            empty: vec![false; root.buffers.len()],
        };
        for (b, buffer) in root.buffers.iter().enumerate() {
            let fallback = EXTENSIONS.iter().any(|n| {
                buffer
                    .extensions
                    .as_ref()
                    .and_then(|e| e.others.get(*n))
                    .and_then(|x| x.get("fallback"))
                    .and_then(|f| f.as_bool())
                    == Some(true)
            });
            plan.empty[b] = fallback && buffer.uri.is_none();
        }
        let mut total: u64 = 0;
        let originals = root.buffers.len();
        for v in 0..root.buffer_views.len() {
            let Some((name, ext)) = EXTENSIONS.iter().find_map(|n| {
                root.buffer_views[v]
                    .extensions
                    .as_ref()
                    .and_then(|e| e.others.get(*n))
                    .map(|x| (*n, x.clone()))
            }) else {
                continue;
            };
            let field = format!("bufferViews[{v}].extensions.{name}");
            let err = |at: &str, msg: String| LoadError::at_json(path, format!("{field}{at}"), msg);
            let number = |key: &str, default: Option<u64>| -> Result<usize, LoadError> {
                match ext.get(key) {
                    None => default
                        .map(|d| d as usize)
                        .ok_or_else(|| err(&format!(".{key}"), "missing".into())),
                    Some(x) => x
                        .as_u64()
                        .and_then(|n| usize::try_from(n).ok())
                        .ok_or_else(|| {
                            err(&format!(".{key}"), format!("{x} is not a whole number"))
                        }),
                }
            };
            let source = (
                number("buffer", None)?,
                number("byteOffset", Some(0))?,
                number("byteLength", None)?,
            );
            if source.0 >= originals {
                return Err(err(
                    ".buffer",
                    format!("buffer {} does not exist", source.0),
                ));
            }
            let (stride, count) = (number("byteStride", None)?, number("count", None)?);
            let mode = match ext.get("mode").and_then(|m| m.as_str()) {
                Some("ATTRIBUTES") => Mode::Attributes,
                Some("TRIANGLES") => Mode::Triangles,
                Some("INDICES") => Mode::Indices,
                other => {
                    return Err(err(
                        ".mode",
                        format!("{other:?}: expected \"ATTRIBUTES\", \"TRIANGLES\" or \"INDICES\""),
                    ))
                }
            };
            let filter = match ext.get("filter").and_then(|f| f.as_str()) {
                None | Some("NONE") => Filter::None,
                Some("OCTAHEDRAL") => Filter::Octahedral,
                Some("QUATERNION") => Filter::Quaternion,
                Some("EXPONENTIAL") => Filter::Exponential,
                Some("COLOR") => Filter::Color,
                Some(f) => return Err(err(".filter", format!("unknown filter {f:?}"))),
            };
            let fits = match (mode, filter) {
                (Mode::Attributes, Filter::None | Filter::Exponential) => {
                    stride > 0 && stride <= 256 && stride % 4 == 0
                }
                (Mode::Attributes, Filter::Octahedral | Filter::Color) => {
                    stride == 4 || stride == 8
                }
                (Mode::Attributes, Filter::Quaternion) => stride == 8,
                (Mode::Triangles, Filter::None) => (stride == 2 || stride == 4) && count % 3 == 0,
                (Mode::Indices, Filter::None) => stride == 2 || stride == 4,
                _ => false,
            };
            if !fits {
                return Err(err(
                    "",
                    format!(
                        "mode {mode:?} with filter {filter:?}, byteStride {stride} and count {count} \
                         is not an encoding meshoptimizer decodes"
                    ),
                ));
            }
            let bytes = (stride as u64).saturating_mul(count as u64);
            total = total.saturating_add(bytes);
            if total > memory {
                return Err(LoadError::new(
                    path,
                    ErrorKind::Unsupported,
                    Location::Json(field),
                    format!(
                        "the compressed views decode to {total} bytes or more, more than the {memory} \
                         bytes of memory available"
                    ),
                ));
            }
            let target = root.buffers.len();
            root.buffers.push(::gltf::json::Buffer {
                byte_length: USize64(bytes),
                name: None,
                uri: None,
                extensions: None,
                extras: Default::default(),
            });
            plan.empty.push(true);
            let view = &mut root.buffer_views[v];
            view.buffer = Index::new(target as u32);
            view.byte_offset = Some(USize64(0));
            view.byte_length = USize64(bytes);
            plan.compressed.push(Compressed {
                view: v,
                name,
                source,
                stride,
                count,
                mode,
                filter,
                target,
            });
        }
        Ok(plan)
    }

    /// Decode every compressed view into its buffer in `buffers` (as
    /// loaded, the empty ones holding no bytes).
    pub(crate) fn decode(
        &self,
        path: &Path,
        buffers: &mut [Cow<'_, [u8]>],
    ) -> Result<(), LoadError> {
        for c in &self.compressed {
            let field = format!("bufferViews[{}].extensions.{}", c.view, c.name);
            let err = |msg: String| LoadError::at_json(path, field.clone(), msg);
            let (b, offset, length) = c.source;
            let data: &[u8] = &buffers[b];
            let end = offset
                .checked_add(length)
                .filter(|&e| e <= data.len())
                .ok_or_else(|| {
                    err(format!(
                        "bytes {offset}+{length} run past the end of buffers[{b}] ({} bytes{})",
                        data.len(),
                        if self.empty[b] {
                            ", a buffer without data"
                        } else {
                            ""
                        }
                    ))
                })?;
            let encoded = &data[offset..end];
            let mut out = decode_view(c, encoded).map_err(|e| {
                err(format!(
                    "the compressed data does not decode (meshoptimizer: {e})"
                ))
            })?;
            apply_filter(c.filter, c.stride, &mut out);
            buffers[c.target] = Cow::Owned(out);
        }
        Ok(())
    }
}

/// A vertex of `N` 32-bit words, the element type meshoptimizer's vertex
/// codec is given for a stride of `4 N` bytes.
#[derive(Clone, Copy)]
struct Words<const N: usize>([u32; N]);

impl<const N: usize> Default for Words<N> {
    fn default() -> Self {
        Words([0; N])
    }
}

/// The vertices of `encoded` as `stride = 4 N` bytes each.
fn vertices<const N: usize>(encoded: &[u8], count: usize) -> meshopt::Result<Vec<u8>> {
    let v: Vec<Words<N>> = meshopt::decode_vertex_buffer(encoded, count)?;
    Ok(v.iter()
        .flat_map(|w| w.0.iter().flat_map(|x| x.to_le_bytes()))
        .collect())
}

/// The decoded bytes of `c`'s view (`count × stride`).
fn decode_view(c: &Compressed, encoded: &[u8]) -> meshopt::Result<Vec<u8>> {
    macro_rules! by_words {
        ($($n:literal)*) => {
            match c.stride / 4 {
                $($n => vertices::<$n>(encoded, c.count),)*
                _ => unreachable!("strides are checked to be 4 to 256"),
            }
        };
    }
    let le = |v: Vec<u32>, two: bool| -> Vec<u8> {
        if two {
            v.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect()
        } else {
            v.iter().flat_map(|&i| i.to_le_bytes()).collect()
        }
    };
    match c.mode {
        Mode::Attributes => by_words!(
            1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32
            33 34 35 36 37 38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59 60
            61 62 63 64
        ),
        Mode::Triangles if c.stride == 2 => {
            let v: Vec<u16> = meshopt::decode_index_buffer(encoded, c.count)?;
            Ok(le(v.into_iter().map(u32::from).collect(), true))
        }
        Mode::Triangles => Ok(le(meshopt::decode_index_buffer(encoded, c.count)?, false)),
        Mode::Indices if c.stride == 2 => {
            let v: Vec<u16> = meshopt::decode_index_sequence(encoded, c.count)?;
            Ok(le(v.into_iter().map(u32::from).collect(), true))
        }
        Mode::Indices => Ok(le(meshopt::decode_index_sequence(encoded, c.count)?, false)),
    }
}

/// Undo `filter` in place on `bytes`, elements of `stride` bytes (strides
/// checked by [`MeshoptViews::plan`]).
fn apply_filter(filter: Filter, stride: usize, bytes: &mut [u8]) {
    fn with<T: Copy>(
        bytes: &mut [u8],
        size: usize,
        read: impl Fn(&[u8]) -> T,
        write: impl Fn(T, &mut [u8]),
        filter: impl FnOnce(&mut [T]),
    ) {
        let mut v: Vec<T> = bytes.chunks_exact(size).map(&read).collect();
        filter(&mut v);
        for (x, out) in v.into_iter().zip(bytes.chunks_exact_mut(size)) {
            write(x, out);
        }
    }
    let i8x4 = |b: &[u8]| [b[0] as i8, b[1] as i8, b[2] as i8, b[3] as i8];
    let put_i8x4 = |x: [i8; 4], o: &mut [u8]| o.copy_from_slice(&x.map(|c| c as u8));
    let u8x4 = |b: &[u8]| [b[0], b[1], b[2], b[3]];
    let put_u8x4 = |x: [u8; 4], o: &mut [u8]| o.copy_from_slice(&x);
    let i16x4 = |b: &[u8]| [0, 1, 2, 3].map(|k| i16::from_le_bytes([b[2 * k], b[2 * k + 1]]));
    let put_i16x4 = |x: [i16; 4], o: &mut [u8]| {
        for (k, c) in x.iter().enumerate() {
            o[2 * k..2 * k + 2].copy_from_slice(&c.to_le_bytes());
        }
    };
    let u16x4 = |b: &[u8]| [0, 1, 2, 3].map(|k| u16::from_le_bytes([b[2 * k], b[2 * k + 1]]));
    let put_u16x4 = |x: [u16; 4], o: &mut [u8]| {
        for (k, c) in x.iter().enumerate() {
            o[2 * k..2 * k + 2].copy_from_slice(&c.to_le_bytes());
        }
    };
    match (filter, stride) {
        (Filter::None, _) => {}
        (Filter::Octahedral, 4) => with(bytes, 4, i8x4, put_i8x4, decode_filter_oct),
        (Filter::Octahedral, _) => with(bytes, 8, i16x4, put_i16x4, decode_filter_oct),
        (Filter::Quaternion, _) => with(bytes, 8, i16x4, put_i16x4, decode_filter_quat),
        // Each 32-bit component is decoded on its own.
        (Filter::Exponential, _) => with(
            bytes,
            4,
            |b| [u32::from_le_bytes([b[0], b[1], b[2], b[3]])],
            |x: [u32; 1], o| o.copy_from_slice(&x[0].to_le_bytes()),
            decode_filter_exp::<1>,
        ),
        (Filter::Color, 4) => with(bytes, 4, u8x4, put_u8x4, decode_filter_color),
        (Filter::Color, _) => with(bytes, 8, u16x4, put_u16x4, decode_filter_color),
    }
}
