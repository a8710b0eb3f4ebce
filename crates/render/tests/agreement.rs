//! The renderer's output does not depend on the acceleration structure (up to
//! ties), on the number of threads, or on anything but its inputs.

use raykit_core::accel::{build_accel, AccelKind, BruteForce, BuildOptions};
use raykit_core::tri::{Moller, TestKind};
use raykit_render::{primary_hits, render, Image, RenderOptions};
use raykit_scene::{builtin, Scene};
use std::sync::atomic::{AtomicU64, Ordering};

fn opts(width: u32, height: u32, spp: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        samples_per_pixel: spp,
        ..RenderOptions::default()
    }
}

fn draw(scene: &Scene, kind: AccelKind, test: TestKind, o: &RenderOptions) -> Image {
    let accel = build_accel(kind, test, &scene.mesh, &BuildOptions::default());
    let cam = scene.camera.unwrap();
    render(&scene.mesh, &scene.lights, accel.as_ref(), &cam, o, &|_| {})
}

#[test]
fn bvh_and_brute_force_give_the_same_image_up_to_ties() {
    for spec in ["cornell", "scatter:triangles=4000"] {
        let scene = builtin(spec).unwrap();
        let o = opts(80, 60, 1);
        let cam = scene.camera.unwrap();
        // Möller–Trumbore; the other tests are checked against it in core.
        let test = TestKind::Moller;
        {
            let brute = draw(&scene, AccelKind::Brute, test, &o);
            let bvh = draw(&scene, AccelKind::Bvh2, test, &o);
            let hb = primary_hits(
                build_accel(
                    AccelKind::Brute,
                    test,
                    &scene.mesh,
                    &BuildOptions::default(),
                )
                .as_ref(),
                &cam,
                80,
                60,
            );
            let hv = primary_hits(
                build_accel(AccelKind::Bvh2, test, &scene.mesh, &BuildOptions::default()).as_ref(),
                &cam,
                80,
                60,
            );
            let mut ties = 0;
            for (i, (a, b)) in hb.iter().zip(&hv).enumerate() {
                let same_prim = a.map(|h| h.prim) == b.map(|h| h.prim);
                if same_prim {
                    assert_eq!(brute.linear[i], bvh.linear[i], "{spec} {test:?} pixel {i}");
                    assert_eq!(brute.rgb[3 * i..3 * i + 3], bvh.rgb[3 * i..3 * i + 3]);
                } else {
                    // A tie: both hit, at the same distance, on different triangles.
                    let (Some(a), Some(b)) = (a, b) else {
                        panic!("{spec} {test:?} pixel {i}: brute {a:?}, bvh {b:?}")
                    };
                    assert!(
                        (a.t - b.t).abs() <= 1e-5 * a.t,
                        "{spec} pixel {i}: {a:?} {b:?}"
                    );
                    ties += 1;
                }
            }
            assert!(ties < hb.len() / 100, "{spec} {test:?}: {ties} ties");
            assert!(hb.iter().filter(|h| h.is_some()).count() > hb.len() / 10);
        }
    }
}

#[test]
fn primary_hits_match_single_ray_queries() {
    let scene = builtin("shirley6").unwrap();
    let accel = BruteForce::<Moller>::new(&scene.mesh);
    let cam = scene.camera.unwrap();
    let hits = primary_hits(&accel, &cam, 20, 15);
    let rays = cam.rays(20, 15);
    for y in 0..15 {
        for x in 0..20 {
            use raykit_core::Accel;
            assert_eq!(
                hits[(y * 20 + x) as usize],
                accel.intersect(&rays.pixel(x, y))
            );
        }
    }
}

#[test]
fn jittered_render_is_deterministic_across_thread_counts() {
    let scene = builtin("cornell").unwrap();
    let accel = BruteForce::<Moller>::new(&scene.mesh);
    let cam = scene.camera.unwrap();
    let o = opts(45, 35, 4);
    let pixels = AtomicU64::new(0);
    let calls = AtomicU64::new(0);
    let progress = |n: u64| {
        pixels.fetch_add(n, Ordering::Relaxed);
        calls.fetch_add(1, Ordering::Relaxed);
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(&scene.mesh, &scene.lights, &accel, &cam, &o, &progress))
    };
    let a = run(1);
    let b = run(3);
    assert_eq!(a, b);
    assert_eq!(a, run(2));
    assert_eq!(pixels.load(Ordering::Relaxed), 3 * 45 * 35);
    assert_eq!(
        calls.load(Ordering::Relaxed),
        3 * 2 * 2,
        "one call per 32x32 tile"
    );
    assert_eq!(a.rgb.len(), 45 * 35 * 3);

    // The jitter does something, and the seed changes it.
    let centre = render(
        &scene.mesh,
        &scene.lights,
        &accel,
        &cam,
        &opts(45, 35, 1),
        &|_| {},
    );
    assert_ne!(a.rgb, centre.rgb);
    let reseeded = RenderOptions {
        seed: 9,
        ..o.clone()
    };
    let c = render(&scene.mesh, &scene.lights, &accel, &cam, &reseeded, &|_| {});
    assert_ne!(a.rgb, c.rgb);
    // Anti-aliasing only moves edge pixels: most stay close.
    let close = a
        .rgb
        .iter()
        .zip(&centre.rgb)
        .filter(|(p, q)| p.abs_diff(**q) <= 3)
        .count();
    assert!(close > a.rgb.len() * 8 / 10);
}

#[test]
fn empty_and_degenerate_sizes() {
    let scene = builtin("shirley6").unwrap();
    let accel = BruteForce::<Moller>::new(&scene.mesh);
    let cam = scene.camera.unwrap();
    let img = render(
        &scene.mesh,
        &scene.lights,
        &accel,
        &cam,
        &opts(0, 0, 1),
        &|_| {},
    );
    assert!(img.rgb.is_empty() && img.linear.is_empty());
    let img = render(
        &scene.mesh,
        &scene.lights,
        &accel,
        &cam,
        &opts(1, 1, 0),
        &|_| {},
    );
    assert_eq!(img.rgb.len(), 3);
}

/// `scene` shrunk by the power of two `f`: positions, camera and lights,
/// with the lights' intensities scaled by `f²` so that their `1/d²`
/// falloff gives the same irradiance.
fn shrunk(scene: &Scene, f: f32) -> Scene {
    use raykit_core::Light;
    let mut s = scene.clone();
    for p in &mut s.mesh.positions {
        *p *= f;
    }
    if let Some(c) = &mut s.camera {
        c.eye *= f;
        c.target *= f;
    }
    for l in &mut s.lights {
        match l {
            Light::Point(p) => {
                p.position *= f;
                p.intensity *= f * f;
            }
            Light::Spot {
                position,
                intensity,
                ..
            } => {
                *position *= f;
                *intensity *= f * f;
            }
            Light::Directional { .. } => {}
        }
    }
    s
}

/// A scene nanometres across and far smaller renders as at its own size:
/// the structures work at unit scale, shadow rays start at an offset of
/// the scene's scale, and normals are found where `f32`'s cross products
/// of such edges underflow. Before, the shrunk Cornell box lost every
/// shadow and its shading.
#[test]
fn a_tiny_scene_renders_as_at_its_own_size() {
    let scene = builtin("cornell").unwrap();
    let o = opts(64, 48, 1);
    let want = draw(&scene, AccelKind::Bvh8, TestKind::Moller, &o);
    for e in [30, 60] {
        let tiny = shrunk(&scene, 2f32.powi(-e));
        let got = draw(&tiny, AccelKind::Bvh8, TestKind::Moller, &o);
        let mut off = 0;
        for (a, b) in want.linear.iter().zip(&got.linear) {
            if (*a - *b).abs().max_element() > 1e-4 * a.abs().max_element().max(1e-3) {
                off += 1;
            }
        }
        // Pixels on a shared edge may take the other triangle.
        assert!(
            off <= want.linear.len() / 200,
            "2^-{e}: {off} pixels differ"
        );
    }
}
