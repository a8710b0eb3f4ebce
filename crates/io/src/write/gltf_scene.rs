//! The scene parts of glTF output: materials (metallic-roughness with
//! `KHR_materials_transmission` and `KHR_materials_ior`), a perspective
//! camera node and `KHR_lights_punctual` light nodes.
//!
//! Our Phong materials map onto metallic-roughness the way the loader maps
//! them back: the base colour is the diffuse colour blended towards the
//! specular colour by the reflectivity (a mirror's base colour is its
//! reflectance), the metallic factor is the reflectivity, and the roughness
//! gives a GGX lobe as wide as the Phong exponent's (`s = 2/r⁴ − 2`).
//! Light colours are written as unit-maximum colour times intensity. The
//! exact Phong colours, exponent and reflectivity also go into the
//! material's `extras.raykit_phong`, which raykit's loader prefers, so a
//! scene survives the round trip unchanged; other viewers ignore it.

use super::json::json_string;
use raykit_core::glam::{Mat3, Quat};
use raykit_core::{Aabb, Camera, Light, Material, Vec3};

/// JSON fields (`,"materials":[…],…,`) to place between `asset` and `scene`,
/// and the camera and light nodes appended to `nodes`; the camera's near
/// plane is set from the size of the scene's bounds, given with it.
/// Returns `","` when there is nothing to add.
pub(super) fn scene_extras(
    materials: &[Material],
    camera: Option<(&Camera, Aabb)>,
    lights: &[Light],
    nodes: &mut Vec<String>,
) -> String {
    let mut out = String::from(",");
    let mut used = Vec::new();
    if !materials.is_empty() {
        let ms: Vec<String> = materials.iter().map(|m| material(m, &mut used)).collect();
        out += &format!(r#""materials":[{}],"#, ms.join(","));
    }
    if let Some((c, b)) = camera {
        let (right, up, forward) = c.basis();
        let q = Quat::from_mat3(&Mat3::from_cols(right, up, -forward)).normalize();
        let znear = b.placing_length() * 1e-4;
        out += &format!(
            r#""cameras":[{{"type":"perspective","perspective":{{"yfov":{},"znear":{znear}}}}}],"#,
            c.vfov_deg.to_radians()
        );
        nodes.push(format!(
            r#"{{"name":"camera","camera":0,"translation":{},"rotation":{}}}"#,
            arr(c.eye.to_array()),
            arr(q.to_array())
        ));
    }
    if !lights.is_empty() {
        let mut defs = Vec::new();
        for (i, l) in lights.iter().enumerate() {
            let (def, translation, direction) = light(l);
            defs.push(def);
            let mut node = format!(
                r#"{{"name":"light {i}","extensions":{{"KHR_lights_punctual":{{"light":{i}}}}}"#
            );
            if let Some(p) = translation {
                node += &format!(r#","translation":{}"#, arr(p.to_array()));
            }
            if let Some(d) = direction {
                node += &format!(r#","rotation":{}"#, arr(rotation_to(d).to_array()));
            }
            node.push('}');
            nodes.push(node);
        }
        out += &format!(
            r#""extensions":{{"KHR_lights_punctual":{{"lights":[{}]}}}},"#,
            defs.join(",")
        );
        used.push("KHR_lights_punctual");
    }
    if !used.is_empty() {
        used.sort_unstable();
        used.dedup();
        let names: Vec<String> = used.iter().map(|u| format!("\"{u}\"")).collect();
        out += &format!(r#""extensionsUsed":[{}],"#, names.join(","));
    }
    out
}

fn arr<const N: usize>(a: [f32; N]) -> String {
    let parts: Vec<String> = a.iter().map(|x| format!("{x}")).collect();
    format!("[{}]", parts.join(","))
}

fn material(m: &Material, used: &mut Vec<&'static str>) -> String {
    let r = m.reflectivity.clamp(0.0, 1.0);
    let base: [f32; 3] = std::array::from_fn(|k| m.diffuse[k] + (m.specular[k] - m.diffuse[k]) * r);
    let roughness = (2.0 / (m.shininess.max(0.0) + 2.0))
        .powf(0.25)
        .clamp(0.0, 1.0);
    let emissive = m.emission.map(|e| e.clamp(0.0, 1.0));
    let mut ext = Vec::new();
    if m.transmission > 0.0 {
        ext.push(format!(
            r#""KHR_materials_transmission":{{"transmissionFactor":{}}}"#,
            m.transmission.clamp(0.0, 1.0)
        ));
        used.push("KHR_materials_transmission");
    }
    if m.ior != 1.5 {
        ext.push(format!(r#""KHR_materials_ior":{{"ior":{}}}"#, m.ior));
        used.push("KHR_materials_ior");
    }
    let ext = if ext.is_empty() {
        String::new()
    } else {
        format!(r#","extensions":{{{}}}"#, ext.join(","))
    };
    let phong = format!(
        r#","extras":{{"raykit_phong":{{"diffuse":{},"specular":{},"shininess":{},"reflectivity":{r}}}}}"#,
        arr(m.diffuse),
        arr(m.specular),
        m.shininess
    );
    format!(
        r#"{{"name":{},"pbrMetallicRoughness":{{"baseColorFactor":{},"metallicFactor":{r},"roughnessFactor":{roughness}}},"emissiveFactor":{}{ext}{phong}}}"#,
        json_string(&m.name),
        arr([base[0], base[1], base[2], 1.0]),
        arr(emissive)
    )
}

/// A colour as (unit-maximum colour, intensity).
fn colour_intensity(c: Vec3) -> (Vec3, f32) {
    let i = c.max_element().max(0.0);
    if i == 0.0 {
        (Vec3::ONE, 0.0)
    } else {
        (c / i, i)
    }
}

/// The light's JSON, node translation and the direction it shines in.
fn light(l: &Light) -> (String, Option<Vec3>, Option<Vec3>) {
    match *l {
        Light::Point(p) => {
            let (c, i) = colour_intensity(p.intensity);
            let def = format!(
                r#"{{"type":"point","color":{},"intensity":{i}}}"#,
                arr(c.to_array())
            );
            (def, Some(p.position), None)
        }
        Light::Spot {
            position,
            direction,
            intensity,
            cos_inner,
            cos_outer,
        } => {
            let (c, i) = colour_intensity(intensity);
            let def = format!(
                r#"{{"type":"spot","color":{},"intensity":{i},"spot":{{"innerConeAngle":{},"outerConeAngle":{}}}}}"#,
                arr(c.to_array()),
                cos_inner.clamp(-1.0, 1.0).acos(),
                cos_outer.clamp(-1.0, 1.0).acos()
            );
            (def, Some(position), Some(direction))
        }
        Light::Directional {
            direction,
            irradiance,
        } => {
            let (c, i) = colour_intensity(irradiance);
            let def = format!(
                r#"{{"type":"directional","color":{},"intensity":{i}}}"#,
                arr(c.to_array())
            );
            (def, None, Some(direction))
        }
    }
}

/// A rotation taking −Z (glTF's light and camera axis) to unit `d`.
fn rotation_to(d: Vec3) -> Quat {
    Quat::from_rotation_arc(-Vec3::Z, d.normalize())
}
