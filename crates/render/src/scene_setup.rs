//! A scene made ready to render: its camera, lights, environment and
//! material overrides applied over the scene file's own settings, as
//! `raykit render` and the Whitted experiments take them from options.

use crate::env::{Environment, EquirectMap, DEFAULT_BOX_SCALE};
use crate::light_spec::{parse_light, parse_vec3};
use anyhow::{bail, Context, Result};
use raykit_core::glam::DVec3;
use raykit_core::raysets::standard_light;
use raykit_core::{Aabb, Camera, Light, Material, PointLight, Vec3};
use raykit_scene::Scene;

/// Camera, light, environment and material overrides of a scene.
#[derive(Clone, Debug)]
pub struct SceneOptions {
    /// Camera position (replaces the scene's camera), in the file's
    /// coordinates (`f64`: a model far from the origin is framed exactly).
    pub eye: Option<DVec3>,
    /// Point the camera looks at (default: the scene centre).
    pub target: Option<DVec3>,
    /// Up direction.
    pub up: Vec3,
    /// Vertical field of view in degrees (default: the scene camera's, else 40).
    pub fov: Option<f32>,
    /// Light specifications ([`parse_light`]); they replace the scene's lights.
    pub light: Vec<String>,
    /// What rays leaving the scene see: `sky`, `black`, `white`, `R,G,B` or
    /// an equirectangular HDR map file.
    pub env: String,
    /// Look the map up where a ray leaves a box around the scene.
    pub env_box: bool,
    /// Size of the environment box relative to the scene bounds.
    pub env_box_scale: f32,
    /// Factor on the environment map's radiance.
    pub env_intensity: f32,
    /// Rotation of the environment map about +y, degrees.
    pub env_rotate: f32,
    /// One material for every triangle ([`material_preset`]).
    pub material: Option<String>,
}

impl Default for SceneOptions {
    /// The scene's own settings under a sky gradient.
    fn default() -> Self {
        SceneOptions {
            eye: None,
            target: None,
            up: Vec3::Y,
            fov: None,
            light: Vec::new(),
            env: "sky".into(),
            env_box: false,
            env_box_scale: DEFAULT_BOX_SCALE,
            env_intensity: 1.0,
            env_rotate: 0.0,
            material: None,
        }
    }
}

/// A scene ready to render.
pub struct RenderSetup {
    /// Geometry, materials and the scene's own settings.
    pub scene: Scene,
    /// The camera after overrides.
    pub camera: Camera,
    /// The lights after overrides: the options' lights, else the scene's,
    /// else one white point light above the scene.
    pub lights: Vec<Light>,
    /// The environment.
    pub environment: Environment,
}

/// Material presets: glass, mirror, gold, white and plastic.
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
pub fn environment(args: &SceneOptions, bounds: &Aabb) -> Result<Environment> {
    if !(args.env_intensity.is_finite() && args.env_intensity >= 0.0) {
        bail!(
            "--env-intensity must be a finite number ≥ 0, got {}",
            args.env_intensity
        );
    }
    if !args.env_rotate.is_finite() {
        bail!(
            "--env-rotate must be a finite number of degrees, got {}",
            args.env_rotate
        );
    }
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
    if !(args.env_box_scale.is_finite() && args.env_box_scale >= 1.0) {
        bail!("--env-box-scale must be at least 1 (the box must contain the scene)");
    }
    let map = EquirectMap::load(std::path::Path::new(&args.env))
        .with_context(|| format!("--env {}", args.env))?
        .with_rotation_deg(args.env_rotate)
        .with_intensity(args.env_intensity);
    Ok(if args.env_box {
        Environment::env_box(map, *bounds, args.env_box_scale)
    } else {
        Environment::map(map)
    })
}

/// Apply the overrides to a loaded scene (vertex normals computed where the
/// file has none); `aspect` is width / height. `origin` is where the
/// scene's coordinates start in the file's (a far model is stored relative
/// to a point near it, [`raykit_io::load_keeping_precision`]): `--eye`,
/// `--target` and the lights' positions are given in the file's
/// coordinates and moved by it.
pub fn setup(
    mut scene: Scene,
    origin: DVec3,
    args: &SceneOptions,
    aspect: f32,
) -> Result<RenderSetup> {
    let local = |p: DVec3| (p - origin).as_vec3();
    if let Some(fov) = args.fov {
        if !(1.0..179.0).contains(&fov) {
            bail!("--fov must be between 1 and 179 degrees");
        }
    }
    if scene.mesh.normals.is_none() {
        scene.mesh.compute_vertex_normals();
    }
    if let Some(name) = &args.material {
        let m = material_preset(name)?;
        scene.mesh.materials = vec![m];
        scene.mesh.tri_material = vec![0; scene.mesh.num_triangles()];
    }
    if !args.up.is_finite() || args.up == Vec3::ZERO {
        bail!("--up must be a direction, not {}", args.up);
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
    if let Some(eye) = args.eye.map(local) {
        camera = Camera {
            eye,
            target: args.target.map(local).unwrap_or(bounds.center()),
            up: args.up,
            vfov_deg: fov,
        };
    } else if let Some(target) = args.target.map(local) {
        camera.target = target;
    }
    if camera.eye == camera.target {
        if args.eye.is_none() && args.target.is_none() && scene.camera.is_some() {
            bail!(
                "the camera of scene '{}' has its eye and target at the same point {} (in f32, \
                 a camera far from the origin can lose its direction): give --eye and --target",
                scene.name,
                camera.eye
            );
        }
        bail!(
            "the camera's eye and target are the same point {}: it looks nowhere (--eye, --target)",
            camera.eye
        );
    }
    // The same test as the render server's camera check: an up along the
    // view leaves the image's roll undefined.
    let view = (camera.target - camera.eye).normalize();
    if args.eye.is_some() && view.cross(camera.up.normalize()).length() < 1e-4 {
        bail!(
            "--up {} is parallel to the view direction {view}: the image's roll is undefined; \
             give an --up across the view",
            camera.up
        );
    }
    let mut lights = Vec::new();
    let centre = (bounds.center().as_dvec3() + origin).as_vec3();
    for spec in &args.light {
        let light = parse_light(spec, centre).with_context(|| format!("--light '{spec}'"))?;
        lights.push(light.placed(|p| local(p.as_dvec3())));
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
