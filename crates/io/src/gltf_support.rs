//! Which glTF features the loader handles, and warnings that name the ones
//! it does not (each once per file, with a count), so nothing is dropped
//! silently. A required extension the loader does not handle is an error:
//! the file cannot be read correctly without it.

use crate::error::{ErrorKind, LoadError, Location};
use ::gltf::json::material::AlphaMode;
use ::gltf::json::texture::{Info, WrappingMode};
use ::gltf::json::validation::Checked;
use ::gltf::json::Root;
use std::path::Path;

/// The extensions the loader reads.
pub(crate) const HANDLED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_mesh_quantization",
    "EXT_mesh_gpu_instancing",
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
];

/// An error for the first entry of `extensionsRequired` that is not handled.
pub(crate) fn check_required(path: &Path, root: &Root) -> Result<(), LoadError> {
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if !HANDLED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(LoadError::new(
                path,
                ErrorKind::Unsupported,
                Location::Json(format!("extensionsRequired[{i}]")),
                format!(
                    "the file requires extension {ext}, which is not supported (supported: {})",
                    HANDLED_EXTENSIONS.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// Count of `KHR_texture_transform` uses in a texture reference.
fn transformed(info: Option<&Info>) -> usize {
    info.and_then(|i| i.extensions.as_ref())
        .is_some_and(|e| e.others.contains_key("KHR_texture_transform")) as usize
}

/// One warning per unsupported feature the document uses.
pub(crate) fn unsupported_warnings(root: &Root) -> Vec<String> {
    let mut w = Vec::new();
    let mut count = |n: usize, what: &str| {
        if n > 0 {
            w.push(format!("{n} {what}"));
        }
    };
    let mats = &root.materials;
    count(
        mats.iter().filter(|m| m.normal_texture.is_some()).count(),
        "material(s) with a normal texture: not supported, ignored",
    );
    count(
        mats.iter()
            .filter(|m| m.occlusion_texture.is_some())
            .count(),
        "material(s) with an occlusion texture: not supported, ignored",
    );
    count(
        mats.iter().filter(|m| m.emissive_texture.is_some()).count(),
        "material(s) with an emissive texture: not supported, ignored (emissiveFactor used)",
    );
    count(
        mats.iter()
            .filter(|m| {
                m.pbr_metallic_roughness
                    .metallic_roughness_texture
                    .is_some()
            })
            .count(),
        "material(s) with a metallicRoughness texture: not supported, ignored (factors used)",
    );
    count(
        mats.iter()
            .filter(|m| {
                m.pbr_metallic_roughness
                    .base_color_texture
                    .as_ref()
                    .is_some_and(|i| i.tex_coord != 0)
            })
            .count(),
        "base-colour texture(s) with a texCoord set other than 0: not supported, \
         those textures are ignored",
    );
    let mut n_mask = 0;
    let mut n_blend = 0;
    for m in mats {
        match m.alpha_mode {
            Checked::Valid(AlphaMode::Mask) => n_mask += 1,
            Checked::Valid(AlphaMode::Blend) => n_blend += 1,
            _ => {}
        }
    }
    count(
        n_mask,
        "material(s) with alphaMode MASK: not supported, rendered opaque",
    );
    count(
        n_blend,
        "material(s) with alphaMode BLEND: not supported, rendered opaque",
    );
    count(
        root.samplers
            .iter()
            .filter(|s| {
                s.wrap_s != Checked::Valid(WrappingMode::Repeat)
                    || s.wrap_t != Checked::Valid(WrappingMode::Repeat)
            })
            .count(),
        "sampler(s) with clamp-to-edge or mirrored-repeat wrapping: not supported, \
         textures are sampled with repeat",
    );
    count(
        root.skins.len(),
        "skin(s): skinning is not supported, meshes are loaded in their bind pose",
    );
    count(
        root.meshes
            .iter()
            .flat_map(|m| &m.primitives)
            .filter(|p| p.targets.as_ref().is_some_and(|t| !t.is_empty()))
            .count(),
        "primitive(s) with morph targets: not supported, the base shape is loaded",
    );
    count(
        root.animations.len(),
        "animation(s): not supported, the static pose is loaded",
    );
    let n_transform: usize = mats
        .iter()
        .map(|m| {
            let p = &m.pbr_metallic_roughness;
            transformed(p.base_color_texture.as_ref())
                + transformed(p.metallic_roughness_texture.as_ref())
                + transformed(m.emissive_texture.as_ref())
        })
        .sum();
    for ext in &root.extensions_used {
        if HANDLED_EXTENSIONS.contains(&ext.as_str()) {
            continue;
        }
        if ext == "KHR_texture_transform" {
            w.push(format!(
                "extension KHR_texture_transform ({n_transform} texture reference(s)) is not \
                 supported: textures are sampled untransformed"
            ));
        } else {
            w.push(format!(
                "extension {ext} (in extensionsUsed) is not supported and is ignored"
            ));
        }
    }
    w
}
