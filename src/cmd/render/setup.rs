//! What `raykit render` and `raykit experiment whitted` render: the scene,
//! its camera, lights, environment and material overrides, from the
//! command line over the scene file's own settings.

use super::lights_arg::{parse_light, parse_vec3, LIGHT_HELP};
use crate::scene_arg;
use anyhow::{bail, Context, Result};
use clap::Args;
use raykit_core::raysets::standard_light;
use raykit_core::{Camera, Light, Material, PointLight, Vec3};
use raykit_render::env::Environment;
use raykit_scene::Scene;

/// Scene, camera, light, environment and material options.
#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// Scene: builtin:NAME[:key=value,...] (`raykit info scenes`) or a mesh or
    /// glTF/GLB file (a glTF file's camera and lights are used unless
    /// overridden).
    #[arg(long, default_value = "builtin:whitted")]
    pub scene: String,
    /// Camera position x,y,z (replaces the scene's camera).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<Vec3>,
    /// Point the camera looks at, x,y,z (default: the scene centre).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<Vec3>,
    /// Up direction x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,1,0")]
    pub up: Vec3,
    /// Vertical field of view in degrees (default: the scene camera's, else 40).
    #[arg(long)]
    pub fov: Option<f32>,
    #[arg(long, value_name = "SPEC", allow_hyphen_values = true, help = LIGHT_HELP)]
    pub light: Vec<String>,
    /// What rays leaving the scene see: `sky` (a gradient), `black`, `white`,
    /// `R,G,B` (uniform), or an equirectangular HDR map (`.exr`, `.hdr`).
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

/// A scene ready to render.
pub struct RenderSetup {
    /// Geometry, materials and the scene's own settings.
    pub scene: Scene,
    /// The camera after overrides.
    pub camera: Camera,
    /// The lights after overrides: `--light`, else the scene's, else one
    /// white point light above the scene.
    pub lights: Vec<Light>,
    /// The environment.
    pub environment: Environment,
}

/// Material presets of `--material`.
pub fn material_preset(name: &str) -> Result<Material> {
    let base = Material {
        name: name.to_string(),
        ..Material::default()
    };
    Ok(match name {
        "glass" => Material {
            diffuse: [1.0; 3],
            specular: [1.0; 3],
            shininess: 512.0,
            transmission: 1.0,
            ior: 1.5,
            ..base
        },
        "mirror" => Material {
            diffuse: [0.0; 3],
            specular: [0.95; 3],
            shininess: 512.0,
            reflectivity: 1.0,
            ..base
        },
        "gold" => Material {
            diffuse: [0.0; 3],
            specular: [1.0, 0.78, 0.34],
            shininess: 256.0,
            reflectivity: 1.0,
            ..base
        },
        "white" => Material {
            diffuse: [0.8; 3],
            specular: [0.0; 3],
            ..base
        },
        "plastic" => Material {
            diffuse: [0.7, 0.12, 0.08],
            specular: [0.5; 3],
            shininess: 96.0,
            reflectivity: 0.08,
            ..base
        },
        _ => bail!("unknown material '{name}': expected glass, mirror, gold, white or plastic"),
    })
}

/// The environment named by `spec` around a scene with bounds `bounds`.
pub fn environment(args: &SceneArgs, bounds: &raykit_core::Aabb) -> Result<Environment> {
    let uniform = match args.env.as_str() {
        "sky" => return Ok(Environment::Sky),
        "black" => Some(Vec3::ZERO),
        "white" => Some(Vec3::ONE),
        s if s.contains(',') && !std::path::Path::new(s).exists() => {
            Some(parse_vec3(s).map_err(anyhow::Error::msg).context("--env")?)
        }
        _ => None,
    };
    if let Some(c) = uniform {
        return Ok(Environment::Constant(c * args.env_intensity));
    }
    if !(args.env_intensity.is_finite() && args.env_intensity >= 0.0) {
        bail!("--env-intensity must be a finite number ≥ 0");
    }
    if !(args.env_box_scale.is_finite() && args.env_box_scale >= 1.0) {
        bail!("--env-box-scale must be at least 1 (the box must contain the scene)");
    }
    let map = raykit_render::env::EquirectMap::load(std::path::Path::new(&args.env))
        .with_context(|| format!("--env {}", args.env))?
        .with_rotation_deg(args.env_rotate)
        .with_intensity(args.env_intensity);
    Ok(if args.env_box {
        Environment::env_box(map, *bounds, args.env_box_scale)
    } else {
        Environment::map(map)
    })
}

/// Load the scene and apply the overrides; `aspect` is width / height.
pub fn setup(args: &SceneArgs, aspect: f32) -> Result<RenderSetup> {
    if let Some(fov) = args.fov {
        if !(1.0..179.0).contains(&fov) {
            bail!("--fov must be between 1 and 179 degrees");
        }
    }
    let mut scene = scene_arg::load(&args.scene)?;
    if scene.mesh.normals.is_none() {
        scene.mesh.compute_vertex_normals();
    }
    if let Some(name) = &args.material {
        let m = material_preset(name)?;
        scene.mesh.materials = vec![m];
        scene.mesh.tri_material = vec![0; scene.mesh.num_triangles()];
    }
    let bounds = scene.mesh.bounds();
    let fov = args
        .fov
        .or(scene.camera.map(|c| c.vfov_deg))
        .unwrap_or(40.0);
    let mut camera = match scene.camera {
        Some(c) => Camera { vfov_deg: fov, ..c },
        None => Camera::fit_points(&bounds, &scene.mesh.positions, fov, aspect),
    };
    if let Some(eye) = args.eye {
        camera = Camera {
            eye,
            target: args.target.unwrap_or(bounds.center()),
            up: args.up,
            vfov_deg: fov,
        };
    } else if let Some(target) = args.target {
        camera.target = target;
    }
    let mut lights = Vec::new();
    for spec in &args.light {
        lights
            .push(parse_light(spec, bounds.center()).with_context(|| format!("--light '{spec}'"))?);
    }
    if lights.is_empty() {
        lights = scene.lights.clone();
    }
    let environment = environment(args, &bounds)?;
    if lights.is_empty() {
        let p = standard_light(&bounds);
        lights
            .push(PointLight::with_irradiance_at(p, Vec3::ONE, p.distance(bounds.center())).into());
    }
    Ok(RenderSetup {
        scene,
        camera,
        lights,
        environment,
    })
}
