//! `--light` specifications: point, directional and spot lights
//! ([`raykit_render::light_spec`]).

use anyhow::Result;
use raykit_core::{Light, Vec3};
pub use raykit_render::light_spec::{parse_vec3, LIGHT_SPEC_HELP as LIGHT_HELP};

/// Parse one `--light` value; `centre` is the scene centre.
pub fn parse_light(spec: &str, centre: Vec3) -> Result<Light> {
    raykit_render::light_spec::parse_light_spec(spec, centre).map_err(anyhow::Error::msg)
}
