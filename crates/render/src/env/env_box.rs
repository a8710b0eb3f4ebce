//! The environment box of the Purcell-style stream tracer (Purcell et al. 2002): the map
//! is painted on the inside of an axis-aligned box around the scene, and a
//! ray leaving the scene is looked up in the direction from the box centre to
//! the point where it leaves the box. Unlike a direction-only lookup, two
//! parallel rays from different places see different parts of the map
//! (parallax), as they would with real surroundings at a finite distance.

use raykit_core::glam::Vec3;
use raykit_core::Aabb;

/// The default size of an environment box relative to the scene bounds
/// ([`Environment::env_box`](super::Environment::env_box)): twice the scene,
/// so the walls are half a scene away from its sides: near enough for
/// visible parallax, far enough that the scene does not touch them.
pub const DEFAULT_BOX_SCALE: f32 = 2.0;

/// Axes thinner than this fraction of the longest are widened to it, so a
/// flat scene (a ground plane alone) still gets a box with a volume.
const MIN_RELATIVE_EXTENT: f32 = 0.01;

/// The environment box around `scene` (Purcell-style stream tracer), grounded: the scene
/// bounds scaled about their centre by `scale` horizontally and upwards, with
/// the floor kept at the scene's lowest point, so the lower half of the map
/// is painted on the ground the scene stands on rather than below it.
/// `None` for empty or non-finite bounds, or when the box overflows.
/// A non-finite or non-positive `scale` is taken as [`DEFAULT_BOX_SCALE`].
pub fn grounded_box(scene: Aabb, scale: f32) -> Option<Aabb> {
    let mut b = centered_box(scene, scale)?;
    b.min.y = scene.min.y;
    Some(b)
}

/// The scene bounds scaled about their centre by `scale` on every axis
/// (thin axes widened first, see [`grounded_box`] for the other rules).
pub fn centered_box(scene: Aabb, scale: f32) -> Option<Aabb> {
    if scene.is_empty() || !scene.min.is_finite() || !scene.max.is_finite() {
        return None;
    }
    let scale = if scale.is_finite() && scale > 0.0 {
        scale
    } else {
        DEFAULT_BOX_SCALE
    };
    let c = scene.center();
    let half = scene.extent() * 0.5;
    let half = half.max(Vec3::splat(half.max_element() * MIN_RELATIVE_EXTENT)) * scale;
    let b = Aabb::new(c - half, c + half);
    (b.min.is_finite() && b.max.is_finite()).then_some(b)
}

/// The ray parameter `t ≥ 0` at which `origin + t·dir` leaves `bounds`
/// (slab test in `f32`), or `None` when the ray misses the box or the box
/// lies behind it. Zero direction components are handled without dividing:
/// the ray is then inside that slab for every `t` or for none.
pub fn exit_t(bounds: &Aabb, origin: Vec3, dir: Vec3) -> Option<f32> {
    let mut near = f32::NEG_INFINITY;
    let mut far = f32::INFINITY;
    for a in 0..3 {
        let (o, d, lo, hi) = (origin[a], dir[a], bounds.min[a], bounds.max[a]);
        if d == 0.0 {
            if o < lo || o > hi {
                return None;
            }
            continue;
        }
        let (t0, t1) = ((lo - o) / d, (hi - o) / d);
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    (near <= far && far >= 0.0).then_some(far)
}

/// The direction from the centre of `bounds` to where the ray leaves it, or
/// `None` when the ray misses the box (or the exit point is the centre
/// itself or not finite), in which case the caller looks up `dir` itself.
pub fn exit_direction(bounds: &Aabb, origin: Vec3, dir: Vec3) -> Option<Vec3> {
    if !(origin.is_finite() && dir.is_finite()) {
        return None;
    }
    let t = exit_t(bounds, origin, dir)?;
    // (origin − centre) + t·dir rather than exit − centre: exact for rays
    // from the centre, where it is t·dir.
    let q = (origin - bounds.center()) + dir * t;
    (q.is_finite() && q != Vec3::ZERO).then_some(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_parallel_rays_inside_and_outside() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        assert_eq!(exit_t(&b, Vec3::ZERO, Vec3::X), Some(1.0));
        assert_eq!(exit_t(&b, Vec3::new(0.5, 0.0, 0.0), Vec3::NEG_X), Some(1.5));
        assert_eq!(exit_t(&b, Vec3::new(0.0, 2.0, 0.0), Vec3::X), None);
        assert_eq!(exit_t(&b, Vec3::new(-3.0, 0.0, 0.0), Vec3::X), Some(4.0));
        assert_eq!(exit_t(&b, Vec3::new(3.0, 0.0, 0.0), Vec3::X), None);
        assert_eq!(exit_direction(&b, Vec3::ZERO, Vec3::ZERO), None);
    }

    #[test]
    fn grounded_box_keeps_the_floor() {
        let scene = Aabb::new(Vec3::new(-1.0, 0.0, -2.0), Vec3::new(1.0, 2.0, 2.0));
        let b = grounded_box(scene, 2.0).unwrap();
        assert_eq!(
            b,
            Aabb::new(Vec3::new(-2.0, 0.0, -4.0), Vec3::new(2.0, 3.0, 4.0))
        );
        let c = centered_box(scene, f32::NAN).unwrap();
        assert_eq!(
            c,
            Aabb::new(Vec3::new(-2.0, -1.0, -4.0), Vec3::new(2.0, 3.0, 4.0))
        );
        assert_eq!(grounded_box(Aabb::EMPTY, 2.0), None);
        let flat = Aabb::new(Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 0.0, 5.0));
        let f = grounded_box(flat, 2.0).unwrap();
        assert_eq!(f.min.y, 0.0);
        assert!((f.max.y - 0.1).abs() < 1e-6, "{f:?}");
        let huge = Aabb::new(Vec3::splat(-3e38), Vec3::splat(3e38));
        assert_eq!(centered_box(huge, 2.0), None);
    }
}
