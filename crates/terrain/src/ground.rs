//! Where a shadow segment meets the ground at its ends (Min 2008's
//! segments, with ends on the declared surface of [`crate::heightfield`]).
//!
//! A segment from a surface point to a light crosses the surface only
//! strictly between its ends, so a segment that leaves an end *into* the
//! ground and stays below the surface to the other end, or to the grid's
//! border, would cross nothing: a light on the ground would see through the
//! hill it stands on, and a slope facing away from a low sun would be lit
//! wherever its segments leave the grid below the surface. Both are
//! shadows, so the declared rule is: a point is in shadow when its segment
//! crosses the surface strictly between its ends **or leaves either end
//! into the ground**, below the plane of the triangle it leaves through.
//!
//! A point light within [`ON_GROUND`] of the surface lies on it. It is
//! placed a rounding margin above the surface ([`place_light`]), so that no
//! rounding of a triangle test near the light finds a crossing the segment
//! does not make, and the rule above decides the segments that leave it
//! downwards.

use crate::heightfield::{index_along, HeightField};

/// Lights closer than this to the surface (metres, either side) lie on it.
pub const ON_GROUND: f64 = 1e-6;

/// How far above the surface a light on the ground is placed, metres: far
/// beyond the rounding of a plane's height near it (about 10⁻¹² cells of
/// position times the slope, and 10⁻¹⁶ of the height), and far below
/// anything measured.
fn ground_margin(z: f64) -> f64 {
    1e-10 * (1.0 + z.abs())
}

/// The surface height under the point light at world position `light` when
/// the light lies on the ground: within [`ON_GROUND`] of the surface, or
/// placed there by [`place_light`]. `None` otherwise, and off the grid.
pub fn ground_under_light(field: &HeightField, light: [f64; 3]) -> Option<f64> {
    surface_under(field, light).filter(|&h| (light[2] - h).abs() <= ON_GROUND + ground_margin(h))
}

/// The light as every mask tests it: a point light on the ground
/// ([`ground_under_light`]) moved to [`ground_margin`] above the surface;
/// anything else unchanged.
pub fn place_light(field: &HeightField, light: [f64; 3]) -> [f64; 3] {
    match ground_under_light(field, light) {
        Some(h) => [light[0], light[1], h + ground_margin(h)],
        None => light,
    }
}

/// The surface height under world position `light`, `None` off the grid
/// or for a position that is not finite.
fn surface_under(field: &HeightField, light: [f64; 3]) -> Option<f64> {
    let (x, y) = (light[0] / field.sx, -light[1] / field.sy);
    let (w, h) = ((field.width - 1) as f64, (field.height - 1) as f64);
    ((0.0..=w).contains(&x) && (0.0..=h).contains(&y) && light[2].is_finite())
        .then(|| field.height_at(x, y))
}

/// Whether a segment leaving grid position (`x`, `y`) on the surface with
/// direction `d` (grid units across, metres up, per unit of its parameter)
/// goes into the ground: in the triangle it leaves through, the surface
/// rises faster along it than the segment does. A segment that leaves along
/// a cell edge or a diagonal is compared with that edge, which both of its
/// triangles share. A start off the grid's cells answers false.
pub fn leaves_into_ground(field: &HeightField, x: f64, y: f64, d: [f64; 3]) -> bool {
    let [dx, dy, dz] = d;
    let (cw, ch) = field.cells();
    // Along the grid's last line, the cell before it.
    let cell = |p: f64, dp: f64, cells: usize| match index_along(p, dp, 1.0) {
        i if dp == 0.0 && i == cells as i64 => i - 1,
        i => i,
    };
    let (ci, cj) = (cell(x, dx, cw), cell(y, dy, ch));
    if ci < 0 || cj < 0 || ci >= cw as i64 || cj >= ch as i64 {
        return false;
    }
    let (u, v) = (x - ci as f64, y - cj as f64);
    // The upper triangle is u >= v (see heightfield.rs): it holds the
    // edges v = 0 and u = 1, the lower one u = 0 and v = 1, both the
    // diagonal. From a point on the diagonal, the direction decides.
    let upper = if dx == 0.0 && (u == 0.0 || u == 1.0) {
        u == 1.0
    } else if dy == 0.0 && (v == 0.0 || v == 1.0) {
        v == 0.0
    } else if u == v {
        dy <= dx
    } else {
        u > v
    };
    let plane = field.cell_plane(ci as usize, cj as usize, upper);
    let rise = plane.du * dx + plane.dv * dy;
    dz < rise - 1e-9 * (dz.abs() + rise.abs()) - 1e-12
}
