//! Direct lighting: Phong's model with Blinn's half vector, as the stack kd-tree GPU tracer
//! shades its hits and the Purcell-style stream tracer's lighting kernel does.
//!
//! For a surface with diffuse colour `kd` (texture applied), specular colour
//! `ks`, exponent `s`, shading normal `n` and unit direction to the viewer `v`:
//!
//! ```text
//! L = kd · ambient + Σ_lights  V · E · (kd · (n·l) + ks · (n·h)^s)
//! ```
//!
//! over the lights with `n·l > 0` and `n_g·l > 0` (the light is in front of
//! the triangle), where `l` is the unit direction to the light, `E` the
//! irradiance it gives ([`Light::toward`]), `h = normalize(l + v)` and `V` in
//! `[0, 1]` the light's visibility: 1 or 0 from a shadow ray, a fraction from
//! a filtered shadow map.

use crate::surface::Surface;
use raykit_core::glam::Vec3;
use raykit_core::{Light, LightSample};

/// Blinn-Phong radiance leaving `s` towards the viewer in unit direction
/// `view`, lit by `lights` and `ambient`; `visibility(i, sample)` says how
/// much of light `i` reaches the point (it is only asked for lights in front
/// of the surface).
pub fn blinn_phong(
    s: &Surface,
    view: Vec3,
    lights: &[Light],
    ambient: Vec3,
    visibility: &mut dyn FnMut(usize, &LightSample) -> f32,
) -> Vec3 {
    let m = s.material;
    let (kd, ks) = (s.diffuse, Vec3::from(m.specular));
    let mut out = kd * ambient;
    for (i, light) in lights.iter().enumerate() {
        let ls = light.toward(s.point);
        let l = ls.to_light;
        let ndl = s.shading_normal.dot(l);
        if ndl <= 0.0 || s.geometric_normal.dot(l) <= 0.0 || ls.irradiance == Vec3::ZERO {
            continue;
        }
        let vis = visibility(i, &ls);
        if vis <= 0.0 {
            continue;
        }
        let h = (l + view).normalize_or_zero();
        let spec = s.shading_normal.dot(h).max(0.0).powf(m.shininess);
        out += vis * ls.irradiance * (kd * ndl + ks * spec);
    }
    out
}
