//! `KHR_draco_mesh_compression`: primitives whose geometry is stored as a
//! Draco bitstream (Google's Draco, as glTF-Transform's `draco`, Blender's
//! exporter and many downloads write it), decoded with the `draco-core`
//! crate into the positions, normals, texture coordinates and triangle
//! corners that the primitive's accessors describe but do not hold.
//!
//! Draco numbers the points and triangles in its own order, so triangle
//! indices differ from those of the uncompressed file; the surface is the
//! same within the encoder's quantization.

use crate::error::{ErrorKind, LoadError, Location};
use crate::gltf_image::view_bytes;
use ::gltf::Document;
use draco_core::{DataType, DecoderBuffer, FaceIndex, Mesh, MeshDecoder, PointIndex};
use std::borrow::Cow;
use std::path::Path;

/// The extension's name.
pub(crate) const EXTENSION: &str = "KHR_draco_mesh_compression";

/// Let the `gltf` crate's validator pass the accessors that the extension
/// leaves without data. Its validator refuses an accessor with neither a
/// buffer view nor sparse values, which the glTF specification allows and
/// the extension relies on: the accessors of a compressed primitive give
/// only counts and types, and the data is the extension's buffer view. Each
/// such accessor of a compressed primitive is pointed at that view; it is
/// never read, since the primitive is decoded instead.
pub(crate) fn point_placeholders_at_data(
    path: &Path,
    root: &mut ::gltf::json::Root,
) -> Result<(), LoadError> {
    use ::gltf::json::Index;
    let mut placeholders = Vec::new();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let Some(ext) = prim
                .extensions
                .as_ref()
                .and_then(|e| e.others.get(EXTENSION))
            else {
                continue;
            };
            let view = ext
                .get("bufferView")
                .and_then(|v| v.as_u64())
                .and_then(|v| u32::try_from(v).ok())
                .ok_or_else(|| {
                    LoadError::at_json(
                        path,
                        format!("meshes[{m}].primitives[{p}].extensions.{EXTENSION}.bufferView"),
                        "missing or not a buffer view index",
                    )
                })?;
            let accessors = prim
                .attributes
                .values()
                .chain(&prim.indices)
                .map(|a| a.value());
            placeholders.extend(accessors.map(|a| (a, view)));
        }
    }
    for (a, view) in placeholders {
        if let Some(acc) = root.accessors.get_mut(a) {
            if acc.buffer_view.is_none() && acc.sparse.is_none() {
                acc.buffer_view = Some(Index::new(view));
            }
        }
    }
    Ok(())
}

/// A decoded primitive: per point `POSITION` (three floats), `NORMAL`
/// and `TEXCOORD_0` where the extension maps them, and three point
/// indices per triangle.
pub(crate) struct DracoPrimitive {
    pub positions: Vec<f32>,
    pub normals: Option<Vec<f32>>,
    pub uvs: Option<Vec<f32>>,
    pub indices: Vec<u32>,
}

/// The geometry of `prim` (named `pname` in errors) when it carries the
/// extension, decoded from its buffer view; `None` when it does not.
pub(crate) fn decode_primitive(
    path: &Path,
    doc: &Document,
    buffers: &[Cow<'_, [u8]>],
    prim: &::gltf::Primitive<'_>,
    pname: &str,
) -> Result<Option<DracoPrimitive>, LoadError> {
    let Some(ext) = prim.extension_value(EXTENSION) else {
        return Ok(None);
    };
    let field = format!("{pname}.extensions.{EXTENSION}");
    let err = |at: &str, msg: String| {
        LoadError::new(
            path,
            ErrorKind::Malformed,
            Location::Json(format!("{field}{at}")),
            msg,
        )
    };
    let view = ext
        .get("bufferView")
        .and_then(|v| v.as_u64())
        .ok_or_else(|| err(".bufferView", "missing or not a buffer view index".into()))?;
    let bytes = usize::try_from(view)
        .map_err(|_| err(".bufferView", format!("{view} is out of range")))
        .and_then(|v| view_bytes(doc.as_json(), buffers, v).map_err(|m| err(".bufferView", m)))?;
    // The decoder checks its input; a panic inside it is turned into an
    // error all the same, as a last line of defence.
    let decoded = std::panic::catch_unwind(|| {
        let mut mesh = Mesh::new();
        MeshDecoder::new()
            .decode(&mut DecoderBuffer::new(bytes), &mut mesh)
            .map(|()| mesh)
    });
    let mesh = match decoded {
        Ok(Ok(mesh)) => mesh,
        Ok(Err(e)) => return Err(err("", format!("the Draco data does not decode: {e:?}"))),
        Err(_) => return Err(err("", "the Draco decoder failed on this data".into())),
    };
    let attribute = |name: &str, dims: usize| -> Result<Option<Vec<f32>>, LoadError> {
        let Some(id) = ext.get("attributes").and_then(|a| a.get(name)) else {
            return Ok(None);
        };
        let at = format!(".attributes.{name}");
        let id = id
            .as_u64()
            .and_then(|i| u32::try_from(i).ok())
            .ok_or_else(|| err(&at, format!("{id} is not a Draco attribute id")))?;
        read_floats(&mesh, id, dims)
            .map(Some)
            .map_err(|m| err(&at, m))
    };
    let Some(positions) = attribute("POSITION", 3)? else {
        return Err(err(".attributes", "no POSITION attribute".into()));
    };
    let normals = attribute("NORMAL", 3)?;
    let uvs = attribute("TEXCOORD_0", 2)?;
    let points = mesh.num_points();
    let mut indices = Vec::with_capacity(3 * mesh.num_faces());
    for f in 0..mesh.num_faces() {
        for p in mesh.face(FaceIndex(f as u32)) {
            if p.0 as usize >= points {
                return Err(err(
                    "",
                    format!(
                        "triangle {f} refers to point {}, but the data has {points}",
                        p.0
                    ),
                ));
            }
            indices.push(p.0);
        }
    }
    Ok(Some(DracoPrimitive {
        positions,
        normals,
        uvs,
        indices,
    }))
}

/// The `dims` float components of every point of the attribute with Draco
/// id `id`, or why they cannot be read.
fn read_floats(mesh: &Mesh, id: u32, dims: usize) -> Result<Vec<f32>, String> {
    let a = mesh
        .attribute_by_unique_id(id)
        .ok_or_else(|| format!("the Draco data has no attribute {id}"))?;
    if a.data_type() != DataType::Float32 || a.num_components() as usize != dims {
        return Err(format!(
            "attribute {id} decodes as {} × {:?}; expected {dims} × Float32",
            a.num_components(),
            a.data_type()
        ));
    }
    let stride = usize::try_from(a.byte_stride()).unwrap_or(0);
    let data = a.buffer().data();
    let mut out = Vec::with_capacity(mesh.num_points() * dims);
    for p in 0..mesh.num_points() {
        let at = (a.mapped_index(PointIndex(p as u32)).0 as usize).checked_mul(stride);
        let value = at
            .and_then(|at| data.get(at..at.checked_add(4 * dims)?))
            .ok_or_else(|| format!("point {p}'s value lies outside attribute {id}'s data"))?;
        out.extend(
            value
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        );
    }
    Ok(out)
}
