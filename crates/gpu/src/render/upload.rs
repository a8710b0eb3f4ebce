//! The shading data of the GPU Whitted renderer (papers 000 and 001): the
//! per-triangle corners, vertex normals and material index, the material
//! and light tables and the frame's parameters, uploaded as bind group 1 of
//! both organisations (`shaders/render/shade_data.wgsl`), with the ray
//! counters, the radiance accumulator and the environment map.

use crate::buffers::{output, storage, uniform};
use crate::context::GpuContext;
use crate::error::{GpuError, GpuResult};
use raykit_core::glam::Vec3;
use raykit_core::{Camera, Light, Material, TriangleMesh};
use raykit_render::env::Environment;
use raykit_render::shadow_bias;

/// Words per triangle in the shading buffer.
pub const TRI_WORDS: usize = 20;

/// Uniform block `ShadeParams` of `shade_data.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadeParams {
    eye: [f32; 3],
    width: u32,
    forward: [f32; 3],
    height: u32,
    right: [f32; 3],
    num_lights: u32,
    up: [f32; 3],
    max_depth: u32,
    ambient: [f32; 3],
    bias: f32,
    env_color: [f32; 3],
    env_kind: u32,
    has_normals: u32,
    shadows: u32,
    lights_offset: u32,
    shadow_scale: f32,
    map_width: u32,
    map_height: u32,
    map_turn: f32,
    map_intensity: f32,
    box_min: [f32; 3],
    _pad0: u32,
    box_max: [f32; 3],
    _pad1: u32,
    box_center: [f32; 3],
    _pad2: u32,
}

/// What the shading reads about the scene, independent of the camera.
pub struct ShadeScene<'a> {
    /// Geometry with materials.
    pub mesh: &'a TriangleMesh,
    /// Lights.
    pub lights: &'a [Light],
    /// What rays leaving the scene see.
    pub environment: &'a Environment,
}

/// Frame settings the shading parameters hold.
pub struct FrameSettings {
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// Longest path in rays.
    pub max_depth: u32,
    /// Ambient radiance.
    pub ambient: Vec3,
    /// Shadow rays on or off.
    pub shadows: bool,
}

/// Bind group 1's buffers.
pub struct ShadeBuffers {
    /// Per-triangle records.
    pub tris: wgpu::Buffer,
    /// Materials then lights.
    pub tables: wgpu::Buffer,
    /// `ShadeParams`.
    pub params: wgpu::Buffer,
    /// Ray counters (4 words).
    pub counters: wgpu::Buffer,
    /// Radiance sums (3 words per pixel).
    pub radiance: wgpu::Buffer,
    /// The environment map's texels.
    pub env_texels: wgpu::Buffer,
}

impl ShadeBuffers {
    /// The six buffers in binding order.
    pub fn all(&self) -> [&wgpu::Buffer; 6] {
        [
            &self.tris,
            &self.tables,
            &self.params,
            &self.counters,
            &self.radiance,
            &self.env_texels,
        ]
    }
}

/// The environment as the shaders read it: kind (0 sky, 1 constant, 2 map
/// by direction, 3 paper 001's environment box), colour, map and box.
#[derive(Default)]
struct EnvUpload {
    kind: u32,
    color: Vec3,
    map: Option<(u32, u32, f32, f32)>,
    texels: Vec<u32>,
    bounds: Option<raykit_core::Aabb>,
}

fn environment_upload(env: &Environment) -> EnvUpload {
    let with_map = |kind, map: &raykit_render::env::EquirectMap| {
        // EquirectMap::with_rotation_deg's turn, from the same inputs.
        let turn = (map.rotation_deg() / 360.0).rem_euclid(1.0);
        EnvUpload {
            kind,
            map: Some((
                map.width() as u32,
                map.height() as u32,
                turn,
                map.intensity(),
            )),
            texels: map.texels().iter().flatten().map(|x| x.to_bits()).collect(),
            ..EnvUpload::default()
        }
    };
    match env {
        Environment::Sky => EnvUpload::default(),
        Environment::Constant(c) => EnvUpload {
            kind: 1,
            color: *c,
            ..EnvUpload::default()
        },
        Environment::Map { map } => with_map(2, map),
        Environment::Box { map, bounds } => EnvUpload {
            bounds: Some(*bounds),
            ..with_map(3, map)
        },
    }
}

/// Refuse what the GPU shading cannot do yet: textured materials.
pub fn check_scene(scene: &ShadeScene) -> GpuResult<()> {
    if let Some(m) = scene
        .mesh
        .materials
        .iter()
        .find(|m| m.base_texture.is_some())
    {
        return Err(GpuError::Unsupported(format!(
            "textures (material '{}' has a base-colour texture); use --backend cpu",
            m.name
        )));
    }
    Ok(())
}

fn push3(out: &mut Vec<u32>, v: [f32; 3]) {
    out.extend(v.map(f32::to_bits));
}

fn material_record(m: &Material, out: &mut Vec<u32>) {
    push3(out, m.diffuse);
    out.push(m.shininess.to_bits());
    push3(out, m.specular);
    out.push(m.reflectivity.clamp(0.0, 1.0).to_bits());
    push3(out, m.emission);
    out.push(m.transmission.clamp(0.0, 1.0).to_bits());
    out.push(m.ior.to_bits());
    out.extend([0; 3]);
}

fn light_record(l: &Light, out: &mut Vec<u32>) {
    let z = [0.0; 3];
    let (kind, pos, dir, e, inner, outer) = match *l {
        Light::Point(p) => (
            0,
            p.position.to_array(),
            z,
            p.intensity.to_array(),
            0.0,
            0.0,
        ),
        Light::Spot {
            position,
            direction,
            intensity,
            cos_inner,
            cos_outer,
        } => (
            1,
            position.to_array(),
            direction.to_array(),
            intensity.to_array(),
            cos_inner,
            cos_outer,
        ),
        Light::Directional {
            direction,
            irradiance,
        } => (2, z, direction.to_array(), irradiance.to_array(), 0.0, 0.0),
    };
    out.push(kind);
    push3(out, pos);
    push3(out, dir);
    push3(out, e);
    out.extend([inner, outer, (inner - outer).max(1e-6)].map(f32::to_bits));
    out.extend([0; 3]);
}

/// Per-triangle corners, vertex normals (zero without normals) and
/// material index (meshes without that material get the default one,
/// appended after the mesh's own, as `Surface::at` falls back).
fn triangle_records(mesh: &TriangleMesh) -> Vec<u32> {
    let fallback = mesh.materials.len() as u32;
    let mut out = Vec::with_capacity(mesh.num_triangles() * TRI_WORDS);
    for i in 0..mesh.num_triangles() {
        for p in mesh.triangle(i) {
            push3(&mut out, p.to_array());
        }
        for k in mesh.indices[i] {
            let n = mesh.normals.as_ref().map_or(Vec3::ZERO, |n| n[k as usize]);
            push3(&mut out, n.to_array());
        }
        let m = mesh.material_of(i);
        out.push(if (m as usize) < mesh.materials.len() {
            m
        } else {
            fallback
        });
        out.push(0);
    }
    out
}

impl ShadeBuffers {
    /// Upload `scene` for frames of `settings` seen through `camera`.
    pub fn upload(
        ctx: &GpuContext,
        scene: &ShadeScene,
        camera: &Camera,
        settings: &FrameSettings,
    ) -> GpuResult<ShadeBuffers> {
        check_scene(scene)?;
        let env = environment_upload(scene.environment);
        let (map_width, map_height, map_turn, map_intensity) = env.map.unwrap_or_default();
        let bounds = env
            .bounds
            .unwrap_or(raykit_core::Aabb::new(Vec3::ZERO, Vec3::ZERO));
        let mesh = scene.mesh;
        let mut tables = Vec::new();
        for m in &mesh.materials {
            material_record(m, &mut tables);
        }
        material_record(&Material::default(), &mut tables);
        let lights_offset = tables.len() as u32;
        for l in scene.lights {
            light_record(l, &mut tables);
        }
        // Camera::rays' frame, computed the same way.
        let (right, up, forward) = camera.basis();
        let h = (camera.vfov_deg.to_radians() * 0.5).tan();
        let aspect = settings.width as f32 / settings.height.max(1) as f32;
        let params = ShadeParams {
            eye: camera.eye.to_array(),
            width: settings.width,
            forward: forward.to_array(),
            height: settings.height,
            right: (right * h * aspect).to_array(),
            num_lights: scene.lights.len() as u32,
            up: (up * h).to_array(),
            max_depth: settings.max_depth.max(1),
            ambient: settings.ambient.to_array(),
            bias: shadow_bias(mesh),
            env_color: env.color.to_array(),
            env_kind: env.kind,
            has_normals: mesh.normals.is_some() as u32,
            shadows: settings.shadows as u32,
            lights_offset,
            shadow_scale: 1.0 - 1e-4,
            map_width,
            map_height,
            map_turn,
            map_intensity,
            box_min: bounds.min.to_array(),
            _pad0: 0,
            box_max: bounds.max.to_array(),
            _pad1: 0,
            box_center: bounds.center().to_array(),
            _pad2: 0,
        };
        let pixels = settings.width as usize * settings.height as usize;
        Ok(ShadeBuffers {
            tris: storage(ctx, "shading triangles", &triangle_records(mesh))?,
            tables: storage(ctx, "materials and lights", &tables)?,
            params: uniform(ctx, "shading parameters", &params),
            counters: output(ctx, "ray counters", 4)?,
            radiance: output(ctx, "radiance", 3 * pixels)?,
            env_texels: storage(ctx, "environment map", &env.texels)?,
        })
    }
}
