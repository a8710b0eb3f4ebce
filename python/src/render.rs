//! `render`: a scene's triangles through raykit-render's one-bounce
//! Blinn-Phong renderer with shadow rays, as an `(h, w, 3)` uint8 image.

use crate::errors::value_error;
use crate::scene::Scene;
use crate::threads::detached;
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3};
use pyo3::prelude::*;
use raykit_core::raysets::standard_light;
use raykit_core::{Camera, Light, PointLight, Vec3};
use raykit_render::{RenderOptions, Tile};

/// Render `scene` (its structure is reused) through a pinhole camera at
/// `eye` looking at `target` (default: the scene's bounding box centre)
/// with vertical field of view `fov` degrees; without `eye`, the camera
/// frames the triangles as `raykit render` frames a mesh. One white point
/// light above the scene, as the command line's default. `window =
/// (x, y, w, h)` renders only that rectangle of the frame (pixels equal to
/// the whole frame's), as an `(h, w, 3)` image.
#[pyfunction]
#[pyo3(signature = (scene, width=800, height=600, eye=None, target=None, up=(0.0, 1.0, 0.0), fov=40.0, samples_per_pixel=1, shadows=true, threads=0, window=None))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
    py: Python<'py>,
    scene: &Scene,
    width: i64,
    height: i64,
    eye: Option<(f32, f32, f32)>,
    target: Option<(f32, f32, f32)>,
    up: (f32, f32, f32),
    fov: f32,
    samples_per_pixel: i64,
    shadows: bool,
    threads: i64,
    window: Option<(u32, u32, u32, u32)>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let built = scene.read();
    let Some(accel) = built.accel() else {
        return Err(value_error("the scene has no triangles to render"));
    };
    if !(1..=16384).contains(&width) || !(1..=16384).contains(&height) {
        return Err(value_error(format!(
            "width and height must be between 1 and 16384, got {width} x {height}"
        )));
    }
    let (width, height) = (width as u32, height as u32);
    if !(1.0..179.0).contains(&fov) {
        return Err(value_error(format!(
            "fov must be between 1 and 179 degrees, got {fov}"
        )));
    }
    if !(1..=4096).contains(&samples_per_pixel) {
        return Err(value_error(format!(
            "samples_per_pixel must be between 1 and 4096, got {samples_per_pixel}"
        )));
    }
    let samples_per_pixel = samples_per_pixel as u32;
    let window = match window {
        None => Tile::whole(width, height),
        Some((x, y, w, h)) => {
            let t = Tile {
                x,
                y,
                width: w,
                height: h,
            };
            if w == 0 || h == 0 || t.clipped(width, height) != t {
                return Err(value_error(format!(
                    "window ({x}, {y}, {w}, {h}) must be a non-empty rectangle inside the {width} x {height} frame"
                )));
            }
            t
        }
    };
    let mesh = &built.mesh;
    let bounds = mesh.bounds();
    let v = |t: (f32, f32, f32)| Vec3::new(t.0, t.1, t.2);
    let camera = match eye {
        Some(e) => Camera {
            eye: v(e),
            target: target.map_or(bounds.center(), v),
            up: v(up),
            vfov_deg: fov,
        },
        None => {
            let mut c =
                Camera::fit_points(&bounds, &mesh.positions, fov, width as f32 / height as f32);
            if let Some(t) = target {
                c.target = v(t);
            }
            c
        }
    };
    if !(camera.eye.is_finite()
        && camera.target.is_finite()
        && (camera.target - camera.eye).normalize().is_finite())
    {
        return Err(value_error(format!(
            "eye {} and target {} must be finite and differ (the camera needs a direction to look in)",
            camera.eye, camera.target
        )));
    }
    if !camera.up.is_finite() {
        return Err(value_error(format!(
            "up must be three finite numbers, got {}",
            camera.up
        )));
    }
    let p = standard_light(&bounds);
    let lights: Vec<Light> =
        vec![PointLight::with_irradiance_at(p, Vec3::ONE, p.distance(bounds.center())).into()];
    let options = RenderOptions {
        width,
        height,
        samples_per_pixel,
        shadows,
        window: Some(window),
        ..RenderOptions::default()
    };
    let image = detached(py, threads, || {
        raykit_render::render(mesh, &lights, accel, &camera, &options, &|_| {})
    })?;
    let rgb = Array3::from_shape_vec((image.height as usize, image.width as usize, 3), image.rgb)
        .expect("three bytes a pixel");
    Ok(rgb.into_pyarray(py))
}
