//! glTF 2.0 output: one scene, one node, one mesh with one triangle
//! primitive (positions, normals and texture coordinates when present, u32
//! indices). Parts and materials are not written.

use super::check;
use crate::uri::base64_encode;
use raykit_core::TriangleMesh;
use std::io::{self, Write};

/// Write `mesh` as GLB (`binary`) or as `.gltf` JSON with the buffer embedded
/// as a base64 data URI.
pub fn write_gltf(w: &mut dyn Write, mesh: &TriangleMesh, binary: bool) -> io::Result<()> {
    check(mesh)?;
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut attributes = Vec::new();
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((mesh.positions[0], mesh.positions[0]), |(l, h), &p| {
            (l.min(p), h.max(p))
        });
    let mut add = |bin: &mut Vec<u8>, data: &[f32], dims: usize, extra: String, target: u32| {
        let offset = bin.len();
        data.iter().for_each(|x| bin.extend(x.to_le_bytes()));
        let i = views.len();
        views.push(format!(
            r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{},"target":{target}}}"#,
            data.len() * 4
        ));
        let ty = ["SCALAR", "VEC2", "VEC3"][dims - 1];
        accessors.push(format!(
            r#"{{"bufferView":{i},"componentType":5126,"count":{},"type":"{ty}"{extra}}}"#,
            data.len() / dims
        ));
        i
    };
    let pos: Vec<f32> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
    let minmax = format!(
        r#","min":[{},{},{}],"max":[{},{},{}]"#,
        lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
    );
    let a = add(&mut bin, &pos, 3, minmax, 34962);
    attributes.push(format!(r#""POSITION":{a}"#));
    if let Some(n) = &mesh.normals {
        let d: Vec<f32> = n.iter().flat_map(|p| p.to_array()).collect();
        let a = add(&mut bin, &d, 3, String::new(), 34962);
        attributes.push(format!(r#""NORMAL":{a}"#));
    }
    if let Some(t) = &mesh.uvs {
        let d: Vec<f32> = t.iter().flat_map(|p| p.to_array()).collect();
        let a = add(&mut bin, &d, 2, String::new(), 34962);
        attributes.push(format!(r#""TEXCOORD_0":{a}"#));
    }
    let ioff = bin.len();
    mesh.indices
        .iter()
        .flatten()
        .for_each(|i| bin.extend(i.to_le_bytes()));
    let iv = views.len();
    views.push(format!(
        r#"{{"buffer":0,"byteOffset":{ioff},"byteLength":{},"target":34963}}"#,
        mesh.indices.len() * 12
    ));
    let ia = accessors.len();
    accessors.push(format!(
        r#"{{"bufferView":{iv},"componentType":5125,"count":{},"type":"SCALAR"}}"#,
        mesh.indices.len() * 3
    ));
    let uri = if binary {
        String::new()
    } else {
        format!(
            r#","uri":"data:application/octet-stream;base64,{}""#,
            base64_encode(&bin)
        )
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0","generator":"raykit-io"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{{}}},"indices":{ia},"mode":4}}]}}],"accessors":[{}],"bufferViews":[{}],"buffers":[{{"byteLength":{}{uri}}}]}}"#,
        attributes.join(","),
        accessors.join(","),
        views.join(","),
        bin.len()
    );
    if !binary {
        return w.write_all(json.as_bytes());
    }
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let total = u32::try_from(total)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "mesh too large for GLB"))?;
    w.write_all(b"glTF")?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&total.to_le_bytes())?;
    w.write_all(&(json.len() as u32).to_le_bytes())?;
    w.write_all(b"JSON")?;
    w.write_all(&json)?;
    w.write_all(&(bin.len() as u32).to_le_bytes())?;
    w.write_all(b"BIN\0")?;
    w.write_all(&bin)
}
