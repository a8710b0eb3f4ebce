//! Reading glTF accessors with every offset, stride and count checked against
//! the buffer data, so that malformed files give an error naming the accessor
//! instead of a panic. Handles all component types (normalised integers
//! included) and sparse accessors.

use crate::error::LoadError;
use ::gltf::accessor::{sparse::IndexType, Accessor, DataType};
use ::gltf::buffer::View;
use std::borrow::Cow;
use std::path::Path;

/// The data of every buffer of a document, by buffer index.
pub(crate) type Buffers<'a> = [Cow<'a, [u8]>];

/// The component values of `acc` (which must have `dims` components per
/// element) as f32, `count × dims` of them. Normalised integers are mapped to
/// [0, 1] or [-1, 1]. `limit` caps the count of accessors without data.
pub(crate) fn read_floats(
    path: &Path,
    acc: &Accessor<'_>,
    buffers: &Buffers<'_>,
    dims: usize,
    limit: usize,
) -> Result<Vec<f32>, LoadError> {
    let ty = acc.data_type();
    let norm = acc.normalized();
    let conv = move |b: &[u8]| -> f32 {
        match (ty, norm) {
            (DataType::F32, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            (DataType::I8, false) => b[0] as i8 as f32,
            (DataType::U8, false) => b[0] as f32,
            (DataType::I16, false) => i16::from_le_bytes([b[0], b[1]]) as f32,
            (DataType::U16, false) => u16::from_le_bytes([b[0], b[1]]) as f32,
            (DataType::U32, _) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
            (DataType::I8, true) => (b[0] as i8 as f32 / 127.0).max(-1.0),
            (DataType::U8, true) => b[0] as f32 / 255.0,
            (DataType::I16, true) => (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
            (DataType::U16, true) => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
        }
    };
    read(path, acc, buffers, dims, limit, conv)
}

/// The values of the scalar index accessor `acc` (unsigned byte, short or int).
pub(crate) fn read_indices(
    path: &Path,
    acc: &Accessor<'_>,
    buffers: &Buffers<'_>,
    limit: usize,
) -> Result<Vec<u32>, LoadError> {
    let ty = acc.data_type();
    if !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32) {
        return Err(LoadError::at_json(
            path,
            format!("accessors[{}]", acc.index()),
            format!("index accessor has component type {ty:?}; expected U8, U16 or U32"),
        ));
    }
    read(path, acc, buffers, 1, limit, move |b: &[u8]| match ty {
        DataType::U8 => b[0] as u32,
        DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    })
}

/// Refuse `acc` when its elements do not fit in its buffer view, before
/// anything is sized from its count (a count no data backs would otherwise
/// be reported as a file too large for memory).
pub(crate) fn check_fits(
    path: &Path,
    acc: &Accessor<'_>,
    buffers: &Buffers<'_>,
) -> Result<(), LoadError> {
    if let Some(view) = acc.view() {
        let name = format!("accessors[{}]", acc.index());
        let elem = acc.data_type().size() * acc.dimensions().multiplicity();
        view_slice(
            path,
            &name,
            &view,
            buffers,
            acc.offset(),
            acc.count(),
            elem,
            true,
        )?;
    }
    Ok(())
}

fn read<T: Copy + Default>(
    path: &Path,
    acc: &Accessor<'_>,
    buffers: &Buffers<'_>,
    dims: usize,
    limit: usize,
    conv: impl Fn(&[u8]) -> T,
) -> Result<Vec<T>, LoadError> {
    let name = format!("accessors[{}]", acc.index());
    let err = |msg: String| LoadError::at_json(path, name.clone(), msg);
    let got_dims = acc.dimensions().multiplicity();
    if got_dims != dims {
        return Err(err(format!(
            "accessor type is {:?}; expected {dims} components per element",
            acc.dimensions()
        )));
    }
    let comp = acc.data_type().size();
    let elem = comp * dims;
    let count = acc.count();
    let mut out = match acc.view() {
        Some(view) => {
            let (data, stride) =
                view_slice(path, &name, &view, buffers, acc.offset(), count, elem, true)?;
            let mut out = Vec::with_capacity(count * dims);
            for i in 0..count {
                let e = &data[i * stride..];
                for c in 0..dims {
                    out.push(conv(&e[c * comp..]));
                }
            }
            out
        }
        None => {
            if count > limit {
                return Err(err(format!(
                    "count {count} without a bufferView is implausible for a file this size"
                )));
            }
            vec![T::default(); count * dims]
        }
    };
    if let Some(sparse) = acc.sparse() {
        let n = sparse.count();
        let idx = sparse.indices();
        let isize_ = match idx.index_type() {
            IndexType::U8 => 1,
            IndexType::U16 => 2,
            IndexType::U32 => 4,
        };
        let sname = format!("{name}.sparse");
        let (ib, _) = view_slice(
            path,
            &sname,
            &idx.view(),
            buffers,
            idx.offset(),
            n,
            isize_,
            false,
        )?;
        let vals = sparse.values();
        let (vb, _) = view_slice(
            path,
            &sname,
            &vals.view(),
            buffers,
            vals.offset(),
            n,
            elem,
            false,
        )?;
        for k in 0..n {
            let b = &ib[k * isize_..];
            let i = match isize_ {
                1 => b[0] as usize,
                2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            if i >= count {
                return Err(LoadError::at_json(
                    path,
                    format!("{sname}.indices"),
                    format!("sparse index {i} is out of range (count {count})"),
                ));
            }
            for c in 0..dims {
                out[i * dims + c] = conv(&vb[k * elem + c * comp..]);
            }
        }
    }
    Ok(out)
}

/// The bytes of `count` elements of `elem` bytes at `offset` in `view`,
/// checked, and the stride (`strided`: honour the view's byteStride).
#[allow(clippy::too_many_arguments)]
fn view_slice<'b>(
    path: &Path,
    name: &str,
    view: &View<'_>,
    buffers: &'b Buffers<'_>,
    offset: usize,
    count: usize,
    elem: usize,
    strided: bool,
) -> Result<(&'b [u8], usize), LoadError> {
    let vname = format!("bufferViews[{}]", view.index());
    let stride = if strided {
        view.stride().unwrap_or(elem)
    } else {
        elem
    };
    if stride < elem {
        return Err(LoadError::at_json(
            path,
            vname,
            format!("byteStride {stride} is smaller than the {elem}-byte elements of {name}"),
        ));
    }
    let b = view.buffer().index();
    let buf: &[u8] = buffers.get(b).map(|c| c.as_ref()).unwrap_or(&[]);
    let vend = view.offset().checked_add(view.length());
    let Some(vend) = vend.filter(|&e| e <= buf.len()) else {
        return Err(LoadError::at_json(
            path,
            vname,
            format!(
                "byteOffset {} + byteLength {} runs past the end of buffers[{b}] ({} bytes)",
                view.offset(),
                view.length(),
                buf.len()
            ),
        ));
    };
    let vdata = &buf[view.offset()..vend];
    if count == 0 {
        return Ok((&[], stride));
    }
    let need = stride
        .checked_mul(count - 1)
        .and_then(|x| x.checked_add(elem))
        .and_then(|x| x.checked_add(offset));
    match need {
        Some(need) if need <= vdata.len() => Ok((&vdata[offset..need], stride)),
        _ => Err(LoadError::at_json(
            path,
            name.to_string(),
            format!(
                "{count} elements of {elem} bytes (stride {stride}) at byteOffset {offset} \
                 do not fit in {vname} ({} bytes)",
                vdata.len()
            ),
        )),
    }
}
