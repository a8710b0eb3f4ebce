//! The built-in Whitted scene (mirror and glass spheres) rendered as a
//! user renders it: a binary BVH with Möller's test, the sky, the scene's
//! own lights and camera.

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_core::Accel;
use raykit_render::env::Environment;
use raykit_render::whitted::{render_whitted, Frame, WhittedOptions, WhittedScene};
use raykit_scene::Scene;

/// The built-in Whitted scene and its binary BVH with Möller's test.
pub fn whitted_scene() -> (Scene, Box<dyn Accel>) {
    let scene = raykit_scene::whitted(1);
    let accel = build_accel(
        AccelKind::Bvh2,
        TestKind::Moller,
        &scene.mesh,
        &BuildOptions::default(),
    );
    (scene, accel)
}

/// The built-in Whitted scene's frame with `opts`.
pub fn whitted_frame(opts: &WhittedOptions) -> Frame {
    let (scene, accel) = whitted_scene();
    let env = Environment::Sky;
    let ws = WhittedScene::new(
        &scene.mesh,
        accel.as_ref(),
        TestKind::Moller,
        &scene.lights,
        &env,
    );
    render_whitted(&ws, &scene.camera.unwrap(), opts, &|_, _| {}).unwrap()
}
