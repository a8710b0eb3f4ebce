//! The shading data of the GPU Whitted renderer (Whitted (1980), on the GPU after Purcell et al. (2002)): the
//! per-triangle corners, vertex normals and material index, the material
//! and light tables and the frame's parameters, uploaded as bind group 1 of
//! both organisations (`shaders/render/shade_data.wgsl`), with the ray
//! counters, the radiance accumulator, the environment map and the
//! base-colour textures.

use super::env_upload::environment_upload;
use super::records::{light_record, material_record, triangle_records, TextureAtlas};
use crate::buffers::{output, storage, uniform};
use crate::context::GpuContext;
use crate::error::GpuResult;
use raykit_core::glam::Vec3;
use raykit_core::{Camera, Light, Material, TriangleMesh};
use raykit_render::env::Environment;
use raykit_render::shadow_bias;

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

/// What the shading of Whitted (1980), on the GPU after Purcell et al. (2002) reads about the scene,
/// independent of the camera: geometry with materials, lights, environment.
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

/// Words of [`ShadeBuffers::counters`]: shadow rays, secondary rays,
/// environment hits, next-queue length, status.
pub(super) const COUNTER_WORDS: usize = 5;

/// Bind group 1's buffers.
pub struct ShadeBuffers {
    /// Per-triangle records.
    pub tris: wgpu::Buffer,
    /// Materials then lights.
    pub tables: wgpu::Buffer,
    /// `ShadeParams`.
    pub params: wgpu::Buffer,
    /// Ray counters (4 words) and the status word, which a kernel sets
    /// when the driver cut one of a thread's loops short.
    pub counters: wgpu::Buffer,
    /// Radiance sums (3 words per pixel).
    pub radiance: wgpu::Buffer,
    /// The environment map's texels.
    pub env_texels: wgpu::Buffer,
    /// Every material's base-colour texels, one after the other.
    pub tex_texels: wgpu::Buffer,
}

impl ShadeBuffers {
    /// The seven buffers in binding order.
    pub fn all(&self) -> [&wgpu::Buffer; 7] {
        [
            &self.tris,
            &self.tables,
            &self.params,
            &self.counters,
            &self.radiance,
            &self.env_texels,
            &self.tex_texels,
        ]
    }
}

impl ShadeBuffers {
    /// Upload `scene` for frames of `settings` seen through `camera`.
    pub fn upload(
        ctx: &GpuContext,
        scene: &ShadeScene,
        camera: &Camera,
        settings: &FrameSettings,
    ) -> GpuResult<ShadeBuffers> {
        let env = environment_upload(scene.environment);
        let atlas = TextureAtlas::build(&scene.mesh.materials);
        let (map_width, map_height, map_turn, map_intensity) = env.map.unwrap_or_default();
        let bounds = env
            .bounds
            .unwrap_or(raykit_core::Aabb::new(Vec3::ZERO, Vec3::ZERO));
        let mesh = scene.mesh;
        let mut tables = Vec::new();
        for (i, m) in mesh.materials.iter().enumerate() {
            material_record(m, atlas.entry(i), &mut tables);
        }
        material_record(&Material::default(), [0; 3], &mut tables);
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
            counters: output(ctx, "ray counters", COUNTER_WORDS)?,
            radiance: output(ctx, "radiance", 3 * pixels)?,
            env_texels: storage(ctx, "environment map", &env.texels)?,
            tex_texels: storage(ctx, "textures", &atlas.texels)?,
        })
    }
}
