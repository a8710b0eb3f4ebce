//! glTF node transforms in `f64`, read from the JSON text.
//!
//! The `gltf` crate parses a node's `matrix`, `translation`, `rotation` and
//! `scale` into `f32`. Geospatial exporters place a model by its root
//! node's translation, at a UTM northing or a geocentric position, where
//! `f32` is half a metre apart or coarser: the model loses its place and,
//! once its vertices are moved there, its shape. The loaders compose node
//! transforms from the `f64` values of the file instead, and round to `f32`
//! once, after taking off the far origin ([`crate::far_origin`]).

use ::gltf::Document;
use raykit_core::glam::{DMat4, DQuat, DVec3};
use serde::Deserialize;

/// The fields of a node that place it; everything else in the file is
/// skipped unread.
#[derive(Deserialize)]
struct NodeFields {
    matrix: Option<[f64; 16]>,
    translation: Option<[f64; 3]>,
    rotation: Option<[f64; 4]>,
    scale: Option<[f64; 3]>,
}

#[derive(Deserialize)]
struct Nodes {
    #[serde(default)]
    nodes: Vec<NodeFields>,
}

/// Each node's own transform (not its parents'), in `doc`'s node order, from
/// the JSON text `json` that `doc` was parsed from: `matrix` as written
/// (column-major), else translation × rotation × scale, the rotation's
/// quaternion used as given (as the `gltf` crate uses it). A text these
/// fields cannot be read from in `f64` (the `gltf` crate accepted it, so
/// this does not arise in valid files) gives the crate's `f32` transforms.
pub(crate) fn local_transforms(doc: &Document, json: &[u8]) -> Vec<DMat4> {
    let from_doc = || -> Vec<DMat4> {
        doc.nodes()
            .map(|n| {
                let m = n.transform().matrix();
                DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from)))
            })
            .collect()
    };
    let Ok(parsed) = serde_json::from_slice::<Nodes>(json) else {
        return from_doc();
    };
    if parsed.nodes.len() != doc.nodes().len() {
        return from_doc();
    }
    parsed
        .nodes
        .iter()
        .map(|n| match n.matrix {
            Some(m) => DMat4::from_cols_array(&m),
            None => {
                let t = n.translation.map_or(DVec3::ZERO, DVec3::from_array);
                let r = n.rotation.map_or(DQuat::IDENTITY, DQuat::from_array);
                let s = n.scale.map_or(DVec3::ONE, DVec3::from_array);
                DMat4::from_translation(t) * DMat4::from_quat(r) * DMat4::from_scale(s)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(json: &str) -> Document {
        Document::from_json(::gltf::json::Root::from_slice(json.as_bytes()).unwrap()).unwrap()
    }

    /// A translation at UTM coordinates keeps its digits, and a node's TRS
    /// and matrix agree with the `gltf` crate's to its `f32` precision.
    #[test]
    fn node_transforms_keep_the_file_digits() {
        let json = r#"{"asset":{"version":"2.0"},"nodes":[
            {"translation":[429252.123,5150885.456,312.789]},
            {"rotation":[0.2,0.3,0.4,0.8426149773176359],"scale":[2,3,4],"translation":[1,2,3]},
            {"matrix":[1,0,0,0, 0,1,0,0, 0,0,1,0, 500000.25,4649776.75,0.5,1]},
            {}]}"#;
        let d = doc(json);
        let locals = local_transforms(&d, json.as_bytes());
        assert_eq!(locals.len(), 4);
        let t = locals[0].w_axis.truncate();
        assert_eq!(t, DVec3::new(429252.123, 5150885.456, 312.789));
        assert_eq!(
            locals[2].w_axis.truncate(),
            DVec3::new(500000.25, 4649776.75, 0.5)
        );
        assert_eq!(locals[3], DMat4::IDENTITY);
        for (n, local) in d.nodes().zip(&locals) {
            let crate_m = n.transform().matrix();
            let ours = local.to_cols_array_2d();
            for c in 0..4 {
                for r in 0..4 {
                    let (a, b) = (f64::from(crate_m[c][r]), ours[c][r]);
                    assert!(
                        (a - b).abs() <= 1e-6 * b.abs().max(1.0),
                        "node {} [{c}][{r}]: {a} vs {b}",
                        n.index()
                    );
                }
            }
        }
        // The crate's f32 translation has lost the millimetres at this northing.
        let crate_t = d.nodes().next().unwrap().transform().matrix()[3];
        assert_ne!(f64::from(crate_t[1]), 5150885.456);
    }
}
