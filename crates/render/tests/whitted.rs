//! The Whitted integrator checked against independent references: a mirror
//! facing a known pattern (reflection recomputed in f64), refraction through
//! a glass slab (Snell's lateral offset in f64), energy conservation in a
//! white furnace, and the two integrators and the two primary-visibility
//! modes against each other.

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::glam::{Affine3A, DVec3, Quat, Vec3};
use raykit_core::tri::TestKind;
use raykit_core::{Accel, Camera, Icosphere, Material, Ray, TriangleMesh};
use raykit_render::env::Environment;
use raykit_render::whitted::{
    render_whitted, Frame, IntegratorKind, PrimaryMode, ShadowMode, ShadowSource, Tracer,
    WhittedOptions, WhittedScene,
};
use raykit_render::Encoding;
use raykit_scene::{material, MeshBuilder};

#[path = "support/builtin_frame.rs"]
mod builtin_frame;
use builtin_frame::whitted_frame;

fn bvh(mesh: &TriangleMesh) -> Box<dyn Accel> {
    build_accel(
        AccelKind::Bvh2,
        TestKind::Moller,
        mesh,
        &BuildOptions::default(),
    )
}

fn frame(mesh: &TriangleMesh, env: &Environment, camera: &Camera, opts: &WhittedOptions) -> Frame {
    let accel = bvh(mesh);
    let scene = WhittedScene::new(mesh, accel.as_ref(), TestKind::Moller, &[], env);
    render_whitted(&scene, camera, opts, &|_, _| {}).expect("renders")
}

fn linear_opts(w: u32, h: u32, depth: u32) -> WhittedOptions {
    WhittedOptions {
        width: w,
        height: h,
        max_depth: depth,
        ambient: Vec3::ZERO,
        shadows: ShadowMode::Off,
        encoding: Encoding::Gamma(1.0),
        ..WhittedOptions::default()
    }
}

fn emissive(name: &str, c: [f32; 3]) -> Material {
    Material {
        emission: c,
        ..material(name, [0.0; 3], 0.0, 1.0)
    }
}

/// Colour of checker cell (i, j), distinct per cell.
fn cell_colour(i: i64, j: i64) -> [f32; 3] {
    let h = (i * 7 + j * 13).rem_euclid(17) as f32 / 17.0;
    [h, 1.0 - h, 0.25 + 0.5 * ((i + j).rem_euclid(2) as f32)]
}

const CELLS: i64 = 8;
const CELL: f32 = 1.0;
const PATTERN_Z: f32 = 6.0;

#[test]
fn mirror_shows_the_pattern_where_f64_reflection_says() {
    // A 4 × 4 mirror in the plane z = 0 facing +z, and behind the camera a
    // checker of emissive unit squares in the plane z = 6 facing −z.
    let mut b = MeshBuilder::new();
    let mirror = b.add_material(Material {
        reflectivity: 1.0,
        ..material("mirror", [0.0; 3], 1.0, 1.0)
    });
    let v = Vec3::new;
    b.begin_part("mirror");
    b.add_quad(
        [
            v(-2., -2., 0.),
            v(2., -2., 0.),
            v(2., 2., 0.),
            v(-2., 2., 0.),
        ],
        mirror,
    );
    b.begin_part("pattern");
    let half = CELLS / 2;
    for i in -half..half {
        for j in -half..half {
            let m = b.add_material(emissive("cell", cell_colour(i, j)));
            let (x0, y0) = (i as f32 * CELL, j as f32 * CELL);
            let (x1, y1) = (x0 + CELL, y0 + CELL);
            let z = PATTERN_Z;
            b.add_quad([v(x0, y0, z), v(x0, y1, z), v(x1, y1, z), v(x1, y0, z)], m);
        }
    }
    let mesh = b.finish();
    let camera = Camera {
        eye: v(0.3, -0.2, 3.0),
        target: v(0.1, 0.1, 0.0),
        up: Vec3::Y,
        vfov_deg: 50.0,
    };
    let (w, h) = (64, 48);
    let env = Environment::Constant(Vec3::splat(0.123));
    let img = frame(&mesh, &env, &camera, &linear_opts(w, h, 2)).image;
    let rays = camera.rays(w, h);
    let (mut checked, mut mirror_pixels) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let r = rays.pixel(x, y);
            let (o, dir) = (r.origin.as_dvec3(), r.dir().as_dvec3());
            // f64: hit the mirror plane, reflect, hit the pattern plane.
            let t = -o.z / dir.z;
            let p = o + dir * t;
            let expected = if t > 0.0 && p.x.abs() < 2.0 && p.y.abs() < 2.0 {
                let refl = DVec3::new(dir.x, dir.y, -dir.z);
                let s = (PATTERN_Z as f64 - p.z) / refl.z;
                let q = p + refl * s;
                let (cx, cy) = (q.x / CELL as f64, q.y / CELL as f64);
                let edge = |c: f64| (c - c.round()).abs() < 0.02;
                let inside = cx.abs() < half as f64 && cy.abs() < half as f64;
                if edge(cx) || edge(cy) || (p.x.abs() > 1.98 || p.y.abs() > 1.98) {
                    continue;
                }
                mirror_pixels += 1;
                if inside {
                    DVec3::from(cell_colour(cx.floor() as i64, cy.floor() as i64).map(f64::from))
                } else {
                    DVec3::splat(0.123)
                }
            } else if (p.x.abs() - 2.0).abs() < 0.02 || (p.y.abs() - 2.0).abs() < 0.02 {
                continue;
            } else {
                DVec3::splat(0.123)
            };
            let got = img.linear[(y * w + x) as usize].as_dvec3();
            assert!(
                (got - expected).abs().max_element() < 1e-5,
                "pixel ({x}, {y}): got {got}, f64 reflection says {expected}"
            );
            checked += 1;
        }
    }
    assert!(
        mirror_pixels > (w * h) as usize / 3,
        "the mirror fills the view: {mirror_pixels}"
    );
    assert!(
        checked > (w * h) as usize * 8 / 10,
        "{checked} pixels checked"
    );
}

/// A glass slab `[-5, 5] × [0, thickness] × [-5, 5]` (a closed box).
fn slab(thickness: f32, ior: f32) -> TriangleMesh {
    let mut b = MeshBuilder::new();
    let glass = b.add_material(Material {
        transmission: 1.0,
        ior,
        ..material("glass", [1.0; 3], 1.0, 1.0)
    });
    b.begin_part("slab");
    b.add_box(
        Affine3A::from_scale_rotation_translation(
            Vec3::new(10.0, thickness, 10.0),
            Quat::IDENTITY,
            Vec3::new(0.0, thickness / 2.0, 0.0),
        ),
        glass,
    );
    b.finish()
}

#[test]
fn glass_slab_shifts_a_ray_by_snells_lateral_offset() {
    let (thickness, ior) = (0.8f32, 1.5f32);
    let mesh = slab(thickness, ior);
    let accel = bvh(&mesh);
    let env = Environment::Constant(Vec3::ONE);
    let tracer = Tracer::new(
        &mesh,
        accel.as_ref(),
        &[],
        &env,
        ShadowSource::Off,
        Vec3::ZERO,
        5,
    );
    for deg in [0.0f64, 10.0, 25.0, 40.0, 60.0, 75.0] {
        let th = deg.to_radians();
        let dir = DVec3::new(th.sin(), -th.cos(), 0.0);
        let origin = DVec3::new(-1.0, 2.0, 0.3);
        let ray = Ray::new(origin.as_vec3(), dir.as_vec3());
        let path = tracer.transmitted_path(&ray);
        assert_eq!(path.len(), 3, "{deg}°: camera ray, inside, out below");
        let out = path[2];
        // Leaves parallel to the incoming ray.
        assert!(
            (out.dir().as_dvec3() - dir).length() < 1e-5,
            "{deg}°: {}",
            out.dir()
        );
        // Inside: Snell's law.
        let inside = path[1].dir().as_dvec3();
        let sin_t = inside.x.hypot(inside.z);
        assert!((th.sin() - ior as f64 * sin_t).abs() < 1e-5, "{deg}°");
        // Lateral offset between the exiting ray's line and the incoming
        // ray's line: d · sin(θi − θt) / cos θt.
        let th_t = (th.sin() / ior as f64).asin();
        let expected = thickness as f64 * (th - th_t).sin() / th_t.cos();
        let p = out.origin.as_dvec3();
        let offset = (p - origin).cross(dir).length();
        // Secondary rays start `bias` off the surface, which moves each
        // segment sideways by at most that much.
        let tol = 1e-5 + 3.0 * tracer.bias as f64;
        assert!(
            (offset - expected).abs() < tol,
            "{deg}°: offset {offset}, Snell says {expected} (± {tol})"
        );
    }
}

/// An icosphere of radius 1 at the origin with material `m`.
fn sphere(m: Material) -> TriangleMesh {
    let mut b = MeshBuilder::new();
    let id = b.add_material(m);
    b.begin_part("sphere");
    b.add_icosphere(&Icosphere::new(3), Affine3A::IDENTITY, id);
    b.finish()
}

fn furnace_camera() -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.4, 4.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        vfov_deg: 35.0,
    }
}

/// A glass cube of side 1.6 turned about two axes, with flat faces.
fn glass_cube() -> TriangleMesh {
    let mut b = MeshBuilder::new();
    let id = b.add_material(Material {
        transmission: 1.0,
        ior: 1.5,
        ..material("glass", [1.0; 3], 1.0, 1.0)
    });
    b.begin_part("cube");
    b.add_box(
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(1.6),
            Quat::from_rotation_y(0.5) * Quat::from_rotation_x(0.3),
            Vec3::ZERO,
        ),
        id,
    );
    b.finish()
}

/// The largest and the mean channel value of an image.
fn max_and_mean(f: &Frame) -> (f32, f64) {
    let mut max = 0.0f32;
    let mut sum = 0.0f64;
    for c in &f.image.linear {
        max = max.max(c.max_element());
        sum += (c.x + c.y + c.z) as f64;
    }
    (max, sum / (3 * f.image.linear.len()) as f64)
}

#[test]
fn white_furnace_glass_and_mirror_neither_create_nor_lose_energy() {
    // In a uniform white environment a lossless dielectric (Fresnel
    // reflection plus refraction) or a perfect mirror must look exactly as
    // bright as the environment: no energy created, none lost.
    let env = Environment::Constant(Vec3::ONE);
    let mirror = sphere(Material {
        reflectivity: 1.0,
        ..material("mirror", [0.0; 3], 1.0, 1.0)
    });
    // A cube cannot trap light (a ray entering one face meets the others at
    // less or more than the critical angle, and leaves through the opposite
    // or entry face within a few bounces).
    for (name, mesh, depth) in [
        ("glass cube", glass_cube(), 60),
        ("mirror sphere", mirror, 3),
    ] {
        let f = frame(&mesh, &env, &furnace_camera(), &linear_opts(48, 48, depth));
        for c in &f.image.linear {
            assert!(
                (c.x - 1.0).abs() < 1e-4 && c.x == c.y && c.y == c.z,
                "{name}: pixel {c}, furnace says 1"
            );
        }
        assert!(f.stats.environment_hits > 0);
    }
    // A faceted glass sphere with interpolated normals can trap rays by total
    // internal reflection (a chord orbit), which the depth limit ends: the
    // energy may fall short but never exceeds the environment's.
    let glass = sphere(Material {
        transmission: 1.0,
        ior: 1.5,
        ..material("glass", [1.0; 3], 1.0, 1.0)
    });
    let f = frame(&glass, &env, &furnace_camera(), &linear_opts(48, 48, 24));
    let (max, mean) = max_and_mean(&f);
    assert!(max <= 1.0 + 1e-4, "glass sphere: brightest {max}");
    assert!(mean > 0.97, "glass sphere: mean {mean}");
}

fn compare(a: &Frame, b: &Frame, what: &str) {
    assert_eq!(a.image.linear.len(), b.image.linear.len());
    let mut max_rel = 0.0f32;
    for (p, q) in a.image.linear.iter().zip(&b.image.linear) {
        let d = (*p - *q).abs().max_element() / p.abs().max_element().max(1e-3);
        max_rel = max_rel.max(d);
    }
    assert!(
        max_rel < 1e-4,
        "{what}: largest relative difference {max_rel}"
    );
    let differing = a
        .image
        .rgb
        .iter()
        .zip(&b.image.rgb)
        .filter(|(x, y)| x != y)
        .count();
    let worst = a
        .image
        .rgb
        .iter()
        .zip(&b.image.rgb)
        .map(|(&x, &y)| (x as i32 - y as i32).abs())
        .max()
        .unwrap_or(0);
    assert!(worst <= 1, "{what}: 8-bit values differ by up to {worst}");
    assert!(
        differing * 1000 <= a.image.rgb.len(),
        "{what}: {differing} of {} 8-bit values differ",
        a.image.rgb.len()
    );
}

#[test]
fn wavefront_image_equals_the_recursive_image() {
    for spp in [1, 3] {
        let opts = WhittedOptions {
            width: 96,
            height: 72,
            samples_per_pixel: spp,
            ..WhittedOptions::default()
        };
        let rec = whitted_frame(&opts);
        let wave = whitted_frame(&WhittedOptions {
            integrator: IntegratorKind::Wavefront,
            ..opts.clone()
        });
        compare(&rec, &wave, &format!("wavefront vs recursive, {spp} spp"));
        assert_eq!(rec.first_hits, wave.first_hits);
        // Both traced the same rays.
        assert_eq!(rec.stats.rays(), wave.stats.rays());
        assert!(rec.stats.secondary_rays > 0 && rec.stats.shadow_rays > 0);
    }
}

#[test]
fn rasterized_primaries_give_the_traced_image() {
    let scene = raykit_scene::whitted(1);
    let camera = scene.camera.unwrap();
    let (w, h) = (96u32, 72u32);
    for (spp, integrator) in [
        (1, IntegratorKind::Recursive),
        (1, IntegratorKind::Wavefront),
        (2, IntegratorKind::Wavefront),
    ] {
        let opts = WhittedOptions {
            width: w,
            height: h,
            samples_per_pixel: spp,
            integrator,
            ..WhittedOptions::default()
        };
        let traced = whitted_frame(&opts);
        let raster = whitted_frame(&WhittedOptions {
            primary: PrimaryMode::Rasterized,
            ..opts.clone()
        });
        assert_eq!(raster.stats.primary_rays, 0);
        assert!(raster.stats.raster_seconds > 0.0);
        // Where the first hits differ, it must be a tie: the ray meets both
        // triangles at the same distance (a shared edge or vertex).
        let rays = camera.rays(w, h);
        let mut ties = 0;
        for (i, (a, b)) in traced.first_hits.iter().zip(&raster.first_hits).enumerate() {
            if a == b {
                if spp == 1 {
                    assert_eq!(
                        traced.image.linear[i], raster.image.linear[i],
                        "pixel {i}: same first hit, same radiance"
                    );
                }
                continue;
            }
            let (a, b) = (a.expect("traced hit"), b.expect("rasterized hit"));
            let ray = rays.pixel(i as u32 % w, i as u32 / w);
            let ray = if spp == 1 {
                ray
            } else {
                let (fx, fy) = raykit_render::whitted::sample_position(
                    0,
                    w,
                    spp,
                    i as u32 % w,
                    i as u32 / w,
                    0,
                );
                rays.ray(fx, fy)
            };
            assert!(
                (a.t - b.t).abs() <= 1e-5 * a.t,
                "pixel {i}: traced t {} on triangle {}, rasterized t {} on triangle {}: not a tie (ray {ray:?})",
                a.t,
                a.prim,
                b.t,
                b.prim
            );
            ties += 1;
        }
        assert!(ties * 50 <= (w * h) as usize, "{ties} ties");
        let same = traced
            .image
            .linear
            .iter()
            .zip(&raster.image.linear)
            .filter(|(p, q)| p == q)
            .count();
        assert!(
            same * 100 >= traced.image.linear.len() * 98,
            "{spp} spp, {integrator:?}: {same} of {} pixels identical",
            traced.image.linear.len()
        );
    }
}

/// Bilinear sampling with repeat wrapping in f64, written for this test.
fn bilinear_f64(texels: &[[f64; 3]], w: usize, h: usize, u: f64, v: f64) -> [f64; 3] {
    let (x, y) = (u * w as f64 - 0.5, v * h as f64 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |i: i64, j: i64| {
        texels[(j.rem_euclid(h as i64) as usize) * w + i.rem_euclid(w as i64) as usize]
    };
    let (i, j) = (x0 as i64, y0 as i64);
    std::array::from_fn(|k| {
        let top = at(i, j)[k] * (1.0 - fx) + at(i + 1, j)[k] * fx;
        let bottom = at(i, j + 1)[k] * (1.0 - fx) + at(i + 1, j + 1)[k] * fx;
        top * (1.0 - fy) + bottom * fy
    })
}

#[test]
fn textured_diffuse_surface_shows_its_texture_under_a_directional_light() {
    use raykit_core::glam::{Vec2, Vec4};
    use raykit_core::{Light, Texture};
    let texels = [
        [0.9, 0.1, 0.1],
        [0.1, 0.8, 0.2],
        [0.2, 0.3, 0.9],
        [0.7, 0.7, 0.1],
    ];
    let texture = Texture::new(
        "checker",
        2,
        2,
        texels
            .iter()
            .map(|c| Vec4::new(c[0], c[1], c[2], 1.0))
            .collect(),
    );
    let v = Vec3::new;
    // A 2 × 2 quad in z = 0 facing +z; uv (0, 0) at the top-left corner
    // (x = −1, y = 1), u along +x, v along −y.
    let mesh = TriangleMesh {
        positions: vec![
            v(-1., 1., 0.),
            v(1., 1., 0.),
            v(1., -1., 0.),
            v(-1., -1., 0.),
        ],
        indices: vec![[0, 3, 2], [0, 2, 1]],
        normals: Some(vec![Vec3::Z; 4]),
        uvs: Some(vec![
            Vec2::new(0., 0.),
            Vec2::new(1., 0.),
            Vec2::new(1., 1.),
            Vec2::new(0., 1.),
        ]),
        materials: vec![Material {
            base_texture: Some(std::sync::Arc::new(texture)),
            ..material("textured", [1.0; 3], 0.0, 1.0)
        }],
        ..TriangleMesh::default()
    };
    let accel = bvh(&mesh);
    let lights = [Light::Directional {
        direction: -Vec3::Z,
        irradiance: Vec3::splat(1.0),
    }];
    let env = Environment::Constant(Vec3::ZERO);
    let scene = WhittedScene::new(&mesh, accel.as_ref(), TestKind::Moller, &lights, &env);
    let camera = Camera {
        eye: v(0.0, 0.0, 4.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        vfov_deg: 30.0,
    };
    let (w, h) = (40, 40);
    let opts = WhittedOptions {
        shadows: ShadowMode::Rays,
        ..linear_opts(w, h, 1)
    };
    let f = render_whitted(&scene, &camera, &opts, &|_, _| {}).unwrap();
    let rays = camera.rays(w, h);
    let f64_texels: Vec<[f64; 3]> = texels.iter().map(|c| c.map(f64::from)).collect();
    let mut inside = 0;
    for y in 0..h {
        for x in 0..w {
            let r = rays.pixel(x, y);
            let (o, d) = (r.origin.as_dvec3(), r.dir().as_dvec3());
            let p = o + d * (-o.z / d.z);
            let got = f.image.linear[(y * w + x) as usize];
            if p.x.abs() >= 0.999 || p.y.abs() >= 0.999 {
                continue;
            }
            inside += 1;
            let want = bilinear_f64(&f64_texels, 2, 2, (p.x + 1.0) / 2.0, (1.0 - p.y) / 2.0);
            for k in 0..3 {
                assert!(
                    (got[k] as f64 - want[k]).abs() < 1e-4,
                    "pixel ({x}, {y}): {got} vs {want:?}"
                );
            }
        }
    }
    assert!(inside > 400, "{inside} pixels on the quad");
}
