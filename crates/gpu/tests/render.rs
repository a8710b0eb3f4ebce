//! The GPU Whitted renderer (one kernel per ray path and the Purcell-style stream tracer's
//! stream) gives the CPU renderer's image on the built-in scenes, and its
//! two organisations give the same image.
//!
//! Agreement is measured per pixel in linear radiance: a pixel agrees when
//! every channel is within 1e-3 relative (of the larger value, at least
//! 1e-3 absolute). At least 99.5% of pixels must agree, and every pixel
//! that does not must be explained: either the GPU's first hit differs from
//! the CPU's only by a tie (same distance, another triangle), or the pixel
//! lies on an edge of the CPU image — the GPU's value lies within the range
//! the CPU gives the pixel's 3×3 neighbourhood (a ray that rounded to the
//! other side of a silhouette, directly or in a reflection).

mod support;

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::glam::Vec3;
use raykit_core::tri::TestKind;
use raykit_core::{Camera, Light, PointLight, Ray, Texture};
use raykit_gpu::{render_whitted_gpu, GpuAccelKind, GpuScene, GpuTracer, ShadeScene};
use raykit_render::env::{Environment, EquirectMap};
use raykit_render::whitted::{
    render_whitted, Frame, IntegratorKind, ShadowMode, WhittedOptions, WhittedScene,
};
use raykit_render::Encoding;
use raykit_scene::Scene;
use support::gpu;

const W: u32 = 96;
const H: u32 = 72;

fn options(integrator: IntegratorKind, spp: u32) -> WhittedOptions {
    WhittedOptions {
        width: W,
        height: H,
        samples_per_pixel: spp,
        seed: 5,
        integrator,
        shadows: ShadowMode::Rays,
        encoding: Encoding::Gamma(1.0),
        ..WhittedOptions::default()
    }
}

fn camera(scene: &Scene) -> Camera {
    scene
        .camera
        .unwrap_or_else(|| Camera::fit(&scene.mesh.bounds(), 45.0, W as f32 / H as f32))
}

fn cpu_frame(scene: &Scene, env: &Environment, opts: &WhittedOptions, test: TestKind) -> Frame {
    let accel = build_accel(AccelKind::Bvh4, test, &scene.mesh, &BuildOptions::default());
    let ws = WhittedScene::new(&scene.mesh, accel.as_ref(), test, &scene.lights, env);
    render_whitted(&ws, &camera(scene), opts, &|_, _| {}).unwrap()
}

fn gpu_scene(scene: &Scene, kind: GpuAccelKind, test: TestKind) -> GpuScene {
    GpuScene::build(gpu(), &scene.mesh, kind, test, &BuildOptions::default()).unwrap()
}

fn gpu_frame(scene: &Scene, g: &GpuScene, env: &Environment, opts: &WhittedOptions) -> Frame {
    let ss = ShadeScene {
        mesh: &scene.mesh,
        lights: &scene.lights,
        environment: env,
    };
    render_whitted_gpu(gpu(), g, &ss, &camera(scene), opts, &|_, _| {})
        .unwrap()
        .frame
}

fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= rel * a[k].abs().max(b[k].abs()).max(1.0))
}

/// True when `v` lies within the CPU's 3×3 neighbourhood of pixel `i`,
/// channel by channel (with 1e-3 slack).
fn within_neighbourhood(cpu: &[Vec3], i: usize, v: Vec3) -> bool {
    let (x, y) = ((i % W as usize) as i64, (i / W as usize) as i64);
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for dy in -1..=1 {
        for dx in -1..=1 {
            let (nx, ny) = (x + dx, y + dy);
            if nx < 0 || ny < 0 || nx >= W as i64 || ny >= H as i64 {
                continue;
            }
            let c = cpu[(ny * W as i64 + nx) as usize];
            lo = lo.min(c);
            hi = hi.max(c);
        }
    }
    let slack = 1e-3 * hi.abs().max_element().max(1.0);
    (0..3).all(|k| v[k] >= lo[k] - slack && v[k] <= hi[k] + slack)
}

/// Compare a GPU frame with the CPU's; returns (agreeing fraction,
/// differing pixels, of which ties, of which edges).
fn agreement(
    label: &str,
    scene: &Scene,
    g: &GpuScene,
    cpu: &Frame,
    gf: &Frame,
    opts: &WhittedOptions,
) {
    let (c, v) = (&cpu.image.linear, &gf.image.linear);
    let differing: Vec<usize> = (0..c.len()).filter(|&i| !close(c[i], v[i], 1e-3)).collect();
    // First hits of the pixels' first camera samples, CPU (from the frame)
    // and GPU (the same camera rays through the same kernel's structure).
    let rays = camera(scene).rays(W, H);
    let cam: Vec<Ray> = differing
        .iter()
        .map(|&i| {
            let (x, y) = (i as u32 % W, i as u32 / W);
            let (fx, fy) = raykit_render::whitted::sample_position(
                opts.seed,
                W,
                opts.samples_per_pixel,
                x,
                y,
                0,
            );
            rays.ray(fx, fy)
        })
        .collect();
    let ghits = GpuTracer::new(gpu(), g)
        .unwrap()
        .intersect_batch(&cam)
        .unwrap();
    let (mut ties, mut edges, mut unexplained) = (0, 0, Vec::new());
    for (k, &i) in differing.iter().enumerate() {
        let ch = cpu.first_hits[i];
        let tie = match (ch, ghits[k]) {
            (Some(a), Some(b)) => a.prim != b.prim && a.t == b.t,
            _ => false,
        };
        if tie {
            ties += 1;
        } else if within_neighbourhood(c, i, v[i]) {
            edges += 1;
        } else {
            unexplained.push(i);
        }
    }
    let frac = 1.0 - differing.len() as f64 / c.len() as f64;
    let worst = (0..c.len())
        .map(|i| ((c[i] - v[i]).abs() / c[i].abs().max(v[i].abs()).max(Vec3::ONE)).max_element())
        .fold(0.0f32, f32::max);
    eprintln!(
        "{label}: {:.3}% of {} pixels within 1e-3 relative; {} differ ({ties} first-hit ties, {edges} edge pixels); \
         largest relative difference {worst:.2e}; {} environment hits; GPU {:.0} ms, CPU {:.0} ms",
        100.0 * frac,
        c.len(),
        differing.len(),
        gf.stats.environment_hits,
        gf.stats.seconds * 1e3,
        cpu.stats.seconds * 1e3
    );
    assert!(
        frac >= 0.995,
        "{label}: only {:.3}% of pixels agree",
        100.0 * frac
    );
    assert!(
        unexplained.is_empty(),
        "{label}: {} differing pixels are neither ties nor edges, e.g. {:?}",
        unexplained.len(),
        unexplained
            .iter()
            .take(4)
            .map(|&i| (i % W as usize, i / W as usize, c[i], v[i]))
            .collect::<Vec<_>>()
    );
    assert_eq!(
        cpu.stats.primary_rays, gf.stats.primary_rays,
        "{label}: primary rays"
    );
}

fn check_scene(spec: &str, env: Environment, spp: u32) {
    let scene = raykit_scene::builtin(spec).unwrap();
    check(spec, &scene, env, spp, GpuAccelKind::BvhThreaded);
}

fn check(spec: &str, scene: &Scene, env: Environment, spp: u32, kind: GpuAccelKind) {
    check_with(spec, scene, env, spp, kind, TestKind::Moller)
}

/// GPU (structure `kind`, triangle test `test`) against the CPU's bvh4 with
/// the same test, both organisations.
fn check_with(
    spec: &str,
    scene: &Scene,
    env: Environment,
    spp: u32,
    kind: GpuAccelKind,
    test: TestKind,
) {
    let g = gpu_scene(scene, kind, test);
    let mut frames = Vec::new();
    for integrator in [IntegratorKind::Recursive, IntegratorKind::Wavefront] {
        let opts = options(integrator, spp);
        let cpu = cpu_frame(scene, &env, &opts, test);
        let gf = gpu_frame(scene, &g, &env, &opts);
        let label = format!(
            "{spec} {} {} {integrator:?} spp {spp}",
            kind.name(),
            test.name()
        );
        agreement(&label, scene, &g, &cpu, &gf, &opts);
        frames.push(gf);
    }
    // The two GPU organisations: the same rays, sums in another order.
    let (a, b) = (&frames[0].image.linear, &frames[1].image.linear);
    let worst = a
        .iter()
        .zip(b)
        .map(|(x, y)| ((*x - *y).abs() / x.abs().max(y.abs()).max(Vec3::ONE)).max_element())
        .fold(0.0f32, f32::max);
    eprintln!("{spec}: GPU recursive vs wavefront, largest relative difference {worst:.2e}");
    assert!(
        worst <= 1e-5,
        "{spec}: GPU recursive and wavefront differ by {worst:e}"
    );
    assert_eq!(
        frames[0].stats.shadow_rays, frames[1].stats.shadow_rays,
        "{spec}: shadow rays"
    );
    assert_eq!(
        frames[0].stats.secondary_rays, frames[1].stats.secondary_rays,
        "{spec}: secondary rays"
    );
}

#[test]
fn cornell_matches_cpu() {
    check_scene("cornell", Environment::Sky, 1);
}

#[test]
fn whitted_mirror_and_glass_match_cpu() {
    check_scene("whitted", Environment::Sky, 2);
}

#[test]
fn shirley6_matches_cpu() {
    check_scene(
        "shirley6",
        Environment::Constant(Vec3::new(0.3, 0.4, 0.5)),
        1,
    );
}

/// Spot, directional and point lights together, and the stack kd-tree GPU tracer's kd-tree
/// kernel with its Plücker test instead of the threaded BVH with Möller.
#[test]
fn every_light_kind_on_the_plucker_kd_tree_matches_cpu() {
    let mut scene = raykit_scene::builtin("whitted").unwrap();
    let b = scene.mesh.bounds();
    let c = b.center();
    let top = Vec3::new(c.x, b.max.y - 0.05 * b.diagonal(), c.z);
    scene.lights = vec![
        Light::Spot {
            position: top,
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            intensity: Vec3::new(3.0, 2.5, 2.0) * b.diagonal() * b.diagonal() * 0.05,
            cos_inner: 20f32.to_radians().cos(),
            cos_outer: 35f32.to_radians().cos(),
        },
        Light::Directional {
            direction: Vec3::new(-0.3, -1.0, -0.6).normalize(),
            irradiance: Vec3::new(0.3, 0.3, 0.35),
        },
        Light::Point(PointLight::with_irradiance_at(
            top + Vec3::new(0.1, 0.0, 0.1) * b.diagonal(),
            Vec3::splat(0.4),
            0.5 * b.diagonal(),
        )),
    ];
    // The stack kd-tree GPU tracer's combination: the kd-tree with the Plücker test.
    check_with(
        "whitted, three light kinds",
        &scene,
        Environment::Sky,
        1,
        GpuAccelKind::KdStack,
        TestKind::Plucker,
    );
}

/// A smooth equirectangular map, looked up by direction and through the
/// environment box, rotated and scaled.
fn test_map() -> EquirectMap {
    let (w, h) = (64, 32);
    let texels = (0..w * h)
        .map(|k| {
            let (i, j) = ((k % w) as f32 / w as f32, (k / w) as f32 / h as f32);
            [
                0.2 + 0.8 * i,
                0.3 + 0.5 * j,
                0.5 + 0.4 * (i * std::f32::consts::TAU).sin() * (j * std::f32::consts::PI).sin(),
            ]
        })
        .collect();
    EquirectMap::new(w, h, texels)
        .unwrap()
        .with_rotation_deg(30.0)
        .with_intensity(1.5)
}

#[test]
fn environment_map_and_box_match_cpu() {
    let scene = raykit_scene::builtin("shirley6").unwrap();
    check(
        "shirley6, map",
        &scene,
        Environment::map(test_map()),
        1,
        GpuAccelKind::BvhThreaded,
    );
    let env = Environment::env_box(test_map(), scene.mesh.bounds(), 2.0);
    assert!(matches!(env, Environment::Box { .. }));
    check(
        "shirley6, environment box",
        &scene,
        env,
        1,
        GpuAccelKind::BvhThreaded,
    );
}

/// A base-colour texture (8×8 checker of distinct colours, bilinear,
/// repeating) on every material of the Cornell box, with texture
/// coordinates from the positions.
#[test]
fn textures_match_cpu() {
    let mut scene = raykit_scene::builtin("whitted").unwrap();
    let b = scene.mesh.bounds();
    let ext = b.extent().max_element();
    scene.mesh.uvs = Some(
        scene
            .mesh
            .positions
            .iter()
            .map(|p| {
                raykit_core::Vec2::new(
                    (p.x + p.y - b.min.x) / ext * 2.3,
                    (p.z - p.y - b.min.z) / ext * 1.7,
                )
            })
            .collect(),
    );
    let texels = (0..64)
        .map(|k| {
            let (i, j) = ((k % 8) as f32, (k / 8) as f32);
            raykit_core::glam::Vec4::new(
                0.2 + 0.1 * i,
                0.9 - 0.1 * j,
                if (k + k / 8) % 2 == 0 { 0.9 } else { 0.2 },
                1.0,
            )
        })
        .collect();
    let tex = std::sync::Arc::new(Texture::new("checker", 8, 8, texels));
    for m in &mut scene.mesh.materials {
        m.base_texture = Some(tex.clone());
    }
    check(
        "whitted, textured",
        &scene,
        Environment::Sky,
        1,
        GpuAccelKind::BvhThreaded,
    );
}
