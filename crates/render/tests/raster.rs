//! The rasterized visibility buffer (hybrid rendering: rasterized first hits, traced rays after) against
//! its independent reference: tracing the same rays through a BVH.

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::rng::Pcg32 as Rng;
use raykit_core::tri::{TestKind, TriangleTest};
use raykit_core::{with_test, Camera, Hit, Ray, TriangleMesh, Vec3};
use raykit_render::raster::{primary_visibility, visibility};
use std::path::Path;
use std::time::Instant;

/// Hit of `ray` with triangle `prim` alone, by the test `test`.
fn hit_one(mesh: &TriangleMesh, test: TestKind, prim: u32, ray: &Ray) -> Option<f32> {
    let [a, b, c] = mesh.triangle(prim as usize);
    with_test!(test, T => {
        T::intersect(&T::precompute(a, b, c), ray, &T::prepare(ray), f32::INFINITY).map(|h| h.t)
    })
}

/// A genuine tie: both triangles hit by the ray, at distances a few ulps apart.
fn is_tie(mesh: &TriangleMesh, test: TestKind, ray: &Ray, a: &Hit, b: &Hit) -> bool {
    let (ta, tb) = match (
        hit_one(mesh, test, a.prim, ray),
        hit_one(mesh, test, b.prim, ray),
    ) {
        (Some(ta), Some(tb)) => (ta, tb),
        _ => return false,
    };
    let ulp = f32::EPSILON * ta.abs().max(tb.abs());
    (ta - tb).abs() <= 4.0 * ulp && (a.t - b.t).abs() <= 4.0 * ulp
}

/// Compare the visibility buffer with `Bvh2::intersect` of the same rays for
/// every triangle test; returns the number of tie pixels (all tests).
fn compare(
    name: &str,
    mesh: &TriangleMesh,
    camera: &Camera,
    (w, h): (u32, u32),
    sample: &(dyn Fn(u32, u32) -> Ray + Sync),
) -> usize {
    let mut ties_all = 0;
    for test in TestKind::ALL {
        let accel = build_accel(AccelKind::Bvh2, test, mesh, &BuildOptions::default());
        let raster = visibility(mesh, test, camera, w, h, sample);
        assert_eq!(raster.len(), (w * h) as usize);
        let (mut ties, mut hits) = (0, 0);
        for y in 0..h {
            for x in 0..w {
                let ray = sample(x, y);
                let traced = accel.intersect(&ray);
                let got = raster[(y * w + x) as usize];
                hits += traced.is_some() as usize;
                if got == traced {
                    continue;
                }
                match (got, traced) {
                    (Some(g), Some(t)) if is_tie(mesh, test, &ray, &g, &t) => ties += 1,
                    _ => panic!(
                        "{name} {}: pixel ({x}, {y}) raster {got:?} traced {traced:?}",
                        test.name()
                    ),
                }
            }
        }
        eprintln!(
            "{name} {}: {hits} hit pixels of {}, {ties} ties",
            test.name(),
            w * h
        );
        assert!(hits > 0, "{name}: nothing visible");
        assert!(
            ties * 50 <= (w * h) as usize,
            "{name} {}: {ties} ties",
            test.name()
        );
        ties_all += ties;
    }
    ties_all
}

/// Pixel-centre rays and jittered rays of `camera`.
fn both_samplings(name: &str, mesh: &TriangleMesh, camera: &Camera, (w, h): (u32, u32)) {
    let rays = camera.rays(w, h);
    compare(name, mesh, camera, (w, h), &|x, y| rays.pixel(x, y));
    let jitter = |x: u32, y: u32| {
        let mut rng = Rng::new(u64::from(y) << 32 | u64::from(x));
        // Anywhere in the pixel, corners included.
        let (fx, fy) = (rng.next_f32(), rng.next_f32());
        rays.ray(x as f32 + fx, y as f32 + fy)
    };
    compare(&format!("{name} jittered"), mesh, camera, (w, h), &jitter);
    let corners = |x: u32, y: u32| rays.ray(x as f32 + (x % 2) as f32, y as f32 + (y % 2) as f32);
    compare(&format!("{name} corners"), mesh, camera, (w, h), &corners);
}

fn bunny() -> TriangleMesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/meshes/bunny_3674.obj");
    raykit_io::load_mesh(&path).expect("bunny mesh")
}

#[test]
fn cornell_from_inside_the_box_matches_traced_rays() {
    let scene = raykit_scene::builtin("cornell").unwrap();
    let b = scene.mesh.bounds();
    let c = b.center();
    // Inside the box, near a wall, looking across: the walls behind and
    // beside the eye cross its plane.
    let camera = Camera {
        eye: c + b.extent() * Vec3::new(0.3, 0.2, -0.2),
        target: c - b.extent() * Vec3::new(0.3, 0.1, 0.0),
        up: Vec3::Y,
        vfov_deg: 100.0,
    };
    assert!(b.contains(camera.eye));
    both_samplings("cornell inside", &scene.mesh, &camera, (96, 64));
    // And the scene's own camera.
    both_samplings("cornell", &scene.mesh, &scene.camera.unwrap(), (80, 60));
}

#[test]
fn shirley6_matches_traced_rays() {
    let scene = raykit_scene::builtin("shirley6").unwrap();
    let camera = scene.camera_or_framing(45.0);
    both_samplings("shirley6", &scene.mesh, &camera, (96, 72));
}

#[test]
fn bunny_matches_traced_rays() {
    let mesh = bunny();
    let camera = Camera::fit(&mesh.bounds(), 40.0, 4.0 / 3.0);
    both_samplings("bunny", &mesh, &camera, (160, 120));
    // Close up, the eye inside the bounding box.
    let b = mesh.bounds();
    let close = Camera {
        eye: b.center() + b.extent() * Vec3::new(0.1, 0.1, 0.45),
        target: b.center(),
        up: Vec3::Y,
        vfov_deg: 90.0,
    };
    both_samplings("bunny close", &mesh, &close, (100, 80));
}

#[test]
fn degenerate_inputs_do_not_panic() {
    let scene = raykit_scene::builtin("cornell").unwrap();
    let cam = scene.camera.unwrap();
    for (w, h) in [(0, 0), (0, 5), (5, 0), (1, 1), (1, 7)] {
        let v = primary_visibility(&scene.mesh, TestKind::Moller, &cam, w, h);
        assert_eq!(v.len(), (w * h) as usize);
    }
    // Degenerate and non-finite triangles, a triangle through the eye.
    let p = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::X * 2.0,
        Vec3::new(f32::NAN, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 5.0),
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
    ];
    let mesh = TriangleMesh::new(
        p,
        vec![[0, 1, 2], [0, 3, 1], [0, 0, 0], [4, 5, 6], [4, 4, 5]],
    );
    let eye_on = Camera {
        eye: Vec3::new(0.0, 0.0, 5.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        vfov_deg: 60.0,
    };
    for camera in [
        eye_on,
        Camera {
            vfov_deg: 179.0,
            ..eye_on
        },
        Camera {
            target: eye_on.eye,
            ..eye_on
        },
    ] {
        let accel = build_accel(
            AccelKind::Bvh2,
            TestKind::Moller,
            &mesh,
            &BuildOptions::default(),
        );
        let v = primary_visibility(&mesh, TestKind::Moller, &camera, 20, 10);
        let rays = camera.rays(20, 10);
        for (i, got) in v.iter().enumerate() {
            let ray = rays.pixel(i as u32 % 20, i as u32 / 20);
            assert_eq!(got.map(|h| h.prim), accel.intersect(&ray).map(|h| h.prim));
        }
    }
}

fn time<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let start = Instant::now();
    let r = f();
    (r, start.elapsed().as_secs_f64() * 1e3)
}

/// Timing of the rasterizer against traced primaries (the Purcell-style stream tracer reports
/// 1.6× for one pass); run with `cargo test --release -p raykit-render
/// --test raster -- --ignored --nocapture`. Prints, asserts nothing about
/// time.
#[test]
#[ignore]
fn speed_against_traced_primaries() {
    let dragon =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/meshes/dragon_vrip_res2.ply.gz");
    let mut scenes = vec![(
        "cornell".to_string(),
        raykit_scene::builtin("cornell").unwrap().mesh,
        raykit_scene::builtin("cornell").unwrap().camera,
    )];
    if dragon.exists() {
        scenes.push((
            "dragon_res2".into(),
            raykit_io::load_mesh(&dragon).unwrap(),
            None,
        ));
    }
    for ((name, mesh, camera), (w, h)) in scenes
        .iter()
        .flat_map(|s| [(s, (512u32, 512u32)), (s, (1280, 720))])
    {
        let camera =
            camera.unwrap_or_else(|| Camera::fit(&mesh.bounds(), 40.0, w as f32 / h as f32));
        let test = TestKind::Moller;
        let (accel, build_ms) =
            time(|| build_accel(AccelKind::Bvh2, test, mesh, &BuildOptions::default()));
        let rays = camera.rays(w, h);
        for _ in 0..2 {
            let (raster, raster_ms) = time(|| primary_visibility(mesh, test, &camera, w, h));
            let (ray_list, gen_ms) = time(|| {
                (0..h)
                    .flat_map(|y| (0..w).map(move |x| (x, y)))
                    .map(|(x, y)| rays.pixel(x, y))
                    .collect::<Vec<_>>()
            });
            let mut traced = vec![None; ray_list.len()];
            let ((), trace_ms) = time(|| accel.intersect_batch(&ray_list, &mut traced));
            let same = raster.iter().zip(&traced).filter(|(a, b)| a == b).count();
            eprintln!(
                "{name}: {} tris, {w}x{h}: raster {raster_ms:.1} ms, rays {gen_ms:.1} ms + intersect_batch {trace_ms:.1} ms (bvh build {build_ms:.0} ms), speed-up {:.2}x; identical pixels {same}/{}",
                mesh.num_triangles(),
                (gen_ms + trace_ms) / raster_ms,
                raster.len()
            );
        }
    }
}
