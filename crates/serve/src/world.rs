//! What every client shares: the loaded scene with its acceleration
//! structure, the lights and the default camera.

use crate::camera_control::camera_problem;
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::raysets::standard_light;
use raykit_core::tri::TestKind;
use raykit_core::{Aabb, Accel, Camera, Vec3};
use raykit_render::{Light, PointLight};
use raykit_scene::Scene;
use std::sync::Arc;

/// A scene ready to render: vertex normals filled in, a BVH built once and
/// shared by all clients.
pub struct Geometry {
    /// The scene as loaded (its own lights and camera, if any).
    pub scene: Scene,
    /// BVH over `scene.mesh`.
    pub accel: Box<dyn Accel>,
    /// Bounds of the mesh.
    pub bounds: Aabb,
    /// Load counter: a new scene gets a new number.
    pub generation: u64,
}

impl Geometry {
    /// Prepare `scene`: normals, BVH (binned SAH, Möller-Trumbore test).
    pub fn new(mut scene: Scene, generation: u64) -> Geometry {
        if scene.mesh.normals.is_none() {
            scene.mesh.compute_vertex_normals();
        }
        let accel = build_accel(
            AccelKind::Bvh2,
            TestKind::Moller,
            &scene.mesh,
            &BuildOptions::default(),
        );
        let bounds = scene.mesh.bounds();
        Geometry {
            scene,
            accel,
            bounds,
            generation,
        }
    }

    /// The scene's lights, or one white light above the mesh as `raykit
    /// render` uses.
    pub fn default_lights(&self) -> Vec<Light> {
        if !self.scene.lights.is_empty() {
            return self.scene.lights.clone();
        }
        let p = standard_light(&self.bounds);
        vec![PointLight::with_irradiance_at(p, Vec3::ONE, p.distance(self.bounds.center())).into()]
    }

    /// The scene's camera when clients could set it themselves (see
    /// [`camera_problem`]), or else one fitting the mesh for `aspect`.
    pub fn default_camera(&self, aspect: f32) -> Camera {
        self.scene
            .camera
            .filter(|c| camera_problem(c).is_none())
            .unwrap_or_else(|| {
                Camera::fit_points(&self.bounds, &self.scene.mesh.positions, 40.0, aspect)
            })
    }

    /// Scale of camera motion: the bounding-box diagonal (1 for an empty
    /// mesh).
    pub fn scale(&self) -> f32 {
        let d = self.bounds.diagonal();
        if d.is_finite() && d > 0.0 {
            d
        } else {
            1.0
        }
    }
}

/// One consistent state of the shared world; changed by replacing it.
#[derive(Clone)]
pub struct World {
    /// The loaded scene.
    pub geometry: Arc<Geometry>,
    /// Lights used for every client.
    pub lights: Vec<Light>,
    /// Camera of new clients and of MJPEG streams.
    pub camera: Camera,
    /// Full resolution of new clients and of MJPEG streams.
    pub full: (u32, u32),
    /// Incremented on every change.
    pub version: u64,
    /// Incremented when what every client sees changes (scene, lights); not
    /// for the defaults (camera, resolution) that only new clients and MJPEG
    /// streams use.
    pub look_version: u64,
}

/// The built-in Cornell box as the world of the unit tests, its camera
/// framed for `full` (width, height).
#[cfg(test)]
pub(crate) fn cornell_world(full: (u32, u32)) -> World {
    let g = Arc::new(Geometry::new(raykit_scene::builtin("cornell").unwrap(), 1));
    World {
        lights: g.default_lights(),
        camera: g.default_camera(full.0 as f32 / full.1 as f32),
        full,
        geometry: g,
        version: 1,
        look_version: 1,
    }
}
