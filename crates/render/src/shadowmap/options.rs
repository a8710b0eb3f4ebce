//! Shadow-map settings.

use raykit_core::TriangleMesh;

/// Settings of the Purcell-style stream tracer's shadow maps (depth rendered from each light,
/// compared against with a box-filtered percentage-closer lookup).
///
/// Defaults ([`Default`]) are for a scene of unit size; use
/// [`ShadowMapOptions::for_mesh`] to scale the world-space bias to a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowMapOptions {
    /// Texels along each side of a map (each of the six faces for point
    /// lights). Default 1024: a point light's cube map is then six 1024²
    /// faces (24 MiB of depth, 4× less to rasterize and hold than 2048),
    /// and texels stay small enough that the maps agree with shadow rays
    /// on the test scenes (`tests/shadowmap.rs`: outside a band of three
    /// texels around shadow edges, more than 99% of points agree); raise it
    /// for large outdoor scenes lit by one directional light. Clamped to
    /// `8..=16384`.
    pub resolution: u32,
    /// Width of the box filter in texels: `pcf × pcf` taps (percentage-closer
    /// filtering against aliasing, the Purcell-style stream tracer). Default 3; 1 (or 0) is a
    /// single tap, no filtering. Clamped to `1..=15`.
    pub pcf: u32,
    /// Constant depth bias, world units. Default `1e-4` (for a unit-size
    /// scene; [`ShadowMapOptions::for_mesh`] gives `1e-4` times the scene's
    /// size).
    pub bias_constant: f32,
    /// Slope-scaled bias, in texels: `bias_slope · texel · tan θ` is added,
    /// `θ` the angle between the surface normal and the direction to the
    /// light (`tan θ` capped at 10) and `texel` the texel's world size at the
    /// point. Default 1.
    pub bias_slope: f32,
}

impl Default for ShadowMapOptions {
    fn default() -> Self {
        ShadowMapOptions {
            resolution: 1024,
            pcf: 3,
            bias_constant: 1e-4,
            bias_slope: 1.0,
        }
    }
}

impl ShadowMapOptions {
    /// The defaults with the constant bias scaled to `mesh`: `1e-4` times the
    /// larger of its bounding-box diagonal and its largest coordinate
    /// magnitude (so the bias also covers `f32` rounding of coordinates far
    /// from the origin), as the shadow-ray offset `shadow_bias` does.
    pub fn for_mesh(mesh: &TriangleMesh) -> Self {
        let b = mesh.bounds();
        let scale = if b.is_empty() {
            1.0
        } else {
            b.diagonal().max(b.min.abs().max(b.max.abs()).max_element())
        };
        let scale = if scale.is_finite() && scale > 0.0 {
            scale
        } else {
            1.0
        };
        ShadowMapOptions {
            bias_constant: 1e-4 * scale,
            ..ShadowMapOptions::default()
        }
    }

    /// Resolution and filter width clamped to their ranges.
    pub(crate) fn clamped(&self) -> (u32, u32) {
        (self.resolution.clamp(8, 16384), self.pcf.clamp(1, 15))
    }
}
