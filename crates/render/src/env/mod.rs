//! Environments: the radiance of rays that leave the scene.
//!
//! * [`Environment::Sky`]: the procedural gradient of [`crate::sky`].
//! * [`Environment::Constant`]: the same radiance from every direction
//!   (white-furnace tests).
//! * [`Environment::Map`]: classic environment mapping, an
//!   [`EquirectMap`] looked up by direction only: fast, but without
//!   parallax, as if the surroundings were infinitely far away.
//! * [`Environment::Box`]: the environment box of the Purcell-style stream tracer (Purcell et al.
//!   2002): the map is painted on the inside of an axis-aligned box
//!   larger than the scene; a ray is intersected with the box and the map is
//!   looked up in the direction from the box centre to the ray's exit point,
//!   which removes the parallax errors of direction-only lookup.
//!
//! # Equirectangular mapping
//!
//! y is up. A direction `d = (x, y, z)` (any length) maps to
//!
//! ```text
//! u = 0.5 + atan2(x, -z) / 2π        v = acos(y / |d|) / π
//! ```
//!
//! ```text
//!          u = 0      0.25      0.5       0.75       1
//!   v = 0  +---------+---------+---------+---------+   +Y (zenith): top row
//!          |         |         |         |         |
//!   v = .5 |   +Z    |   -X    |   -Z    |   +X    |   horizon
//!          |  (seam) |         | (centre)|         |
//!   v = 1  +---------+---------+---------+---------+   -Y (nadir): bottom row
//! ```
//!
//! so the image centre column looks along `-Z` (the default camera's view),
//! `u` grows towards `+X` at `u = 0.75`, and the left and right edges meet
//! behind, at `+Z`. Texel `(i, j)` (row 0 at the top) has its centre at
//! `u = (i + ½)/width`, `v = (j + ½)/height`. Lookups filter bilinearly,
//! wrapping in `u` and clamping in `v`. See [`dir_to_uv`] and [`uv_to_dir`].

mod env_box;
mod equirect;
mod error;
mod load;
mod mapping;

pub use env_box::{centered_box, exit_direction, exit_t, grounded_box, DEFAULT_BOX_SCALE};
pub use equirect::EquirectMap;
pub use error::EnvError;
pub use load::MAX_TEXELS;
pub use mapping::{dir_to_uv, uv_to_dir};

use raykit_core::glam::Vec3;
use raykit_core::Aabb;
use std::sync::Arc;

/// What a ray that leaves the scene sees. Maps are shared (`Arc`), so
/// environments are cheap to clone.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Environment {
    /// The sky gradient of [`crate::sky::sky`].
    #[default]
    Sky,
    /// The same linear radiance from every direction.
    Constant(Vec3),
    /// Classic environment mapping: the map looked up by direction only.
    Map {
        /// The map.
        map: Arc<EquirectMap>,
    },
    /// The environment box: `map` painted on the inside of `bounds`,
    /// looked up from the box centre towards each ray's exit point. Rays that
    /// start outside the box and miss it fall back to direction lookup.
    Box {
        /// The map.
        map: Arc<EquirectMap>,
        /// The box, which should enclose the scene.
        bounds: Aabb,
    },
}

impl Environment {
    /// Classic direction-only environment mapping with `map`.
    pub fn map(map: impl Into<Arc<EquirectMap>>) -> Self {
        Environment::Map { map: map.into() }
    }

    /// The environment box around `scene_bounds`: the bounds scaled
    /// about their centre by `scale` ([`DEFAULT_BOX_SCALE`] is a sensible
    /// choice), except the floor, which stays at the scene's lowest point so
    /// that the ground of the map lies under the scene rather than below it
    /// (see [`grounded_box`]; [`env_box_centered`](Self::env_box_centered)
    /// scales the floor too). Empty or non-finite bounds give
    /// [`Environment::Map`].
    pub fn env_box(map: impl Into<Arc<EquirectMap>>, scene_bounds: Aabb, scale: f32) -> Self {
        Self::boxed(map.into(), grounded_box(scene_bounds, scale))
    }

    /// [`env_box`](Self::env_box) with the box scaled about the scene centre
    /// on every axis, floor included ([`centered_box`]), for scenes that
    /// float rather than stand on the ground.
    pub fn env_box_centered(
        map: impl Into<Arc<EquirectMap>>,
        scene_bounds: Aabb,
        scale: f32,
    ) -> Self {
        Self::boxed(map.into(), centered_box(scene_bounds, scale))
    }

    fn boxed(map: Arc<EquirectMap>, bounds: Option<Aabb>) -> Self {
        match bounds {
            Some(bounds) => Environment::Box { map, bounds },
            None => Environment::Map { map },
        }
    }

    /// The linear radiance seen by a ray from `origin` along `dir` (any
    /// length) that left the scene. `origin` only matters for
    /// [`Environment::Box`]. Direction-dependent environments give black for
    /// a zero or non-finite `dir`.
    pub fn radiance(&self, origin: Vec3, dir: Vec3) -> Vec3 {
        match self {
            Environment::Sky => match dir.try_normalize() {
                Some(d) => crate::sky::sky(d),
                None => Vec3::ZERO,
            },
            Environment::Constant(c) => *c,
            Environment::Map { map } => map.lookup(dir),
            Environment::Box { map, bounds } => {
                map.lookup(exit_direction(bounds, origin, dir).unwrap_or(dir))
            }
        }
    }

    /// A one-line description for logs.
    pub fn describe(&self) -> String {
        match self {
            Environment::Sky => "sky gradient".into(),
            Environment::Constant(c) => {
                format!("constant radiance ({}, {}, {})", c.x, c.y, c.z)
            }
            Environment::Map { map } => {
                format!("environment map {} by direction", describe_map(map))
            }
            Environment::Box { map, bounds } => format!(
                "environment box (the map seen with parallax, as in paper 001) from ({}, {}, {}) to ({}, {}, {}) with map {}",
                bounds.min.x,
                bounds.min.y,
                bounds.min.z,
                bounds.max.x,
                bounds.max.y,
                bounds.max.z,
                describe_map(map)
            ),
        }
    }
}

fn describe_map(map: &EquirectMap) -> String {
    let mut s = format!(
        "{} ({}x{}, rotation {}°, intensity {}",
        map.source(),
        map.width(),
        map.height(),
        map.rotation_deg(),
        map.intensity()
    );
    if map.clamped_texels() > 0 {
        s += &format!(", {} bad texels set to 0", map.clamped_texels());
    }
    s + ")"
}
