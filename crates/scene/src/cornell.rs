//! A Cornell-style box: white floor, ceiling and back wall, red left and green
//! right wall, open front, a tall box, a short box with a smooth sphere on
//! top, and one point light under the ceiling.

use crate::builder::{material, MeshBuilder};
use crate::{PointLight, Scene};
use raykit_core::glam::{Affine3A, Quat, Vec3};
use raykit_core::rng::Pcg32;
use raykit_core::Icosphere;
use raykit_core::{Camera, Material};

/// Half the side of the room (the room is `[-5, 5] × [0, 10] × [-5, 5]`,
/// open towards `+z`).
pub const HALF: f32 = 5.0;

/// Subdivisions of the sphere's icosphere (1280 triangles).
pub const SPHERE_SUBDIVISIONS: u32 = 3;

/// Triangles of the scene: 5 walls × 2, 2 boxes × 12, the sphere.
pub const TRIANGLES: usize = 10 + 24 + 20 * 4usize.pow(SPHERE_SUBDIVISIONS);

/// The Cornell box. `seed` jitters the boxes' angles (±4°) and positions
/// (±0.25); parts are named `floor`, `ceiling`, `back wall`, `left wall`,
/// `right wall`, `tall box`, `short box` and `sphere` (the last three closed).
pub fn cornell(seed: u64) -> Scene {
    build(seed, false)
}

/// The Cornell box of [`cornell`] with Whitted's materials (Whitted
/// 1980 renders such scenes): the tall box a silver mirror and the sphere
/// clear glass (index of refraction 1.5), for reflections and refractions.
pub fn whitted(seed: u64) -> Scene {
    let mut scene = build(seed, true);
    scene.name = "whitted".into();
    scene
}

fn build(seed: u64, whitted: bool) -> Scene {
    let mut rng = Pcg32::new(seed);
    let mut jitter = |s: f32| rng.range_f32(-s, s);
    let mut b = MeshBuilder::new();
    let white = b.add_material(material("white", [0.73, 0.73, 0.73], 0.0, 1.0));
    let red = b.add_material(material("red", [0.63, 0.06, 0.05], 0.0, 1.0));
    let green = b.add_material(material("green", [0.12, 0.45, 0.15], 0.0, 1.0));
    let boxes = b.add_material(material("box", [0.73, 0.71, 0.68], 0.05, 16.0));
    let (tall, sphere) = if whitted {
        let mirror = Material {
            reflectivity: 1.0,
            ..material("mirror", [0.0; 3], 0.95, 256.0)
        };
        let glass = Material {
            transmission: 1.0,
            ior: 1.5,
            ..material("glass", [1.0; 3], 1.0, 256.0)
        };
        (b.add_material(mirror), b.add_material(glass))
    } else {
        let blue = material("sphere", [0.15, 0.25, 0.65], 0.5, 64.0);
        (boxes, b.add_material(blue))
    };

    let h = HALF;
    let top = 2.0 * h;
    let v = Vec3::new;
    // Walls, counter-clockwise seen from inside the room.
    let walls = [
        (
            "floor",
            [v(-h, 0., h), v(h, 0., h), v(h, 0., -h), v(-h, 0., -h)],
            white,
        ),
        (
            "ceiling",
            [v(-h, top, -h), v(h, top, -h), v(h, top, h), v(-h, top, h)],
            white,
        ),
        (
            "back wall",
            [v(-h, 0., -h), v(h, 0., -h), v(h, top, -h), v(-h, top, -h)],
            white,
        ),
        (
            "left wall",
            [v(-h, 0., h), v(-h, 0., -h), v(-h, top, -h), v(-h, top, h)],
            red,
        ),
        (
            "right wall",
            [v(h, 0., -h), v(h, 0., h), v(h, top, h), v(h, top, -h)],
            green,
        ),
    ];
    for (name, corners, m) in walls {
        b.begin_part(name);
        b.add_quad(corners, m);
    }

    let tall_angle = (17.0 + jitter(4.0)).to_radians();
    let tall_at = v(-1.8 + jitter(0.25), 3.0, -1.5 + jitter(0.25));
    b.begin_part("tall box");
    b.add_box(
        Affine3A::from_scale_rotation_translation(
            v(3.0, 6.0, 3.0),
            Quat::from_rotation_y(tall_angle),
            tall_at,
        ),
        tall,
    );

    let short_angle = (-17.0 + jitter(4.0)).to_radians();
    let short_at = v(1.8 + jitter(0.25), 1.5, 1.2 + jitter(0.25));
    b.begin_part("short box");
    b.add_box(
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(3.0),
            Quat::from_rotation_y(short_angle),
            short_at,
        ),
        boxes,
    );

    let radius = 1.2;
    b.begin_part("sphere");
    b.add_icosphere(
        &Icosphere::new(SPHERE_SUBDIVISIONS),
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(radius),
            Quat::IDENTITY,
            short_at + v(0.0, 1.5 + radius, 0.0),
        ),
        sphere,
    );

    let light_at = v(0.0, top - 0.7, 1.0);
    Scene {
        name: "cornell".into(),
        mesh: b.finish(),
        lights: vec![
            PointLight::with_irradiance_at(light_at, v(1.0, 0.92, 0.8) * 0.6, light_at.y).into(),
        ],
        camera: Some(Camera {
            eye: v(0.0, h, 3.9 * h),
            target: v(0.0, h, 0.0),
            up: Vec3::Y,
            vfov_deg: 40.0,
        }),
    }
}
