//! Traversals longer than a driver's loop limit: Mesa's lavapipe ends every
//! loop of an invocation once it has made 65,535 loop passes in all, so a
//! long traversal would silently return a wrong answer. The kernels detect
//! a loop that ended with its condition still true, and the host refuses
//! the results with [`GpuError::LoopLimit`]; everywhere else the GPU gives
//! the CPU's answers, and ordinary scenes are never refused.

mod support;

use glam::Vec3;
use raykit_core::accel::{build_accel, Accel, AccelKind, BruteForce, BuildOptions};
use raykit_core::raysets::standard_sets;
use raykit_core::tri::{Moller, TestKind};
use raykit_core::{Camera, Hit, Light, PointLight, Ray, TriangleMesh};
use raykit_gpu::{
    render_whitted_gpu, GpuAccelKind, GpuCaster, GpuError, GpuScene, GpuTerrain, GpuTracer,
    ShadeScene,
};
use raykit_render::env::Environment;
use raykit_render::whitted::{
    render_whitted, IntegratorKind, ShadowMode, WhittedOptions, WhittedScene,
};
use raykit_render::Encoding;
use raykit_terrain::view::{cast_image, Caster};
use raykit_terrain::{Dem, HeightField, MaxMipmap, TerrainCamera};
use support::{compare, gpu, shared_data};

/// `n` equal triangles stacked along z, triangle k at z = -k: a ray along
/// z crosses every one, and the threaded BVH's pre-order walk visits most
/// of its nodes whichever way the ray goes.
fn stack(n: usize) -> TriangleMesh {
    let mut v = Vec::with_capacity(3 * n);
    for k in 0..n {
        let z = -(k as f32);
        v.push(Vec3::new(-1.0, -1.0, z));
        v.push(Vec3::new(1.0, -1.0, z));
        v.push(Vec3::new(0.0, 1.0, z));
    }
    let idx = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    TriangleMesh::new(v, idx)
}

fn is_lavapipe() -> bool {
    gpu().info.name.contains("llvmpipe")
}

/// Assert that `e` is the loop limit error, naming what was cut short.
fn assert_refused(e: &GpuError, what: &str, case: &str) {
    assert!(
        matches!(e, GpuError::LoopLimit { .. }),
        "{case}: unexpected error {e}"
    );
    let msg = e.to_string();
    assert!(
        msg.contains(what) && msg.contains("loop") && msg.contains("--backend cpu"),
        "{case}: {msg}"
    );
    eprintln!("{case}: refused: {msg}");
}

/// Nearest hits and occlusion on `kind`: the CPU's answers, or the loop
/// limit error; returns whether the nearest hits were refused.
fn exact_or_refused(
    mesh: &TriangleMesh,
    kind: GpuAccelKind,
    rays: &[Ray],
    want: &[Option<Hit>],
    occluded: &[bool],
) -> bool {
    let ctx = gpu();
    let scene =
        GpuScene::build(ctx, mesh, kind, TestKind::Moller, &BuildOptions::default()).unwrap();
    let tracer = GpuTracer::new(ctx, &scene).unwrap();
    let refused = |e: GpuError| {
        assert!(
            matches!(e, GpuError::LoopLimit { .. }),
            "{}: unexpected error {e}",
            kind.name()
        );
        let msg = e.to_string();
        assert!(
            msg.contains("loop") && msg.contains("--backend cpu"),
            "{msg}"
        );
        eprintln!("{}: refused: {msg}", kind.name());
    };
    let near = match tracer.intersect_batch(rays) {
        Ok(got) => {
            assert_eq!(
                got,
                want,
                "{}: nearest hits differ from the CPU's",
                kind.name()
            );
            false
        }
        Err(e) => {
            refused(e);
            true
        }
    };
    match tracer.occluded_batch(rays) {
        Ok(got) => assert_eq!(got, occluded, "{}: occlusion differs", kind.name()),
        Err(e) => refused(e),
    }
    near
}

#[test]
fn traversals_past_the_loop_limit_are_exact_or_refused() {
    // 100,000 triangles: the upward ray's nearest hit is triangle 99,999,
    // found by brute force only after 99,999 passes of its loop.
    let mesh = stack(100_000);
    let rays = [
        Ray::new(Vec3::new(0.01, 0.02, 10.0), Vec3::new(0.0, 0.0, -1.0)),
        Ray::new(Vec3::new(0.01, 0.02, -200_000.0), Vec3::new(0.0, 0.0, 1.0)),
    ];
    let cpu = BruteForce::<Moller>::new(&mesh);
    let mut want = vec![None; rays.len()];
    cpu.intersect_batch(&rays, &mut want);
    assert_eq!(want[0].map(|h| h.prim), Some(0));
    assert_eq!(want[1].map(|h| h.prim), Some(99_999));
    let mut occluded = vec![false; rays.len()];
    cpu.occluded_batch(&rays, &mut occluded);
    for kind in GpuAccelKind::ALL {
        let refused = exact_or_refused(&mesh, kind, &rays, &want, &occluded);
        if is_lavapipe() && matches!(kind, GpuAccelKind::Brute | GpuAccelKind::BvhThreaded) {
            assert!(
                refused,
                "{}: lavapipe's loop limit went unnoticed",
                kind.name()
            );
        }
    }
}

#[test]
fn ordinary_scenes_are_not_refused() {
    let ctx = gpu();
    let mesh = raykit_io::load_mesh(&shared_data().join("meshes/bunny_3674.obj")).unwrap();
    let reference = BruteForce::<Moller>::new(&mesh);
    let sets = standard_sets(&mesh, &reference, 32, 5);
    for kind in GpuAccelKind::ALL {
        let scene =
            GpuScene::build(ctx, &mesh, kind, TestKind::Moller, &BuildOptions::default()).unwrap();
        let tracer = GpuTracer::new(ctx, &scene).unwrap();
        for rays in &sets {
            let mut want = vec![None; rays.len()];
            reference.intersect_batch(rays, &mut want);
            let got = tracer
                .intersect_batch(rays)
                .unwrap_or_else(|e| panic!("{}: {e}", kind.name()));
            let d = compare(&want, &got);
            assert!(
                d.hit_miss.is_empty() && d.distance.is_empty(),
                "{}: {d:?}",
                kind.name()
            );
            tracer
                .occluded_batch(rays)
                .unwrap_or_else(|e| panic!("{}: {e}", kind.name()));
        }
    }
}

/// Renders a tiny view of the Cornell box lit by `lights` with `integrator`
/// on the CPU and the GPU (threaded BVH): the CPU's radiance (1e-3
/// relative per channel, on all but a few silhouette pixels), or the loop
/// limit error; returns whether the GPU refused.
fn render_exact_or_refused(lights: Vec<Light>, integrator: IntegratorKind, shadows: bool) -> bool {
    let mut scene = raykit_scene::builtin("cornell").unwrap();
    scene.lights = lights;
    let (w, h) = (8, 6);
    let opts = WhittedOptions {
        width: w,
        height: h,
        samples_per_pixel: 1,
        seed: 5,
        integrator,
        shadows: if shadows {
            ShadowMode::Rays
        } else {
            ShadowMode::Off
        },
        encoding: Encoding::Gamma(1.0),
        ..WhittedOptions::default()
    };
    let camera = scene
        .camera
        .unwrap_or_else(|| Camera::fit(&scene.mesh.bounds(), 45.0, w as f32 / h as f32));
    let env = Environment::Sky;
    let accel = build_accel(
        AccelKind::Bvh4,
        TestKind::Moller,
        &scene.mesh,
        &BuildOptions::default(),
    );
    let ws = WhittedScene::new(
        &scene.mesh,
        accel.as_ref(),
        TestKind::Moller,
        &scene.lights,
        &env,
    );
    let cpu = render_whitted(&ws, &camera, &opts, &|_, _| {}).unwrap();
    let g = GpuScene::build(
        gpu(),
        &scene.mesh,
        GpuAccelKind::BvhThreaded,
        TestKind::Moller,
        &BuildOptions::default(),
    )
    .unwrap();
    let ss = ShadeScene {
        mesh: &scene.mesh,
        lights: &scene.lights,
        environment: &env,
    };
    let case = format!("{} lights, {integrator:?}", scene.lights.len());
    match render_whitted_gpu(gpu(), &g, &ss, &camera, &opts, &|_, _| {}) {
        Ok(frame) => {
            // A ray at a silhouette may round to the other side of it: a
            // few pixels may differ (tests/render.rs explains each one).
            let close = |a: f32, b: f32| (a - b).abs() <= 1e-3 * a.abs().max(b.abs()).max(1.0);
            let differ: Vec<usize> = cpu
                .image
                .linear
                .iter()
                .zip(&frame.frame.image.linear)
                .enumerate()
                .filter(|(_, (a, b))| !(close(a.x, b.x) && close(a.y, b.y) && close(a.z, b.z)))
                .map(|(i, _)| i)
                .collect();
            assert!(
                differ.len() * 10 <= (w * h) as usize,
                "{case}: pixels {differ:?} differ from the CPU's"
            );
            false
        }
        Err(e) => {
            assert_refused(&e, "a pixel's rays", &case);
            true
        }
    }
}

/// `n` equal point lights at one spot under the Cornell box's ceiling,
/// together as bright as one ordinary light.
fn lights(n: usize) -> Vec<Light> {
    let b = raykit_scene::builtin("cornell").unwrap().mesh.bounds();
    let c = b.center();
    let at = Vec3::new(c.x, b.max.y - 0.1 * b.diagonal(), c.z);
    vec![
        Light::Point(PointLight::with_irradiance_at(
            at,
            Vec3::splat(0.8 / n as f32),
            0.5 * b.diagonal(),
        ));
        n
    ]
}

#[test]
fn renders_past_the_loop_limit_are_exact_or_refused() {
    // 70,000 lights: each shaded hit makes 70,000 passes of the lights
    // loop, past lavapipe's 65,535.
    for integrator in [IntegratorKind::Recursive, IntegratorKind::Wavefront] {
        let refused = render_exact_or_refused(lights(70_000), integrator, false);
        if is_lavapipe() {
            assert!(
                refused,
                "{integrator:?}: lavapipe's loop limit went unnoticed"
            );
        }
    }
}

#[test]
fn ordinary_renders_are_not_refused() {
    for integrator in [IntegratorKind::Recursive, IntegratorKind::Wavefront] {
        let refused = render_exact_or_refused(lights(3), integrator, true);
        assert!(!refused, "{integrator:?}: an ordinary render was refused");
    }
}

/// A strip of `cells` cells along x, one cell wide, rising 1 cm per cell,
/// and a one-pixel camera whose ray runs up the strip parallel to the
/// surface, 5 mm above it: it misses, after the maximum-mipmap walk has
/// gone down to every cell (each cell's maximum, at its far edge, is above
/// the ray's height at its near edge) and the boxes' march has crossed
/// them all.
fn rising_strip(cells: usize) -> (HeightField, TerrainCamera) {
    let w = cells + 1;
    let row: Vec<f32> = (0..w).map(|c| 0.01 * c as f32).collect();
    let heights = [row.clone(), row].concat();
    let field = HeightField::new(&Dem::from_heights(w, 2, heights)).unwrap();
    let eye = [0.5, -0.5, 0.01];
    let camera = TerrainCamera {
        eye,
        target: [eye[0] + 1000.0, eye[1], eye[2] + 10.0],
        vfov_deg: 10.0,
        width: 1,
        height: 1,
    };
    (field, camera)
}

/// The GPU casters' answers on `cells` cells of the rising strip: the
/// CPU's, or the loop limit error; returns whether each caster (maximum
/// mipmap, boxes) refused.
fn terrain_exact_or_refused(cells: usize) -> [bool; 2] {
    let (field, camera) = rising_strip(cells);
    let pyramid = MaxMipmap::new(&field);
    let terrain = GpuTerrain::new(gpu(), &field, &pyramid).unwrap();
    let cpu = cast_image(&field, &pyramid, &camera, Caster::MaxMipmap);
    assert_eq!(cpu.hits, [None], "the ray runs above the strip");
    [GpuCaster::MaxMipmap, GpuCaster::Boxes { tau: 16.0 }].map(|caster| {
        let case = format!("{cells} cells, {caster:?}");
        match terrain.cast(gpu(), &field, &pyramid, &camera, caster) {
            Ok(got) => {
                assert_eq!(got.hits, cpu.hits, "{case}: differs from the CPU");
                false
            }
            Err(e) => {
                assert_refused(&e, "a ray's march over the DEM", &case);
                true
            }
        }
    })
}

#[test]
fn terrain_casts_past_the_loop_limit_are_exact_or_refused() {
    // 60,000 cells: the maximum-mipmap walk visits each cell's node and
    // climbs back up between them, well over 65,535 loop passes.
    let [maxmip, _] = terrain_exact_or_refused(60_000);
    if is_lavapipe() {
        assert!(maxmip, "lavapipe's loop limit went unnoticed");
    }
}

#[test]
fn ordinary_terrain_casts_are_not_refused() {
    assert_eq!(terrain_exact_or_refused(1_000), [false, false]);
}
