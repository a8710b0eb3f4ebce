//! Punctual lights: point, spot and directional, as in glTF's
//! `KHR_lights_punctual`, with Phong (1975) lighting.

use glam::Vec3;

/// A point light: position and radiant intensity in linear RGB. The
/// irradiance it gives a surface facing it at distance `d` is
/// `intensity / d²` (no other constant), which the renderers follow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position in world space.
    pub position: Vec3,
    /// Radiant intensity, linear RGB; falloff `1/d²`.
    pub intensity: Vec3,
}

impl PointLight {
    /// A light at `position` with intensity `intensity`.
    pub fn new(position: Vec3, intensity: Vec3) -> Self {
        PointLight {
            position,
            intensity,
        }
    }

    /// A light at `position` that gives irradiance `irradiance` (linear RGB)
    /// at distance `distance`, i.e. intensity `irradiance · distance²`.
    pub fn with_irradiance_at(position: Vec3, irradiance: Vec3, distance: f32) -> Self {
        PointLight::new(position, irradiance * distance * distance)
    }

    /// Irradiance at `point` on a surface facing the light (before the cosine
    /// factor and before any shadowing).
    pub fn irradiance_at(&self, point: Vec3) -> Vec3 {
        self.intensity / (self.position - point).length_squared()
    }
}

/// A punctual light of any kind.
///
/// Spot cones follow `KHR_lights_punctual`: full intensity inside the inner
/// cone angle, zero outside the outer one, and a smooth step of the cosine in
/// between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Light from a point in every direction, `intensity / d²`.
    Point(PointLight),
    /// A point light restricted to a cone around `direction`.
    Spot {
        /// Apex of the cone.
        position: Vec3,
        /// Unit direction the light shines in.
        direction: Vec3,
        /// Radiant intensity on the axis, linear RGB; falloff `1/d²`.
        intensity: Vec3,
        /// Cosine of the inner cone half-angle (full intensity inside).
        cos_inner: f32,
        /// Cosine of the outer cone half-angle (no light outside).
        cos_outer: f32,
    },
    /// Parallel light from infinitely far away, like the sun.
    Directional {
        /// Unit direction the light travels in.
        direction: Vec3,
        /// Irradiance on a surface facing the light, linear RGB.
        irradiance: Vec3,
    },
}

/// What a light gives a point: where it comes from and how much.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the point towards the light.
    pub to_light: Vec3,
    /// Distance to the light (`f32::INFINITY` for directional lights).
    pub distance: f32,
    /// Irradiance on a surface facing the light, before the cosine factor
    /// and before any shadowing.
    pub irradiance: Vec3,
}

impl From<PointLight> for Light {
    fn from(p: PointLight) -> Light {
        Light::Point(p)
    }
}

impl Light {
    /// The light with its position (a point or spot light's; a directional
    /// light has none) replaced by `place(position)`: the light moved into
    /// another frame. Direction and intensity stay.
    pub fn placed(self, place: impl Fn(Vec3) -> Vec3) -> Light {
        match self {
            Light::Point(p) => Light::Point(PointLight {
                position: place(p.position),
                ..p
            }),
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => Light::Spot {
                position: place(position),
                direction,
                intensity,
                cos_inner,
                cos_outer,
            },
            directional => directional,
        }
    }

    /// The light arriving at `point`.
    pub fn toward(&self, point: Vec3) -> LightSample {
        match *self {
            Light::Point(p) => {
                let d = p.position - point;
                let dist = d.length();
                LightSample {
                    to_light: d / dist.max(f32::MIN_POSITIVE),
                    distance: dist,
                    irradiance: p.intensity / (dist * dist).max(f32::MIN_POSITIVE),
                }
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => {
                let d = position - point;
                let dist = d.length();
                let to_light = d / dist.max(f32::MIN_POSITIVE);
                let cos = (-to_light).dot(direction);
                let cone = smooth_cone(cos, cos_inner, cos_outer);
                LightSample {
                    to_light,
                    distance: dist,
                    irradiance: intensity * cone / (dist * dist).max(f32::MIN_POSITIVE),
                }
            }
            Light::Directional {
                direction,
                irradiance,
            } => LightSample {
                to_light: -direction,
                distance: f32::INFINITY,
                irradiance,
            },
        }
    }

    /// The light's position (`None` for directional lights).
    pub fn position(&self) -> Option<Vec3> {
        match *self {
            Light::Point(p) => Some(p.position),
            Light::Spot { position, .. } => Some(position),
            Light::Directional { .. } => None,
        }
    }

    /// Short name of the kind: `point`, `spot` or `directional`.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Light::Point(_) => "point",
            Light::Spot { .. } => "spot",
            Light::Directional { .. } => "directional",
        }
    }
}

/// The `KHR_lights_punctual` spot attenuation: 1 inside the inner cone, 0
/// outside the outer one, the squared linear ramp of the cosine between.
fn smooth_cone(cos: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos >= cos_inner {
        return 1.0;
    }
    let span = (cos_inner - cos_outer).max(1e-6);
    let t = ((cos - cos_outer) / span).clamp(0.0, 1.0);
    t * t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_light_follows_inverse_square() {
        let l = Light::from(PointLight::new(Vec3::new(0.0, 4.0, 0.0), Vec3::splat(32.0)));
        let s = l.toward(Vec3::ZERO);
        assert_eq!(s.to_light, Vec3::Y);
        assert_eq!(s.distance, 4.0);
        assert_eq!(s.irradiance, Vec3::splat(2.0));
    }

    #[test]
    fn spot_cone_is_full_inside_dark_outside_and_ramps_between() {
        let (inner, outer) = (10f32.to_radians(), 20f32.to_radians());
        let l = Light::Spot {
            position: Vec3::ZERO,
            direction: -Vec3::Y,
            intensity: Vec3::ONE,
            cos_inner: inner.cos(),
            cos_outer: outer.cos(),
        };
        let at = |deg: f32| {
            let a = deg.to_radians();
            l.toward(Vec3::new(a.sin(), -a.cos(), 0.0)).irradiance.x
        };
        assert!((at(5.0) - 1.0).abs() < 1e-5);
        assert_eq!(at(25.0), 0.0);
        let mid = at(15.0) as f64;
        let t = (15f64.to_radians().cos() - 20f64.to_radians().cos())
            / (10f64.to_radians().cos() - 20f64.to_radians().cos());
        assert!((mid - t * t).abs() < 1e-4, "{mid} vs {}", t * t);
    }

    #[test]
    fn directional_light_is_the_same_everywhere() {
        let l = Light::Directional {
            direction: Vec3::new(0.0, -1.0, 0.0),
            irradiance: Vec3::splat(3.0),
        };
        for p in [Vec3::ZERO, Vec3::splat(1e6)] {
            let s = l.toward(p);
            assert_eq!((s.to_light, s.irradiance), (Vec3::Y, Vec3::splat(3.0)));
            assert!(s.distance.is_infinite());
        }
        assert_eq!(l.position(), None);
    }
}
