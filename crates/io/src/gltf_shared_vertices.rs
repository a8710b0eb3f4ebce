//! Primitives of one glTF mesh that share their vertex arrays.
//!
//! A mesh's primitives may name the same POSITION (and NORMAL and
//! TEXCOORD_0) accessors and differ only in their indices and material:
//! exporters that split a mesh by material do this, and so does raykit's
//! own writer, one primitive per run of triangles with the same material.
//! Such primitives are one set of vertices. Read once per placement and
//! counted once in the flattened size, a terrain of a million triangles in
//! 110,000 material runs over one vertex array loads as the 501,264
//! vertices it has, where a copy per primitive would be 5.5·10¹⁰.

use gltf::Semantic;

/// The accessors that make a primitive's vertices: POSITION, NORMAL and
/// TEXCOORD_0.
pub(crate) type VertexKey = (usize, Option<usize>, Option<usize>);

/// The vertex arrays of `prim`, or `None` when they are not shared with
/// another primitive's by accessor: no POSITION, or Draco-compressed
/// (`KHR_draco_mesh_compression`), whose vertices are decoded per
/// primitive.
pub(crate) fn vertex_key(prim: &gltf::Primitive<'_>) -> Option<VertexKey> {
    if prim.extension_value(crate::gltf_draco::EXTENSION).is_some() {
        return None;
    }
    let index = |s: Semantic| prim.get(&s).map(|a| a.index());
    Some((
        index(Semantic::Positions)?,
        index(Semantic::Normals),
        index(Semantic::TexCoords(0)),
    ))
}
