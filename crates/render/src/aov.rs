//! Arbitrary output variables of a frame: what the camera's first hit was,
//! per pixel — distance, surface normal and triangle id — for compositing,
//! debugging and checking the rasterized visibility buffer of the Purcell-style stream tracer.

use crate::surface::Surface;
use raykit_core::glam::Vec3;
use raykit_core::{Camera, Hit, Material, TriangleMesh};

/// An AOV that `raykit render --aov` can write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AovKind {
    /// Distance along the camera ray to the first hit (`inf` on a miss).
    Depth,
    /// Unit shading normal at the first hit, facing the camera (zero on a
    /// miss).
    Normal,
    /// Triangle index of the first hit (−1 on a miss).
    TriangleId,
}

impl AovKind {
    /// All kinds, in the order of `--aov` help.
    pub const ALL: [AovKind; 3] = [AovKind::Depth, AovKind::Normal, AovKind::TriangleId];

    /// Name on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            AovKind::Depth => "depth",
            AovKind::Normal => "normal",
            AovKind::TriangleId => "id",
        }
    }

    /// The kind called `name`.
    pub fn parse(name: &str) -> Option<AovKind> {
        AovKind::ALL.into_iter().find(|k| k.name() == name.trim())
    }
}

/// Per-pixel first-hit data of a `width × height` frame, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Aovs {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Distance to the first hit, `f32::INFINITY` where the ray missed.
    pub depth: Vec<f32>,
    /// Unit shading normal facing the camera, zero where the ray missed.
    pub normal: Vec<Vec3>,
    /// Triangle index, −1 where the ray missed. The EXR file's `id` channel
    /// holds it as f32, exact for the first 2²⁴ triangles.
    pub id: Vec<i64>,
}

impl Aovs {
    /// The AOVs of the first hits `hits` (as [`crate::whitted::Frame`]
    /// keeps them) of the pixel-centre rays of `camera`.
    pub fn from_hits(
        mesh: &TriangleMesh,
        camera: &Camera,
        width: u32,
        height: u32,
        hits: &[Option<Hit>],
    ) -> Aovs {
        let rays = camera.rays(width, height);
        let fallback = Material::default();
        let n = width as usize * height as usize;
        let (mut depth, mut normal, mut id) =
            (vec![f32::INFINITY; n], vec![Vec3::ZERO; n], vec![-1; n]);
        for (i, h) in hits.iter().enumerate().take(n) {
            if let Some(h) = h {
                let ray = rays.pixel((i % width as usize) as u32, (i / width as usize) as u32);
                let s = Surface::at(mesh, &ray, h, &fallback);
                depth[i] = h.t * ray.dir().length();
                normal[i] = s.shading_normal;
                id[i] = h.prim as i64;
            }
        }
        Aovs {
            width,
            height,
            depth,
            normal,
            id,
        }
    }

    /// An 8-bit RGB picture of one AOV: depth as grey (near white, far
    /// dark, between the nearest and farthest hit), normals as
    /// `0.5 + 0.5·n`, ids as a distinct colour per triangle (misses black).
    pub fn preview(&self, kind: AovKind) -> Vec<u8> {
        match kind {
            AovKind::Depth => {
                let finite = self.depth.iter().copied().filter(|d| d.is_finite());
                let (lo, hi) = finite.fold((f32::INFINITY, 0.0f32), |(lo, hi), d| {
                    (lo.min(d), hi.max(d))
                });
                let span = (hi - lo).max(1e-20);
                self.depth
                    .iter()
                    .flat_map(|&d| {
                        let g = if d.is_finite() {
                            (255.0 * (1.0 - 0.85 * (d - lo) / span)).round() as u8
                        } else {
                            0
                        };
                        [g; 3]
                    })
                    .collect()
            }
            AovKind::Normal => self
                .normal
                .iter()
                .flat_map(|n| {
                    if *n == Vec3::ZERO {
                        [0; 3]
                    } else {
                        (n.to_array())
                            .map(|c| ((0.5 + 0.5 * c) * 255.0).round().clamp(0.0, 255.0) as u8)
                    }
                })
                .collect(),
            AovKind::TriangleId => self
                .id
                .iter()
                .flat_map(|&id| {
                    if id < 0 {
                        return [0; 3];
                    }
                    let h = (id as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
                    [
                        (h >> 56) as u8 | 0x30,
                        (h >> 40) as u8 | 0x30,
                        (h >> 24) as u8 | 0x30,
                    ]
                })
                .collect(),
        }
    }

    /// The float channels of one AOV for an EXR file: `Z` for depth, `R`,
    /// `G`, `B` for the normal's x, y, z, and `id` for the triangle id.
    pub fn channels(&self, kind: AovKind) -> Vec<(&'static str, Vec<f32>)> {
        match kind {
            AovKind::Depth => vec![("Z", self.depth.clone())],
            AovKind::Normal => ["R", "G", "B"]
                .into_iter()
                .enumerate()
                .map(|(k, name)| (name, self.normal.iter().map(|n| n[k]).collect()))
                .collect(),
            AovKind::TriangleId => vec![("id", self.id.iter().map(|&i| i as f32).collect())],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
    use raykit_core::tri::TestKind;

    #[test]
    fn aovs_agree_with_the_hit_geometry() {
        let scene = raykit_scene::builtin("cornell").unwrap();
        let camera = scene.camera.unwrap();
        let accel = build_accel(
            AccelKind::Bvh2,
            TestKind::Moller,
            &scene.mesh,
            &BuildOptions::default(),
        );
        let (w, h) = (40, 30);
        let hits = crate::primary_hits(accel.as_ref(), &camera, w, h);
        let a = Aovs::from_hits(&scene.mesh, &camera, w, h, &hits);
        let rays = camera.rays(w, h);
        for (i, hit) in hits.iter().enumerate() {
            let ray = rays.pixel(i as u32 % w, i as u32 / w);
            match hit {
                None => assert!(a.depth[i].is_infinite() && a.id[i] == -1),
                Some(hit) => {
                    // The depth is the distance from the eye to the hit
                    // point interpolated from the triangle's corners.
                    let [p, q, r] = scene.mesh.triangle(hit.prim as usize);
                    let point = p * (1.0 - hit.u - hit.v) + q * hit.u + r * hit.v;
                    assert!((a.depth[i] - point.distance(ray.origin)).abs() < 1e-3 * a.depth[i]);
                    assert!(a.normal[i].dot(ray.dir()) < 0.0);
                    assert!((a.normal[i].length() - 1.0).abs() < 1e-4);
                    assert_eq!(a.id[i], hit.prim as i64);
                }
            }
        }
        assert_eq!(a.preview(AovKind::Normal).len(), (w * h * 3) as usize);
        assert_eq!(a.channels(AovKind::Normal).len(), 3);
    }
}
