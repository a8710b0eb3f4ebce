//! Camera motions driven by client input: orbit, pan, zoom, fly and the
//! device-orientation mode that stands in for the Purcell-style stream tracer's tracked handheld.

use raykit_core::glam::{Mat3, Quat, Vec3};
use raykit_core::{Camera, MAX_CAMERA_COORDINATE};

/// Smallest angle (radians) kept between the view offset and the up axis, so
/// an orbit never flips over a pole.
pub const POLE_MARGIN: f32 = 0.01;

/// Turn the eye around the target: `yaw` radians about the camera's up axis,
/// then `pitch` radians towards it (positive raises the eye), stopping
/// [`POLE_MARGIN`] short of the poles. The eye-target distance is kept.
pub fn orbit(camera: &Camera, yaw: f32, pitch: f32) -> Camera {
    let up = camera.up.normalize_or(Vec3::Y);
    let offset = Quat::from_axis_angle(up, yaw) * (camera.eye - camera.target);
    let dist = offset.length();
    let polar = (offset.dot(up) / dist).clamp(-1.0, 1.0).acos();
    let new_polar = (polar - pitch).clamp(POLE_MARGIN, std::f32::consts::PI - POLE_MARGIN);
    let mut axis = up.cross(offset);
    if axis.length_squared() < 1e-12 {
        axis = up.any_orthonormal_vector();
    }
    // Rotating about up × offset by +a moves the offset away from up.
    let offset = Quat::from_axis_angle(axis.normalize(), new_polar - polar) * offset;
    Camera {
        eye: camera.target + offset,
        ..*camera
    }
}

/// Move eye and target along the camera's right and up axes by `x` and `y`
/// times the eye-target distance.
pub fn pan(camera: &Camera, x: f32, y: f32) -> Camera {
    let (right, up, _) = camera.basis();
    let shift = (right * x + up * y) * camera.eye.distance(camera.target);
    Camera {
        eye: camera.eye + shift,
        target: camera.target + shift,
        ..*camera
    }
}

/// Multiply the eye-target distance by `factor`, never closer than
/// `min_distance`.
pub fn zoom(camera: &Camera, factor: f32, min_distance: f32) -> Camera {
    let offset = camera.eye - camera.target;
    let dist = offset.length();
    let new_dist = (dist * factor).max(min_distance);
    Camera {
        eye: camera.target + offset * (new_dist / dist),
        ..*camera
    }
}

/// Move eye and target in the camera frame by `forward`, `right` and `up`
/// times `scale` (the scene's bounding-box diagonal).
pub fn fly(camera: &Camera, forward: f32, right: f32, up: f32, scale: f32) -> Camera {
    let (r, u, f) = camera.basis();
    let shift = (f * forward + r * right + u * up) * scale;
    Camera {
        eye: camera.eye + shift,
        target: camera.target + shift,
        ..*camera
    }
}

/// The direction a phone's back camera faces for the W3C
/// `DeviceOrientationEvent` angles (degrees; `alpha` about the earth's up
/// axis, `beta` about the device's x axis, `gamma` about its y axis, applied
/// as R = Rz(α) Rx(β) Ry(γ)), in a y-up scene frame where east is +x and
/// north is −z.
pub fn orientation_direction(alpha: f32, beta: f32, gamma: f32) -> Vec3 {
    let r = Mat3::from_rotation_z(alpha.to_radians())
        * Mat3::from_rotation_x(beta.to_radians())
        * Mat3::from_rotation_y(gamma.to_radians());
    // The back camera looks along the device's −z; earth (east, north, up)
    // maps to scene (x, −z, y).
    let d = r * Vec3::NEG_Z;
    Vec3::new(d.x, d.z, -d.y)
}

/// Look in the device's direction ([`orientation_direction`]) from the
/// current eye, keeping the eye-target distance and the up vector.
pub fn orient(camera: &Camera, alpha: f32, beta: f32, gamma: f32) -> Camera {
    let dist = camera.eye.distance(camera.target);
    let dir = orientation_direction(alpha, beta, gamma);
    Camera {
        target: camera.eye + dir * dist,
        ..*camera
    }
}

/// Why a camera cannot be rendered, or `None` when it can: every number
/// finite, eye and target apart, up not parallel to the view, field of view
/// in `1..179` degrees.
pub fn camera_problem(camera: &Camera) -> Option<&'static str> {
    let v = [camera.eye, camera.target, camera.up];
    if v.iter().any(|p| !p.is_finite()) || !camera.vfov_deg.is_finite() {
        return Some("camera numbers must be finite");
    }
    if v.iter()
        .any(|p| p.abs().max_element() > MAX_CAMERA_COORDINATE)
    {
        return Some("camera coordinates must be below 1e18");
    }
    let offset = camera.target - camera.eye;
    if offset.length_squared() <= f32::MIN_POSITIVE || !offset.length().is_normal() {
        return Some("camera eye and target must differ");
    }
    if camera.up.length_squared() <= f32::MIN_POSITIVE
        || offset.normalize().cross(camera.up.normalize()).length() < 1e-4
    {
        return Some("camera up must be non-zero and not parallel to the view direction");
    }
    if !(1.0..=179.0).contains(&camera.vfov_deg) {
        return Some("camera fov must be between 1 and 179 degrees");
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera {
            eye: Vec3::new(1.0, 2.0, 5.0),
            target: Vec3::new(0.5, 1.0, 0.0),
            up: Vec3::Y,
            vfov_deg: 40.0,
        }
    }

    /// Spherical angles of the offset eye − target in f64: (azimuth about
    /// +y from +z towards +x, polar angle from +y).
    fn angles(c: &Camera) -> (f64, f64) {
        let o = (c.eye - c.target).as_dvec3();
        (o.x.atan2(o.z), (o.y / o.length()).acos())
    }

    #[test]
    fn orbit_turns_by_the_given_angles_and_keeps_the_distance() {
        let c = cam();
        let (az, pol) = angles(&c);
        let o = orbit(&c, 0.3, 0.2);
        let (az2, pol2) = angles(&o);
        assert!((az2 - az - 0.3).abs() < 1e-5, "{az} -> {az2}");
        assert!((pol - pol2 - 0.2).abs() < 1e-5, "{pol} -> {pol2}");
        let (d, d2) = (
            c.eye.as_dvec3().distance(c.target.as_dvec3()),
            o.eye.as_dvec3().distance(o.target.as_dvec3()),
        );
        assert!((d - d2).abs() < 1e-5 * d);
        assert_eq!(o.target, c.target);
        // Past the pole it stops at the margin.
        let top = orbit(&c, 0.0, 10.0);
        assert!((angles(&top).1 - POLE_MARGIN as f64).abs() < 1e-4);
        assert!(camera_problem(&top).is_none());
    }

    #[test]
    fn pan_and_fly_move_eye_and_target_together() {
        let c = cam();
        let (r, u, f) = c.basis();
        let p = pan(&c, 0.1, -0.2);
        let d = c.eye.distance(c.target);
        let want = (r * 0.1 - u * 0.2) * d;
        assert!((p.eye - c.eye - want).length() < 1e-5);
        assert!((p.target - c.target - want).length() < 1e-5);
        let q = fly(&c, 0.5, 0.0, 0.25, 2.0);
        assert!((q.eye - c.eye - (f + u * 0.5)).length() < 1e-5);
        assert!((q.target - q.eye - (c.target - c.eye)).length() < 1e-5);
    }

    #[test]
    fn zoom_scales_the_distance_with_a_floor() {
        let c = cam();
        let d = c.eye.distance(c.target);
        let z = zoom(&c, 0.5, 0.0);
        assert!((z.eye.distance(c.target) - 0.5 * d).abs() < 1e-5);
        assert!(((z.eye - c.target).normalize() - (c.eye - c.target).normalize()).length() < 1e-6);
        let near = zoom(&c, 1e-6, 0.1);
        assert!((near.eye.distance(c.target) - 0.1).abs() < 1e-5);
    }

    #[test]
    fn device_orientation_follows_the_w3c_frame() {
        // Flat on a table, screen up: the back camera looks down.
        assert!((orientation_direction(0.0, 0.0, 0.0) - Vec3::NEG_Y).length() < 1e-6);
        // Upright (beta 90) facing north: looks north, i.e. −z.
        assert!((orientation_direction(0.0, 90.0, 0.0) - Vec3::NEG_Z).length() < 1e-6);
        // Turned 90° counter-clockwise seen from above (alpha 90): west, −x.
        assert!((orientation_direction(90.0, 90.0, 0.0) - Vec3::NEG_X).length() < 1e-6);
        let o = orient(&cam(), 90.0, 90.0, 0.0);
        assert_eq!(o.eye, cam().eye);
        assert!(((o.target - o.eye).normalize() - Vec3::NEG_X).length() < 1e-6);
    }

    #[test]
    fn bad_cameras_are_named() {
        let mut c = cam();
        c.eye.x = f32::NAN;
        assert!(camera_problem(&c).is_some());
        let mut c = cam();
        c.target = c.eye;
        assert!(camera_problem(&c).is_some());
        let mut c = cam();
        c.up = c.target - c.eye;
        assert!(camera_problem(&c).is_some());
        let mut c = cam();
        c.vfov_deg = 180.0;
        assert!(camera_problem(&c).is_some());
        assert!(camera_problem(&cam()).is_none());
    }
}
