//! Shadow maps, after the Purcell-style stream tracer's hybrid renderer: instead of a shadow
//! feeler ray per light and surface point, the depth of the scene seen from
//! each light is rendered once by the CPU rasterizer ([`crate::raster`]),
//! and a point is lit where it is no farther from the light than the stored
//! depth, box-filtered (percentage-closer filtering) against aliasing.
//!
//! - Directional lights: one orthographic map fitted around the scene bounds
//!   seen along the light.
//! - Spot lights: one perspective map covering the outer cone (half-angles up
//!   to 60°; wider cones get a cube map).
//! - Point lights: a cube map of six 90° perspective faces.
//!
//! Every map is a little wider than its region (by the filter radius plus
//! two texels) so the filter taps of a covered point stay inside it. Each
//! texel stores the exact distance along its centre ray to the nearest
//! triangle (the rasterizer computes the same hit as a traced ray), and a
//! lookup compares it with where that texel's ray meets the plane of the
//! receiving surface (exact for planar receivers), less a bias: constant
//! plus slope-scaled by the angle between the normal and the light
//! ([`ShadowMapOptions`]).

mod depth;
mod distinct;
mod options;
mod views;

pub use options::ShadowMapOptions;

use depth::DepthMap;
use distinct::distinct_triangles;
use raykit_core::{Light, TriangleMesh, Vec3};
use rayon::prelude::*;

/// The maps of one light.
enum LightMaps {
    /// Nothing to shadow (empty scene, unusable light): always lit.
    None,
    /// One orthographic or perspective map.
    Single(DepthMap),
    /// Six faces around the light's position, in `views::cube` order.
    Cube(Vec<DepthMap>),
}

/// The Purcell-style stream tracer's shadow maps for a list of lights: build once with
/// [`ShadowMaps::build`], then query [`ShadowMaps::visibility`] instead of
/// casting shadow rays.
pub struct ShadowMaps {
    opts: ShadowMapOptions,
    pcf: u32,
    lights: Vec<(Light, LightMaps)>,
}

impl ShadowMaps {
    /// Render the depth maps of every light of `lights` for `mesh`
    /// (Williams 1978): all maps in parallel, each rasterized in parallel
    /// bands, from the mesh without repeated triangles (see `distinct.rs`).
    pub fn build(mesh: &TriangleMesh, lights: &[Light], opts: &ShadowMapOptions) -> ShadowMaps {
        let (res, pcf) = opts.clamped();
        let border = views::border(pcf);
        let bounds = mesh.bounds();
        // Every view to render, tagged with its light.
        let mut jobs = Vec::new();
        let mut kinds = Vec::new();
        for (i, light) in lights.iter().enumerate() {
            let usable = !bounds.is_empty() && bounds.min.is_finite() && bounds.max.is_finite();
            match *light {
                _ if !usable => kinds.push(0),
                Light::Directional { direction, .. } => {
                    let dir = direction.normalize_or_zero();
                    if dir == Vec3::ZERO || !dir.is_finite() {
                        kinds.push(0);
                    } else {
                        jobs.push((i, views::orthographic(dir, &bounds, res, border)));
                        kinds.push(1);
                    }
                }
                Light::Spot {
                    position,
                    direction,
                    cos_outer,
                    ..
                } if position.is_finite() => {
                    let dir = direction.normalize_or_zero();
                    let half = cos_outer.clamp(-1.0, 1.0).acos();
                    if dir != Vec3::ZERO
                        && dir.is_finite()
                        && half.is_finite()
                        && half <= views::MAX_SPOT_HALF_ANGLE_DEG.to_radians()
                    {
                        let tan = half.tan().max(1e-3);
                        jobs.push((
                            i,
                            views::perspective(position, dir, Vec3::Y, tan, res, border),
                        ));
                        kinds.push(1);
                    } else {
                        jobs.extend(views::cube(position, res, border).map(|v| (i, v)));
                        kinds.push(6);
                    }
                }
                Light::Point(p) if p.position.is_finite() => {
                    jobs.extend(views::cube(p.position, res, border).map(|v| (i, v)));
                    kinds.push(6);
                }
                _ => kinds.push(0),
            }
        }
        let distinct = distinct_triangles(mesh);
        let mut maps = jobs
            .into_par_iter()
            .map(|(_, view)| DepthMap::render(&distinct, view, res))
            .collect::<Vec<_>>()
            .into_iter();
        let lights = lights
            .iter()
            .zip(kinds)
            .map(|(light, kind)| {
                let maps = match kind {
                    1 => maps.next().map_or(LightMaps::None, LightMaps::Single),
                    6 => LightMaps::Cube(maps.by_ref().take(6).collect()),
                    _ => LightMaps::None,
                };
                (*light, maps)
            })
            .collect();
        ShadowMaps {
            opts: *opts,
            pcf,
            lights,
        }
    }

    /// Fraction in `[0, 1]` of the filter taps (the Purcell-style stream tracer's box filter,
    /// `pcf × pcf`) that see `point` lit by light `light_index`: 1 lit, 0 in
    /// shadow, between only near shadow boundaries. `geometric_normal` is the
    /// surface's normal at `point` (either orientation, any length; zero
    /// falls back to a depth test at the point itself). Points outside a
    /// map's region (outside a spot's cone, behind a spot light) and unknown
    /// light indices count as lit.
    pub fn visibility(&self, light_index: usize, point: Vec3, geometric_normal: Vec3) -> f32 {
        let Some((light, maps)) = self.lights.get(light_index) else {
            return 1.0;
        };
        if !point.is_finite() {
            return 1.0;
        }
        let map = match maps {
            LightMaps::None => return 1.0,
            LightMaps::Single(m) => m,
            LightMaps::Cube(faces) => {
                let Some(pos) = light.position() else {
                    return 1.0;
                };
                match faces.get(views::cube_face(point - pos)) {
                    Some(m) => m,
                    None => return 1.0,
                }
            }
        };
        let to_light = light.toward(point).to_light;
        let mut n = geometric_normal.normalize_or_zero();
        if !n.is_finite() {
            n = Vec3::ZERO;
        }
        let cos = n.dot(to_light).abs();
        let tan = if n == Vec3::ZERO || cos.is_nan() || cos <= 0.0 {
            10.0
        } else {
            ((1.0 - cos * cos).max(0.0).sqrt() / cos).min(10.0)
        };
        let bias = self.opts.bias_constant.max(0.0)
            + self.opts.bias_slope.max(0.0) * map.texel_size(point) * tan;
        let bias = if bias.is_finite() { bias } else { 0.0 };
        map.lit_fraction(point, n, self.pcf, bias).unwrap_or(1.0)
    }

    /// Number of lights the maps were built for.
    pub fn len(&self) -> usize {
        self.lights.len()
    }

    /// True when built for no light.
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// Bytes held by the depth maps (the Purcell-style stream tracer's memory cost of shadow maps).
    pub fn memory_bytes(&self) -> usize {
        self.lights
            .iter()
            .map(|(_, m)| match m {
                LightMaps::None => 0,
                LightMaps::Single(m) => m.bytes(),
                LightMaps::Cube(faces) => faces.iter().map(DepthMap::bytes).sum(),
            })
            .sum::<usize>()
            + std::mem::size_of::<Self>()
    }
}
