//! The shading records the WGSL reads (Whitted (1980), on the GPU after Purcell et al. (2002) shade from
//! per-triangle and per-material tables): triangles, materials, lights and
//! the texture atlas.

use raykit_core::glam::{Vec2, Vec3};
use raykit_core::{Light, Material, TriangleMesh};

/// Words per triangle in the shading buffer.
pub const TRI_WORDS: usize = 26;

fn push3(out: &mut Vec<u32>, v: [f32; 3]) {
    out.extend(v.map(f32::to_bits));
}

/// A material (16 words): diffuse, shininess, specular, reflectivity,
/// emission, transmission, ior (t and r clamped to [0, 1] as the CPU
/// shading clamps them), then its texture's first texel, width and height
/// in the atlas (width 0: none).
pub fn material_record(m: &Material, texture: [u32; 3], out: &mut Vec<u32>) {
    push3(out, m.diffuse);
    out.push(m.shininess.to_bits());
    push3(out, m.specular);
    out.push(m.reflectivity.clamp(0.0, 1.0).to_bits());
    push3(out, m.emission);
    out.push(m.transmission.clamp(0.0, 1.0).to_bits());
    out.push(m.ior.to_bits());
    out.extend(texture);
}

/// A light (16 words): kind (0 point, 1 spot, 2 directional), position,
/// direction, intensity or irradiance, cos_inner, cos_outer and the cone's
/// ramp width as `Light::toward` computes it.
pub fn light_record(l: &Light, out: &mut Vec<u32>) {
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

/// Per-triangle corners, vertex normals (zero without normals), material
/// index (meshes without that material get the default one, appended after
/// the mesh's own, as `Surface::at` falls back) and the corners' texture
/// coordinates (zero without them).
pub fn triangle_records(mesh: &TriangleMesh) -> Vec<u32> {
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
        for k in mesh.indices[i] {
            let t = mesh.uvs.as_ref().map_or(Vec2::ZERO, |t| t[k as usize]);
            out.extend([t.x.to_bits(), t.y.to_bits()]);
        }
    }
    out
}

/// Every material's base-colour texture, RGB texels one texture after the
/// other, and where each material's starts.
pub struct TextureAtlas {
    /// RGB f32 bit patterns.
    pub texels: Vec<u32>,
    entries: Vec<[u32; 3]>,
}

impl TextureAtlas {
    /// The atlas of `materials`' textures.
    pub fn build(materials: &[Material]) -> TextureAtlas {
        let mut texels = Vec::new();
        let mut entries = Vec::with_capacity(materials.len());
        for m in materials {
            match &m.base_texture {
                Some(t) if !t.texels.is_empty() => {
                    entries.push([(texels.len() / 3) as u32, t.width, t.height]);
                    for c in &t.texels {
                        texels.extend([c.x, c.y, c.z].map(f32::to_bits));
                    }
                }
                _ => entries.push([0; 3]),
            }
        }
        TextureAtlas { texels, entries }
    }

    /// Material `i`'s (first texel, width, height); width 0 without texture.
    pub fn entry(&self, i: usize) -> [u32; 3] {
        self.entries.get(i).copied().unwrap_or([0; 3])
    }
}
