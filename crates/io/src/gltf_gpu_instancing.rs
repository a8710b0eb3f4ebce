//! `EXT_mesh_gpu_instancing`: a node that draws its mesh many times, each
//! copy placed by a translation, a rotation and a scale read from
//! accessors (glTF-Transform's `instance`, gltfpack's `-mi`). The copies
//! are placed in the node's space, so each one's world transform is the
//! node's times its own. The node's children and camera are not copied.

use crate::error::LoadError;
use crate::gltf_accessor::{read_floats, Buffers};
use ::gltf::Document;
use raykit_core::glam::{DMat4, DQuat, DVec3};
use std::path::Path;

/// The extension's name.
pub(crate) const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// Where `node`'s mesh is placed: at `world` alone, or, with the
/// extension, at `world` times each copy's translation, rotation and
/// scale (in that order, as a node's own). Accessors are read as
/// [`read_floats`] reads them (`limit`: the file size); a missing or
/// out-of-range accessor, a wrong element type or copies of unequal
/// counts are errors naming the node's field.
pub(crate) fn mesh_placements(
    path: &Path,
    doc: &Document,
    buffers: &Buffers<'_>,
    limit: usize,
    node: &::gltf::Node<'_>,
    world: &DMat4,
) -> Result<Vec<DMat4>, LoadError> {
    let Some(ext) = node.extension_value(EXTENSION) else {
        return Ok(vec![*world]);
    };
    let field = format!("nodes[{}].extensions.{EXTENSION}.attributes", node.index());
    let err = |at: &str, msg: String| {
        let at = if at.is_empty() {
            field.clone()
        } else {
            format!("{field}.{at}")
        };
        LoadError::at_json(path, at, msg)
    };
    let Some(attributes) = ext.get("attributes").and_then(|a| a.as_object()) else {
        return Err(err("", "missing; expected an object of accessors".into()));
    };
    let read = |name: &str, dims: usize| -> Result<Option<Vec<f32>>, LoadError> {
        let Some(v) = attributes.get(name) else {
            return Ok(None);
        };
        let index = v
            .as_u64()
            .ok_or_else(|| err(name, format!("{v} is not an accessor index")))?;
        let acc = usize::try_from(index)
            .ok()
            .and_then(|i| doc.accessors().nth(i))
            .ok_or_else(|| {
                err(
                    name,
                    format!(
                        "accessor index {index} is out of range (the file has {} accessors)",
                        doc.accessors().len()
                    ),
                )
            })?;
        read_floats(path, &acc, buffers, dims, limit).map(Some)
    };
    let t = read("TRANSLATION", 3)?;
    let r = read("ROTATION", 4)?;
    let s = read("SCALE", 3)?;
    let counts = [
        t.as_ref().map(|v| v.len() / 3),
        r.as_ref().map(|v| v.len() / 4),
        s.as_ref().map(|v| v.len() / 3),
    ];
    let Some(n) = counts.iter().flatten().copied().next() else {
        return Err(err(
            "",
            "none of TRANSLATION, ROTATION and SCALE is given".into(),
        ));
    };
    if counts.iter().flatten().any(|&c| c != n) {
        return Err(err(
            "",
            format!(
                "the accessors have different counts (TRANSLATION, ROTATION, SCALE: {counts:?})"
            ),
        ));
    }
    (0..n)
        .map(|i| {
            let v3 = |v: &Option<Vec<f32>>, d: DVec3| {
                v.as_ref().map_or(d, |v| {
                    DVec3::new(v[3 * i].into(), v[3 * i + 1].into(), v[3 * i + 2].into())
                })
            };
            let q = r.as_ref().map_or(DQuat::IDENTITY, |v| {
                let c = |k: usize| f64::from(v[4 * i + k]);
                DQuat::from_xyzw(c(0), c(1), c(2), c(3))
            });
            // Quantized rotations are unit only to their precision.
            let len = q.length();
            if !(len.is_finite() && len > 0.5 && len < 2.0) {
                return Err(err(
                    "ROTATION",
                    format!("copy {i}: {q} is not a unit quaternion"),
                ));
            }
            let local = DMat4::from_scale_rotation_translation(
                v3(&s, DVec3::ONE),
                q / len,
                v3(&t, DVec3::ZERO),
            );
            Ok(*world * local)
        })
        .collect()
}
