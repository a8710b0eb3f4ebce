//! Pixel values recomputed independently in f64: camera rays, ray/triangle
//! hits, Blinn-Phong with 1/d² point lights, hard shadows and sRGB encoding.

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::glam::{Affine3A, DVec3, Quat, Vec3};
use raykit_core::tri::TestKind;
use raykit_core::{Camera, TriangleMesh};
use raykit_render::{render, Image, RenderOptions};
use raykit_scene::{material, MeshBuilder, PointLight};

fn d(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

/// Unit direction of the ray through the centre of pixel (x, y).
fn camera_dir(cam: &Camera, w: u32, h: u32, x: u32, y: u32) -> DVec3 {
    let forward = (d(cam.target) - d(cam.eye)).normalize();
    let right = forward.cross(d(cam.up)).normalize();
    let up = right.cross(forward);
    let t = (cam.vfov_deg as f64).to_radians().mul_add(0.5, 0.0).tan();
    let sx = 2.0 * (x as f64 + 0.5) / w as f64 - 1.0;
    let sy = 1.0 - 2.0 * (y as f64 + 0.5) / h as f64;
    (forward + right * (t * w as f64 / h as f64 * sx) + up * (t * sy)).normalize()
}

/// Ray/triangle by Cramer's rule: (t, u, v) with the point
/// (1-u-v)a + ub + vc, for t > tmin.
fn hit_triangle(o: DVec3, dir: DVec3, [a, b, c]: [DVec3; 3], tmin: f64) -> Option<(f64, f64, f64)> {
    let (e1, e2) = (b - a, c - a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-14 {
        return None;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > tmin).then_some((t, u, v))
}

fn srgb(x: f64) -> i32 {
    let x = x.clamp(0.0, 1.0);
    let y = if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (y * 255.0).round() as i32
}

fn assert_pixel(img: &Image, x: u32, y: u32, expected: DVec3, what: &str) {
    let got = img.pixel(x, y);
    for k in 0..3 {
        let e = srgb(expected[k]);
        assert!(
            (got[k] as i32 - e).abs() <= 1,
            "{what} pixel ({x}, {y}): got {got:?}, expected {:?} from {expected}",
            [srgb(expected.x), srgb(expected.y), srgb(expected.z)]
        );
    }
}

/// Everything the reference shading needs, in f64.
struct Reference<'a> {
    mesh: &'a TriangleMesh,
    lights: &'a [PointLight],
    ambient: f64,
    shadows: bool,
}

impl Reference<'_> {
    fn tri(&self, i: usize) -> [DVec3; 3] {
        self.mesh.triangle(i).map(d)
    }

    /// Nearest hit, or None; also None (skip) when near a triangle edge.
    fn nearest(&self, o: DVec3, dir: DVec3) -> Option<Option<(usize, f64, f64, f64)>> {
        let mut best: Option<(usize, f64, f64, f64)> = None;
        for i in 0..self.mesh.num_triangles() {
            if let Some((t, u, v)) = hit_triangle(o, dir, self.tri(i), 1e-9) {
                if best.is_none_or(|b| t < b.1) {
                    best = Some((i, t, u, v));
                }
            }
        }
        match best {
            Some((_, _, u, v)) if u.min(v).min(1.0 - u - v) < 1e-3 => None,
            b => Some(b),
        }
    }

    /// Is the segment from p to the light blocked (p's own triangle excluded
    /// by t > 1e-7)?
    fn blocked(&self, p: DVec3, light: DVec3) -> bool {
        let dir = light - p;
        (0..self.mesh.num_triangles())
            .any(|i| hit_triangle(p, dir, self.tri(i), 1e-7).is_some_and(|(t, _, _)| t < 1.0))
    }

    /// Blinn-Phong radiance of the hit (i, u, v) seen along unit `dir`.
    fn shade(&self, dir: DVec3, (i, _t, u, v): (usize, f64, f64, f64)) -> DVec3 {
        let [a, b, c] = self.tri(i);
        let w = 1.0 - u - v;
        let p = a * w + b * u + c * v;
        let mut ng = (b - a).cross(c - a).normalize();
        if ng.dot(dir) > 0.0 {
            ng = -ng;
        }
        let nv = self.mesh.normals.as_ref().unwrap();
        let [i0, i1, i2] = self.mesh.indices[i].map(|k| d(nv[k as usize]));
        let mut n = (i0 * w + i1 * u + i2 * v).normalize();
        if n.dot(ng) < 0.0 {
            n = -n;
        }
        let m = &self.mesh.materials[self.mesh.tri_material[i] as usize];
        let kd = DVec3::from(m.diffuse.map(f64::from));
        let ks = DVec3::from(m.specular.map(f64::from));
        let mut out = kd * self.ambient;
        for light in self.lights {
            let lp = d(light.position);
            let l = (lp - p).normalize();
            if n.dot(l) <= 0.0 || ng.dot(l) <= 0.0 || (self.shadows && self.blocked(p, lp)) {
                continue;
            }
            let h = (l - dir).normalize();
            let e = d(light.intensity) / (lp - p).length_squared();
            out += e * (kd * n.dot(l) + ks * n.dot(h).max(0.0).powf(m.shininess as f64));
        }
        out
    }
}

fn draw(mesh: &TriangleMesh, lights: &[PointLight], cam: &Camera, o: &RenderOptions) -> Image {
    let accel = build_accel(
        AccelKind::Bvh2,
        TestKind::Moller,
        mesh,
        &BuildOptions::default(),
    );
    let lights: Vec<raykit_scene::Light> = lights.iter().map(|&l| l.into()).collect();
    render(mesh, &lights, accel.as_ref(), cam, o, &|_| {})
}

#[test]
fn blinn_phong_with_interpolated_normals_matches_f64() {
    let mut b = MeshBuilder::new();
    let floor = b.add_material(material("floor", [0.6, 0.5, 0.4], 0.3, 20.0));
    let smooth = b.add_material(material("smooth", [0.2, 0.5, 0.7], 0.5, 60.0));
    b.add_quad(
        [
            Vec3::new(-5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, -5.0),
            Vec3::new(-5.0, 0.0, -5.0),
        ],
        floor,
    );
    // A triangle standing up, with three different vertex normals.
    let v = [
        b.push_vertex(Vec3::new(-3.0, 0.5, -1.0), Vec3::new(-0.5, 0.2, 1.0)),
        b.push_vertex(Vec3::new(1.0, 0.5, -2.0), Vec3::new(0.6, 0.1, 1.0)),
        b.push_vertex(Vec3::new(-1.0, 3.5, -1.5), Vec3::new(0.0, 0.9, 0.6)),
    ];
    b.push_triangle(v, smooth);
    let mesh = b.finish();
    let lights = [
        PointLight::new(Vec3::new(2.0, 6.0, 4.0), Vec3::new(30.0, 27.0, 24.0)),
        PointLight::new(Vec3::new(-4.0, 2.0, 3.0), Vec3::new(5.0, 5.0, 8.0)),
    ];
    let cam = Camera {
        eye: Vec3::new(0.5, 3.0, 8.0),
        target: Vec3::new(0.0, 0.5, 0.0),
        up: Vec3::Y,
        vfov_deg: 50.0,
    };
    let o = RenderOptions {
        width: 48,
        height: 36,
        ambient: Vec3::splat(0.05),
        ..RenderOptions::default()
    };
    let img = draw(&mesh, &lights, &cam, &o);
    let reference = Reference {
        mesh: &mesh,
        lights: &lights,
        ambient: 0.05,
        shadows: true,
    };
    let (mut checked, mut on_triangle) = (0, 0);
    for y in 0..o.height {
        for x in 0..o.width {
            let dir = camera_dir(&cam, o.width, o.height, x, y);
            let Some(Some(hit)) = reference.nearest(d(cam.eye), dir) else {
                continue;
            };
            assert_pixel(&img, x, y, reference.shade(dir, hit), "shading");
            checked += 1;
            on_triangle += (hit.0 == 2) as u32;
        }
    }
    assert!(
        checked > 1000 && on_triangle > 50,
        "{checked} {on_triangle}"
    );
}

#[test]
fn shadow_of_a_box_is_ambient_only_and_the_rest_is_lit() {
    let mut b = MeshBuilder::new();
    let floor = b.add_material(material("floor", [0.7, 0.7, 0.7], 0.2, 10.0));
    let grey = b.add_material(material("box", [0.5, 0.5, 0.5], 0.0, 1.0));
    b.add_quad(
        [
            Vec3::new(-10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, -10.0),
            Vec3::new(-10.0, 0.0, -10.0),
        ],
        floor,
    );
    // A box floating over the floor: |x|, |z| <= 1, 3 <= y <= 4.
    b.add_box(
        Affine3A::from_scale_rotation_translation(
            Vec3::new(2.0, 1.0, 2.0),
            Quat::IDENTITY,
            Vec3::new(0.0, 3.5, 0.0),
        ),
        grey,
    );
    let mesh = b.finish();
    let light = PointLight::new(Vec3::new(0.0, 10.0, 0.0), Vec3::splat(60.0));
    let lights = [light];
    // Below the box, so floor rays cannot hit it on the way.
    let cam = Camera {
        eye: Vec3::new(0.0, 2.5, 7.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        vfov_deg: 40.0,
    };
    let ambient = 0.08;
    let o = RenderOptions {
        width: 64,
        height: 48,
        ambient: Vec3::splat(ambient as f32),
        ..RenderOptions::default()
    };
    let img = draw(&mesh, &lights, &cam, &o);
    let unshadowed = draw(
        &mesh,
        &lights,
        &cam,
        &RenderOptions {
            shadows: false,
            ..o.clone()
        },
    );

    // The shadow is the top face (y = 4) projected from the light onto y = 0:
    // |x|, |z| < 10 / (10 - 4) = 1.667.
    let kd = 0.7;
    let reference = Reference {
        mesh: &mesh,
        lights: &lights,
        ambient,
        shadows: false,
    };
    let (mut dark, mut lit) = (0, 0);
    for y in 0..o.height {
        for x in 0..o.width {
            let dir = camera_dir(&cam, o.width, o.height, x, y);
            if dir.y >= 0.0 {
                continue;
            }
            let t = -2.5 / dir.y;
            let p = d(cam.eye) + dir * t;
            let r = p.x.abs().max(p.z.abs());
            if r < 1.5 {
                assert_pixel(&img, x, y, DVec3::splat(ambient * kd), "shadowed");
                let Some(Some(hit)) = reference.nearest(d(cam.eye), dir) else {
                    continue;
                };
                assert_pixel(&unshadowed, x, y, reference.shade(dir, hit), "shadows off");
                assert!(unshadowed.pixel(x, y)[0] > img.pixel(x, y)[0] + 50);
                dark += 1;
            } else if r > 1.85 && r < 9.5 {
                // Lit: ambient plus the light, recomputed by hand for the plane.
                let l = d(light.position) - p;
                let (dist2, l) = (l.length_squared(), l.normalize());
                let n = DVec3::Y;
                let h = (l - dir).normalize();
                let e = 60.0 / dist2;
                let expected =
                    ambient * kd + e * (kd * n.dot(l) + 0.2 * n.dot(h).max(0.0).powf(10.0));
                assert_pixel(&img, x, y, DVec3::splat(expected), "lit");
                lit += 1;
            }
        }
    }
    assert!(dark >= 20 && lit >= 200, "dark {dark}, lit {lit}");
}

#[test]
fn a_concave_corner_facing_the_light_is_lit_along_its_edge() {
    // A floor (y = 0) meeting a wall (z = -2), the light in front of both:
    // no point either face shows is in shadow, so every pixel must equal
    // the render without shadows. The camera looks at a point of the edge
    // with its right axis along the edge, so the middle row of an image of
    // odd height sees the edge itself, where each shadow ray starts in the
    // other face's plane.
    let mut b = MeshBuilder::new();
    let grey = b.add_material(material("grey", [0.6, 0.6, 0.6], 0.2, 10.0));
    b.add_quad(
        [
            Vec3::new(-5.0, 0.0, 6.0),
            Vec3::new(5.0, 0.0, 6.0),
            Vec3::new(5.0, 0.0, -2.0),
            Vec3::new(-5.0, 0.0, -2.0),
        ],
        grey,
    );
    b.add_quad(
        [
            Vec3::new(-5.0, 0.0, -2.0),
            Vec3::new(5.0, 0.0, -2.0),
            Vec3::new(5.0, 6.0, -2.0),
            Vec3::new(-5.0, 6.0, -2.0),
        ],
        grey,
    );
    let mesh = b.finish();
    let lights = [PointLight::new(Vec3::new(0.3, 4.0, 4.0), Vec3::splat(40.0))];
    let cam = Camera {
        eye: Vec3::new(0.0, 3.0, 5.0),
        target: Vec3::new(0.0, 0.0, -2.0),
        up: Vec3::Y,
        vfov_deg: 40.0,
    };
    let o = RenderOptions {
        width: 41,
        height: 31,
        ambient: Vec3::splat(0.05),
        ..RenderOptions::default()
    };
    let img = draw(&mesh, &lights, &cam, &o);
    let unshadowed = draw(
        &mesh,
        &lights,
        &cam,
        &RenderOptions {
            shadows: false,
            ..o.clone()
        },
    );
    let mut on_edge = 0;
    for y in 0..o.height {
        for x in 0..o.width {
            let dir = camera_dir(&cam, o.width, o.height, x, y);
            // Where the pixel's ray meets the floor's plane, in f64.
            let p = d(cam.eye) + dir * (-3.0 / dir.y);
            on_edge += ((p.z + 2.0).abs() < 1e-4) as u32;
            assert_eq!(
                img.pixel(x, y),
                unshadowed.pixel(x, y),
                "pixel ({x}, {y}), {:.6} from the edge",
                p.z + 2.0
            );
        }
    }
    assert!(on_edge >= o.width / 2, "{on_edge} pixels on the edge");
}
