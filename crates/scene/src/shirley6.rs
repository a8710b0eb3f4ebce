//! A small scene in the spirit of Peter Shirley's test scene 6, the 804-triangle
//! scene of the intersection benchmarks in the stack kd-tree GPU tracer: a checkered ground, two
//! smooth spheres and three boxes under one point light.

use crate::builder::{material, MeshBuilder};
use crate::{PointLight, Scene};
use raykit_core::glam::{Affine3A, Quat, Vec3};
use raykit_core::rng::Pcg32;
use raykit_core::Camera;
use raykit_core::Icosphere;

/// Cells per side of the ground grid (2 triangles each).
pub const GROUND_CELLS: u32 = 8;

/// Subdivisions of the spheres (320 triangles each).
pub const SPHERE_SUBDIVISIONS: u32 = 2;

/// Triangles of the scene: ground 128, two spheres 640, three boxes 36.
pub const TRIANGLES: usize =
    2 * (GROUND_CELLS * GROUND_CELLS) as usize + 2 * 20 * 4usize.pow(SPHERE_SUBDIVISIONS) + 36;

/// The scene; `seed` jitters object positions (±0.3) and box angles (±10°).
/// Parts: `ground` (open), `sphere 0`, `sphere 1`, `box 0`, `box 1`, `box 2`
/// (closed).
pub fn shirley6(seed: u64) -> Scene {
    let mut rng = Pcg32::new(seed);
    let mut jitter = |s: f32| rng.range_f32(-s, s);
    let mut b = MeshBuilder::new();
    let light = b.add_material(material("ground light", [0.75, 0.75, 0.72], 0.02, 8.0));
    let dark = b.add_material(material("ground dark", [0.25, 0.25, 0.28], 0.02, 8.0));
    let sphere_mats = [
        b.add_material(material("red plastic", [0.7, 0.12, 0.1], 0.4, 48.0)),
        b.add_material(material("blue plastic", [0.1, 0.25, 0.7], 0.4, 48.0)),
    ];
    let box_mats = [
        b.add_material(material("yellow", [0.8, 0.65, 0.15], 0.1, 16.0)),
        b.add_material(material("white", [0.8, 0.8, 0.8], 0.1, 16.0)),
        b.add_material(material("teal", [0.1, 0.5, 0.45], 0.1, 16.0)),
    ];
    let v = Vec3::new;

    b.begin_part("ground");
    b.add_grid(
        v(-10.0, 0.0, 10.0),
        v(20.0, 0.0, 0.0),
        v(0.0, 0.0, -20.0),
        (GROUND_CELLS, GROUND_CELLS),
        |i, j| if (i + j) % 2 == 0 { light } else { dark },
    );

    let ico = Icosphere::new(SPHERE_SUBDIVISIONS);
    let spheres = [(v(-2.5, 0.0, 0.0), 1.5), (v(2.0, 0.0, 2.0), 1.0)];
    for (k, ((at, r), m)) in spheres.into_iter().zip(sphere_mats).enumerate() {
        b.begin_part(format!("sphere {k}"));
        let center = at + v(jitter(0.3), r, jitter(0.3));
        let t = Affine3A::from_scale_rotation_translation(Vec3::splat(r), Quat::IDENTITY, center);
        b.add_icosphere(&ico, t, m);
    }

    let boxes = [
        (v(3.5, 0.0, -2.5), v(1.5, 1.5, 1.5), 30.0),
        (v(-5.0, 0.0, -3.0), v(1.0, 3.0, 1.0), 15.0),
        (v(0.5, 0.0, -4.0), v(3.0, 0.6, 2.0), -10.0),
    ];
    for (k, ((at, size, deg), m)) in boxes.into_iter().zip(box_mats).enumerate() {
        b.begin_part(format!("box {k}"));
        let center = at + v(jitter(0.3), 0.5 * size.y, jitter(0.3));
        let angle = (deg + jitter(10.0)).to_radians();
        let t =
            Affine3A::from_scale_rotation_translation(size, Quat::from_rotation_y(angle), center);
        b.add_box(t, m);
    }

    let light_at = v(6.0, 12.0, 8.0);
    Scene {
        name: "shirley6".into(),
        mesh: b.finish(),
        lights: vec![
            PointLight::with_irradiance_at(light_at, Vec3::splat(1.0), light_at.length()).into(),
        ],
        camera: Some(Camera {
            eye: v(0.0, 5.0, 15.0),
            target: v(0.0, 1.0, -1.0),
            up: Vec3::Y,
            vfov_deg: 45.0,
        }),
    }
}
