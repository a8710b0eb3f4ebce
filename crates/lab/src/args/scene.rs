//! What `raykit render` and `raykit experiment whitted` render: the scene,
//! its camera, lights, environment and material overrides, from the
//! command line over the scene file's own settings.

use super::scene_arg;
use anyhow::Result;
use clap::Args;
use raykit_core::glam::DVec3;
use raykit_core::Vec3;
use raykit_render::light_spec::{parse_dvec3, parse_vec3, LIGHT_HELP};
use raykit_render::scene_setup::SceneOptions;
pub use raykit_render::scene_setup::{material_preset, RenderSetup};

/// Scene, camera, light, environment and material options.
#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// Scene: builtin:NAME[:key=value,...] (`raykit info scenes`) or a mesh or
    /// glTF/GLB file (a glTF file's camera and lights are used unless
    /// overridden).
    #[arg(long, default_value = "builtin:whitted")]
    pub scene: String,
    /// Camera position x,y,z (replaces the scene's camera), in the file's
    /// coordinates, read in f64.
    #[arg(long, value_parser = parse_dvec3, allow_hyphen_values = true)]
    pub eye: Option<DVec3>,
    /// Point the camera looks at, x,y,z (default: the scene centre).
    #[arg(long, value_parser = parse_dvec3, allow_hyphen_values = true)]
    pub target: Option<DVec3>,
    /// Up direction x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,1,0")]
    pub up: Vec3,
    /// Vertical field of view in degrees (default: the scene camera's, else 40).
    #[arg(long)]
    pub fov: Option<f32>,
    /// Light specifications (the help text is [`LIGHT_HELP`]).
    #[arg(long, value_name = "SPEC", allow_hyphen_values = true, help = LIGHT_HELP)]
    pub light: Vec<String>,
    /// What rays leaving the scene see: `sky` (a gradient), `black`, `white`,
    /// `R,G,B` (uniform), or an equirectangular HDR map (`.exr`, `.hdr`; up to 16384 × 16384 texels).
    #[arg(long, default_value = "sky")]
    pub env: String,
    /// The environment box: look the map up where a ray leaves a box
    /// around the scene (reflections get parallax) instead of by direction.
    #[arg(long)]
    pub env_box: bool,
    /// Size of the environment box relative to the scene bounds.
    #[arg(long, default_value_t = raykit_render::env::DEFAULT_BOX_SCALE)]
    pub env_box_scale: f32,
    /// Factor on the environment map's radiance.
    #[arg(long, default_value_t = 1.0)]
    pub env_intensity: f32,
    /// Rotation of the environment map about +y, degrees.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub env_rotate: f32,
    /// Give every triangle one material: glass, mirror, gold, white or plastic.
    #[arg(long)]
    pub material: Option<String>,
}

impl SceneArgs {
    /// `scene` with the overrides `options`.
    pub fn new(scene: String, options: SceneOptions) -> Self {
        SceneArgs {
            scene,
            eye: options.eye,
            target: options.target,
            up: options.up,
            fov: options.fov,
            light: options.light,
            env: options.env,
            env_box: options.env_box,
            env_box_scale: options.env_box_scale,
            env_intensity: options.env_intensity,
            env_rotate: options.env_rotate,
            material: options.material,
        }
    }

    /// The overrides, apart from the scene itself.
    pub fn options(&self) -> SceneOptions {
        SceneOptions {
            eye: self.eye,
            target: self.target,
            up: self.up,
            fov: self.fov,
            light: self.light.clone(),
            env: self.env.clone(),
            env_box: self.env_box,
            env_box_scale: self.env_box_scale,
            env_intensity: self.env_intensity,
            env_rotate: self.env_rotate,
            material: self.material.clone(),
        }
    }
}

/// Load the scene and apply the overrides; `aspect` is width / height.
pub fn setup(args: &SceneArgs, aspect: f32) -> Result<RenderSetup> {
    let options = args.options();
    if let Some(fov) = options.fov {
        if !(1.0..179.0).contains(&fov) {
            anyhow::bail!("--fov must be between 1 and 179 degrees");
        }
    }
    let (scene, origin) = scene_arg::load_keeping_precision(&args.scene)?;
    raykit_render::scene_setup::setup(scene, origin, &options, aspect)
}
