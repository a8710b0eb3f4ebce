//! The Purcell-style stream tracer's shadow maps against their independent reference: shadow
//! rays through a BVH (`Accel::occluded`, as the renderer casts them), and
//! the analytic shadow of a plate.

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::rng::Pcg32;
use raykit_core::tri::TestKind;
use raykit_core::{Accel, Camera, Light, PointLight, Ray, TriangleMesh, Vec3};
use raykit_render::shadow_bias;
use raykit_render::shadowmap::{ShadowMapOptions, ShadowMaps};

/// The renderer's shadow ray: from the point offset along the normal towards
/// the light, stopping just short of it.
fn ray_lit(accel: &dyn Accel, mesh: &TriangleMesh, light: &Light, p: Vec3, n: Vec3) -> bool {
    let ls = light.toward(p);
    let origin = p + n * shadow_bias(mesh);
    let ray = Ray::segment(origin, ls.to_light, 0.0, ls.distance * (1.0 - 1e-4));
    !accel.occluded(&ray)
}

/// Two unit tangents of the plane with normal `n`.
fn tangents(n: Vec3) -> (Vec3, Vec3) {
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let t1 = n.cross(a).normalize();
    (t1, n.cross(t1))
}

/// Surface points seen by `camera` that face `light` (and lie in its cone):
/// (point, unit geometric normal facing the camera).
fn seen_points(
    accel: &dyn Accel,
    mesh: &TriangleMesh,
    camera: &Camera,
    light: &Light,
    (w, h): (u32, u32),
) -> Vec<(Vec3, Vec3)> {
    let rays = camera.rays(w, h);
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let ray = rays.pixel(x, y);
            let Some(hit) = accel.intersect(&ray) else {
                continue;
            };
            let p = ray.at(hit.t);
            let mut n = mesh.face_normal(hit.prim as usize).normalize_or_zero();
            if n.dot(ray.dir()) > 0.0 {
                n = -n;
            }
            let ls = light.toward(p);
            if n.dot(ls.to_light) > 0.05 && ls.irradiance.max_element() > 0.0 {
                out.push((p, n));
            }
        }
    }
    out
}

/// Agreement of the maps with shadow rays on the points seen by `camera`,
/// excluding points within `margin` of a shadow boundary (a shadow ray from a
/// point displaced by `margin` disagrees). Returns (agreeing, compared,
/// excluded, shadowed among compared).
fn agreement(
    mesh: &TriangleMesh,
    light: Light,
    camera: &Camera,
    opts: &ShadowMapOptions,
    margin: &dyn Fn(Vec3) -> f32,
) -> (usize, usize, usize, usize) {
    let accel = build_accel(
        AccelKind::Bvh2,
        TestKind::Moller,
        mesh,
        &BuildOptions::default(),
    );
    let maps = ShadowMaps::build(mesh, &[light], opts);
    let (mut agree, mut compared, mut excluded, mut shadowed) = (0, 0, 0, 0);
    for (p, n) in seen_points(accel.as_ref(), mesh, camera, &light, (160, 120)) {
        let lit = ray_lit(accel.as_ref(), mesh, &light, p, n);
        let (t1, t2) = tangents(n);
        let m = margin(p);
        let near_boundary = (0..8).any(|k| {
            let a = k as f32 * std::f32::consts::FRAC_PI_4;
            let q = p + (t1 * a.cos() + t2 * a.sin()) * m;
            ray_lit(accel.as_ref(), mesh, &light, q, n) != lit
        });
        if near_boundary {
            excluded += 1;
            continue;
        }
        compared += 1;
        shadowed += !lit as usize;
        let v = maps.visibility(0, p, n);
        assert!((0.0..=1.0).contains(&v));
        agree += ((v >= 0.5) == lit) as usize;
    }
    (agree, compared, excluded, shadowed)
}

fn check_agreement(
    name: &str,
    mesh: &TriangleMesh,
    light: Light,
    camera: &Camera,
    texel: &dyn Fn(Vec3) -> f32,
) {
    for pcf in [3, 1] {
        let opts = ShadowMapOptions {
            pcf,
            ..ShadowMapOptions::for_mesh(mesh)
        };
        let margin = |p: Vec3| 3.0 * texel(p);
        let (agree, compared, excluded, shadowed) = agreement(mesh, light, camera, &opts, &margin);
        eprintln!(
            "{name} pcf {pcf}: {agree} of {compared} agree ({} disagree), {excluded} excluded near boundaries, {shadowed} in shadow",
            compared - agree
        );
        assert!(
            compared > 2000 && shadowed > 100,
            "{name}: test not meaningful"
        );
        assert!(excluded * 5 < compared, "{name}: too many excluded");
        assert!(
            agree as f64 > 0.99 * compared as f64,
            "{name} pcf {pcf}: {agree} of {compared}"
        );
    }
}

#[test]
fn shadow_maps_agree_with_shadow_rays() {
    let res = ShadowMapOptions::default().resolution as f32;
    let scene = raykit_scene::builtin("shirley6").unwrap();
    let camera = scene.camera.unwrap();
    let diag = scene.mesh.bounds().diagonal();
    // Directional light: texels of at most ~diag/res.
    let sun = Light::Directional {
        direction: Vec3::new(-0.4, -1.0, -0.3).normalize(),
        irradiance: Vec3::ONE,
    };
    check_agreement("shirley6 directional", &scene.mesh, sun, &camera, &|_| {
        1.5 * diag / res
    });
    // Spot light, 40° outer cone.
    let pos = Vec3::new(1.0, 9.0, 3.0);
    let spot = Light::Spot {
        position: pos,
        direction: (Vec3::new(0.0, 0.0, -2.0) - pos).normalize(),
        intensity: Vec3::ONE,
        cos_inner: 30f32.to_radians().cos(),
        cos_outer: 40f32.to_radians().cos(),
    };
    let tan = 40f32.to_radians().tan();
    check_agreement("shirley6 spot", &scene.mesh, spot, &camera, &|p| {
        2.5 * (p - pos).length() * tan / res
    });
    // The scene's point light, and the Cornell box's (inside the box).
    for name in ["shirley6", "cornell"] {
        let scene = raykit_scene::builtin(name).unwrap();
        let light = scene.lights[0];
        let pos = light.position().unwrap();
        check_agreement(
            &format!("{name} point"),
            &scene.mesh,
            light,
            &scene.camera.unwrap(),
            &|p| 3.0 * (p - pos).length() / res,
        );
    }
}

/// A quad with corners `c ± a ± b`.
fn quad(positions: &mut Vec<Vec3>, indices: &mut Vec<[u32; 3]>, c: Vec3, a: Vec3, b: Vec3) {
    let i = positions.len() as u32;
    positions.extend([c - a - b, c + a - b, c + a + b, c - a + b]);
    indices.extend([[i, i + 1, i + 2], [i, i + 2, i + 3]]);
}

#[test]
fn pcf_is_fractional_only_near_the_plate_shadow_edge_and_monotone_across_it() {
    let (mut p, mut ix) = (Vec::new(), Vec::new());
    quad(&mut p, &mut ix, Vec3::ZERO, Vec3::X * 6.0, Vec3::Z * 6.0);
    quad(&mut p, &mut ix, Vec3::Y, Vec3::X, Vec3::Z);
    let mesh = TriangleMesh::new(p, ix);
    let dir = Vec3::new(0.35, -1.0, 0.15).normalize();
    let light = Light::Directional {
        direction: dir,
        irradiance: Vec3::ONE,
    };
    let res = 256;
    let opts = ShadowMapOptions {
        resolution: res,
        ..ShadowMapOptions::for_mesh(&mesh)
    };
    let maps = ShadowMaps::build(&mesh, &[light], &opts);
    // The plate at height 1 casts the square [-1, 1]² shifted by `shift`.
    let shift = Vec3::new(dir.x, 0.0, dir.z) / -dir.y;
    let texel = 1.5 * mesh.bounds().diagonal() / res as f32;
    let reach = (opts.pcf as f32 * 0.5 + 1.0) * std::f32::consts::SQRT_2 * texel;
    let mut rng = Pcg32::new(7);
    let (mut fractional, mut shadowed) = (0, 0);
    for _ in 0..20000 {
        let g = Vec3::new(rng.range_f32(-5.0, 5.0), 0.0, rng.range_f32(-5.0, 5.0));
        let v = maps.visibility(0, g, Vec3::Y);
        let q = g - shift;
        // Distance to the boundary of the shadow square.
        let out = Vec3::new((q.x.abs() - 1.0).max(0.0), 0.0, (q.z.abs() - 1.0).max(0.0)).length();
        let inside = (1.0 - q.x.abs()).min(1.0 - q.z.abs());
        let dist = if inside > 0.0 { inside } else { out };
        if dist > reach {
            assert_eq!(
                v,
                if inside > 0.0 { 0.0 } else { 1.0 },
                "at {g} ({dist} from the edge)"
            );
        }
        fractional += (v > 0.0 && v < 1.0) as usize;
        shadowed += (v == 0.0) as usize;
    }
    assert!(fractional > 0 && shadowed > 100);
    // Monotone across each edge, walking outwards on lines perpendicular to it.
    for (axis, sign) in [
        (Vec3::X, 1.0),
        (Vec3::X, -1.0),
        (Vec3::Z, 1.0),
        (Vec3::Z, -1.0),
    ] {
        let along = Vec3::new(axis.z, 0.0, axis.x);
        for k in 0..5 {
            let offset = along * (-0.8 + 0.4 * k as f32);
            let mut last = -1.0f32;
            let mut seen_fraction = false;
            for s in 0..400 {
                let d = -5.0 * texel + s as f32 * (10.0 * texel / 400.0);
                let g = shift + offset + axis * sign * (1.0 + d);
                let v = maps.visibility(0, g, Vec3::Y);
                assert!(v >= last, "not monotone at {g}: {v} after {last}");
                seen_fraction |= v > 0.0 && v < 1.0;
                last = v;
            }
            assert_eq!(last, 1.0);
            assert!(seen_fraction, "no filtered step across the edge");
        }
    }
}

#[test]
fn no_acne_on_a_lone_tilted_plane() {
    for tilt_deg in [0.0f32, 30.0, 60.0, 80.0] {
        let t = tilt_deg.to_radians();
        let n = Vec3::new(t.sin(), t.cos(), 0.0);
        let (a, b) = (Vec3::new(t.cos(), -t.sin(), 0.0) * 3.0, Vec3::Z * 3.0);
        let (mut p, mut ix) = (Vec::new(), Vec::new());
        quad(&mut p, &mut ix, Vec3::new(0.3, 0.2, -0.1), a, b);
        let mesh = TriangleMesh::new(p, ix);
        let lights = [
            Light::Directional {
                direction: -Vec3::Y,
                irradiance: Vec3::ONE,
            },
            Light::Spot {
                position: Vec3::new(0.0, 8.0, 0.0),
                direction: -Vec3::Y,
                intensity: Vec3::ONE,
                cos_inner: 0.9,
                cos_outer: 0.8,
            },
            Light::Point(PointLight::new(Vec3::new(1.0, 5.0, 2.0), Vec3::ONE)),
        ];
        let maps = ShadowMaps::build(&mesh, &lights, &ShadowMapOptions::for_mesh(&mesh));
        let mut rng = Pcg32::new(3);
        for (i, light) in lights.iter().enumerate() {
            let mut tested = 0;
            for _ in 0..20000 {
                let (s, r) = (rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
                let q = Vec3::new(0.3, 0.2, -0.1) + a * s + b * r;
                let ls = light.toward(q);
                if n.dot(ls.to_light) <= 0.0 || ls.irradiance.max_element() <= 0.0 {
                    continue;
                }
                tested += 1;
                let v = maps.visibility(i, q, n);
                assert_eq!(
                    v,
                    1.0,
                    "tilt {tilt_deg}, {}: acne at {q}",
                    light.kind_name()
                );
            }
            assert!(tested > 1000, "tilt {tilt_deg} {}", light.kind_name());
        }
    }
}

#[test]
fn degenerate_inputs_do_not_panic() {
    let empty = TriangleMesh::new(Vec::new(), Vec::new());
    let scene = raykit_scene::builtin("cornell").unwrap();
    let inside = scene.mesh.bounds().center();
    let lights = [
        Light::Directional {
            direction: Vec3::ZERO,
            irradiance: Vec3::ONE,
        },
        Light::Point(PointLight::new(Vec3::splat(f32::NAN), Vec3::ONE)),
        Light::Point(PointLight::new(inside, Vec3::ONE)),
        Light::Point(PointLight::new(scene.mesh.triangle(0)[0], Vec3::ONE)),
        Light::Spot {
            position: inside,
            direction: Vec3::Y,
            intensity: Vec3::ONE,
            cos_inner: -1.0,
            cos_outer: -2.0,
        },
    ];
    for opts in [
        ShadowMapOptions {
            resolution: 0,
            pcf: 0,
            bias_constant: f32::NAN,
            bias_slope: -1.0,
        },
        ShadowMapOptions {
            resolution: 64,
            pcf: 100,
            ..ShadowMapOptions::default()
        },
    ] {
        for mesh in [&empty, &scene.mesh] {
            let maps = ShadowMaps::build(mesh, &lights, &opts);
            assert_eq!(maps.len(), lights.len());
            assert!(maps.memory_bytes() > 0);
            for i in 0..lights.len() + 1 {
                for p in [
                    inside,
                    Vec3::splat(f32::NAN),
                    Vec3::splat(1e30),
                    lights[3].position().unwrap(),
                ] {
                    for n in [Vec3::Y, Vec3::ZERO, Vec3::splat(f32::INFINITY)] {
                        let v = maps.visibility(i, p, n);
                        assert!((0.0..=1.0).contains(&v), "{v}");
                    }
                }
            }
        }
    }
}

/// Build times of the Purcell-style stream tracer's shadow maps (the Cornell box's point light,
/// a directional light on the dragon) at the default resolution and at
/// 2048; run with `cargo test --release -p raykit-render --test shadowmap
/// -- --ignored --nocapture`. Prints, asserts nothing about time.
#[test]
#[ignore]
fn build_times() {
    let cornell = raykit_scene::builtin("cornell").unwrap();
    let mut cases = vec![("cornell point", cornell.mesh, cornell.lights[0])];
    let dragon = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/meshes/dragon_vrip_res2.ply.gz");
    if dragon.exists() {
        let sun = Light::Directional {
            direction: Vec3::new(-0.4, -1.0, -0.3).normalize(),
            irradiance: Vec3::ONE,
        };
        cases.push((
            "dragon directional",
            raykit_io::load_mesh(&dragon).unwrap(),
            sun,
        ));
    }
    for (name, mesh, light) in &cases {
        for res in [ShadowMapOptions::default().resolution, 2048] {
            let opts = ShadowMapOptions {
                resolution: res,
                ..ShadowMapOptions::for_mesh(mesh)
            };
            for _ in 0..3 {
                let start = std::time::Instant::now();
                let maps = ShadowMaps::build(mesh, &[*light], &opts);
                eprintln!(
                    "{name}: {} tris, {res}²: build {:.1} ms, {:.1} MiB",
                    mesh.num_triangles(),
                    start.elapsed().as_secs_f64() * 1e3,
                    maps.memory_bytes() as f64 / (1 << 20) as f64
                );
            }
        }
    }
}
