//! glTF cameras and `KHR_lights_punctual` lights, placed by the world
//! transform of the node that carries them.
//!
//! * Lights: a point or spot light sits at the node's world origin; spot and
//!   directional lights shine along the node's world -Z (normalised). The
//!   light's `color × intensity` is used directly as [`Light`] intensity
//!   (point, spot) or irradiance (directional): the physical units of the
//!   extension (candela, lux) are **not** converted; the renderer's exposure
//!   setting scales the result. Spot cones come from `innerConeAngle` and
//!   `outerConeAngle` (defaults 0 and π/4). `range` is ignored with a warning.
//! * Camera: the first node in traversal order with a perspective camera
//!   gives `eye` = world origin, `target = eye + world -Z`, `up` = world +Y
//!   and the vertical field of view `yfov` in degrees. Orthographic cameras
//!   are skipped with a warning; when there are several perspective cameras
//!   a warning says the first is used.

use crate::error::LoadError;
use ::gltf::json::camera::Type as CameraType;
use ::gltf::json::extensions::scene::khr_lights_punctual::{Light as JsonLight, Type as LightType};
use ::gltf::json::validation::Checked;
use ::gltf::json::Root;
use raykit_core::glam::Mat4;
use raykit_core::{Camera, Light, PointLight, Vec3};
use std::path::Path;

/// The lights of a document's root extension (empty when it has none).
fn json_lights(root: &Root) -> &[JsonLight] {
    root.extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map_or(&[], |l| l.lights.as_slice())
}

/// Check the camera and light indices of every node before the `gltf`
/// crate's validation, for errors that name the field and the valid range.
pub(crate) fn check_scene_indices(path: &Path, root: &Root) -> Result<(), LoadError> {
    let n_lights = json_lights(root).len();
    for (i, node) in root.nodes.iter().enumerate() {
        if let Some(c) = node.camera {
            if c.value() >= root.cameras.len() {
                return Err(LoadError::at_json(
                    path,
                    format!("nodes[{i}].camera"),
                    format!(
                        "camera index {} is out of range (the file has {} cameras)",
                        c.value(),
                        root.cameras.len()
                    ),
                ));
            }
        }
        let light = node
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref());
        if let Some(l) = light {
            if l.light.value() >= n_lights {
                return Err(LoadError::at_json(
                    path,
                    format!("nodes[{i}].extensions.KHR_lights_punctual.light"),
                    format!(
                        "light index {} is out of range (the file has {n_lights} lights in \
                         extensions.KHR_lights_punctual.lights)",
                        l.light.value()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Collects lights and the camera while the node tree is walked.
#[derive(Default)]
pub(crate) struct SceneCollector {
    /// Lights found so far, in traversal order.
    pub lights: Vec<Light>,
    /// The first perspective camera.
    pub camera: Option<Camera>,
    perspective: usize,
    orthographic: usize,
    ranged: usize,
    bad_cones: usize,
    degenerate: Vec<String>,
}

impl SceneCollector {
    /// Take the camera and light of node `index` (JSON level, indices already
    /// checked) placed by its world transform `world`.
    pub(crate) fn visit(&mut self, root: &Root, index: usize, world: &Mat4) {
        let Some(node) = root.nodes.get(index) else {
            return;
        };
        let origin = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        let placed = origin.is_finite() && forward != Vec3::ZERO && forward.is_finite();
        if let Some(c) = node.camera.and_then(|c| root.cameras.get(c.value())) {
            match (&c.type_, &c.perspective) {
                (Checked::Valid(CameraType::Perspective), Some(p)) => {
                    self.perspective += 1;
                    if self.camera.is_none() {
                        let fov_ok = p.yfov > 0.0 && p.yfov < std::f32::consts::PI;
                        if placed && up != Vec3::ZERO && fov_ok {
                            self.camera = Some(Camera {
                                eye: origin,
                                target: origin + forward,
                                up,
                                vfov_deg: p.yfov.to_degrees(),
                            });
                        } else {
                            self.degenerate.push(format!(
                                "nodes[{index}]: camera skipped (degenerate transform, or yfov not between 0 and π)"
                            ));
                        }
                    }
                }
                _ => self.orthographic += 1,
            }
        }
        let light_index = node
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map(|l| l.light.value());
        if let Some(l) = light_index.and_then(|i| json_lights(root).get(i)) {
            if !placed {
                self.degenerate.push(format!(
                    "nodes[{index}]: light skipped (degenerate transform)"
                ));
                return;
            }
            match self.convert(l, origin, forward) {
                Some(light) => self.lights.push(light),
                None => self.degenerate.push(format!(
                    "nodes[{index}]: light skipped (colour × intensity negative or not finite)"
                )),
            }
        }
    }

    fn convert(&mut self, l: &JsonLight, position: Vec3, direction: Vec3) -> Option<Light> {
        if l.range.is_some() {
            self.ranged += 1;
        }
        let power = Vec3::from_array(l.color) * l.intensity;
        if !power.is_finite() || power.min_element() < 0.0 {
            return None;
        }
        Some(match l.type_ {
            Checked::Valid(LightType::Point) => Light::Point(PointLight::new(position, power)),
            Checked::Valid(LightType::Directional) => Light::Directional {
                direction,
                irradiance: power,
            },
            Checked::Valid(LightType::Spot) => {
                let (inner, outer) = l
                    .spot
                    .as_ref()
                    .map_or((0.0, std::f32::consts::FRAC_PI_4), |s| {
                        (s.inner_cone_angle, s.outer_cone_angle)
                    });
                let half_pi = std::f32::consts::FRAC_PI_2;
                let ok = (0.0..half_pi).contains(&inner) && inner < outer && outer <= half_pi;
                let (inner, outer) = if ok {
                    (inner, outer)
                } else {
                    self.bad_cones += 1;
                    let outer = if outer.is_finite() {
                        outer.clamp(1e-3, half_pi)
                    } else {
                        std::f32::consts::FRAC_PI_4
                    };
                    let inner = if inner.is_finite() { inner } else { 0.0 };
                    (inner.clamp(0.0, outer), outer)
                };
                Light::Spot {
                    position,
                    direction,
                    intensity: power,
                    cos_inner: inner.cos(),
                    cos_outer: outer.cos(),
                }
            }
            Checked::Invalid => return None,
        })
    }

    /// Warnings about what was skipped or ignored, once each.
    pub(crate) fn warnings(&self) -> Vec<String> {
        let mut w = self.degenerate.clone();
        if self.orthographic > 0 {
            w.push(format!(
                "{} orthographic camera node(s) skipped: only perspective cameras are supported",
                self.orthographic
            ));
        }
        if self.perspective > 1 && self.camera.is_some() {
            w.push(format!(
                "{} perspective camera nodes: the first in traversal order is used",
                self.perspective
            ));
        }
        if self.ranged > 0 {
            w.push(format!(
                "KHR_lights_punctual range ignored on {} light(s): lights fall off as 1/d² \
                 without a cutoff",
                self.ranged
            ));
        }
        if self.bad_cones > 0 {
            w.push(format!(
                "{} spot light(s) with cone angles outside 0 <= inner < outer <= π/2: clamped",
                self.bad_cones
            ));
        }
        w
    }
}
