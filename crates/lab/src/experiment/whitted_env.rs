//! The environment table of `raykit experiment whitted`: the environment
//! box of the Purcell-style stream tracer (rays that leave the scene hit a
//! box around it, with parallax and the ground) against environment
//! mapping (a direction lookup), at 5 bounces — time per frame and how much
//! the images differ.

use super::{shared_data, shared_mesh};
use crate::args::scene::{setup, RenderSetup, SceneArgs};
use crate::measure::{median_ms, spread_percent};
use anyhow::{Context, Result};
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_core::Vec3;
use raykit_render::whitted::{render_whitted, WhittedOptions, WhittedScene};
use raykit_render::Image;
use serde::Serialize;
use std::path::Path;

/// Rays per path, camera ray included.
const DEPTH: u32 = 5;

/// One environment's frame time.
#[derive(Serialize)]
pub struct EnvRow {
    /// "box" or "map".
    pub environment: String,
    /// Triangles of the scene.
    pub triangles: usize,
    /// Median frame time.
    pub ms: f64,
    /// Spread (max − min) over the median.
    pub noise: Option<f64>,
    /// Rays traced per frame, millions.
    pub rays_millions: f64,
    /// Paths that ended in the environment, millions.
    pub environment_hits_millions: f64,
}

/// The two rows and the difference between their images.
#[derive(Serialize)]
pub struct EnvTable {
    /// Environment box, then environment map.
    pub rows: Vec<EnvRow>,
    /// Pixels with a channel more than 2 of 255 apart, percent.
    pub pixels_differing_pct: f64,
    /// RMSE of the linear radiance.
    pub rmse: f64,
}

fn scene_args(env_box: bool) -> SceneArgs {
    SceneArgs {
        scene: shared_mesh("dragon_vrip_res4.ply.gz"),
        eye: None,
        target: None,
        up: Vec3::Y,
        fov: None,
        light: vec!["dir:-0.4,-1,-0.5:0.9,0.85,0.8".into()],
        env: shared_data()
            .join("envmaps/courtyard.exr")
            .to_string_lossy()
            .into_owned(),
        env_box,
        env_box_scale: raykit_render::env::DEFAULT_BOX_SCALE,
        env_intensity: 1.0,
        env_rotate: 0.0,
        material: Some("glass".into()),
    }
}

/// Render the glass dragon in the courtyard map with each environment,
/// `reps` frames each, on the current rayon pool; write `env-box.png`,
/// `env-map.png` and `env-box-vs-map-x4.png` into `out`.
pub fn env_table(width: u32, height: u32, reps: usize, out: &Path) -> Result<EnvTable> {
    let mut rows = Vec::new();
    let mut images: Vec<Image> = Vec::new();
    for env_box in [true, false] {
        let RenderSetup {
            scene,
            camera,
            lights,
            environment,
        } = setup(&scene_args(env_box), width as f32 / height as f32)
            .context("environment table scene")?;
        let mesh = &scene.mesh;
        let accel = build_accel(
            AccelKind::Bvh2,
            TestKind::Moller,
            mesh,
            &BuildOptions::default(),
        );
        let ws = WhittedScene::new(
            mesh,
            accel.as_ref(),
            TestKind::Moller,
            &lights,
            &environment,
        );
        let opts = WhittedOptions {
            width,
            height,
            max_depth: DEPTH,
            ..WhittedOptions::default()
        };
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..reps.max(1) {
            let f = render_whitted(&ws, &camera, &opts, &|_, _| {})?;
            times.push(f.stats.seconds);
            last = Some(f);
        }
        let f = last.expect("at least one frame");
        let (ms, noise) = median_ms(&times);
        let name = if env_box { "box" } else { "map" };
        eprintln!(
            "environment {name}: {ms:.1} ms (noise {})",
            spread_percent(noise)
        );
        rows.push(EnvRow {
            environment: name.into(),
            triangles: mesh.num_triangles(),
            ms,
            noise,
            rays_millions: f.stats.rays() as f64 / 1e6,
            environment_hits_millions: f.stats.environment_hits as f64 / 1e6,
        });
        raykit_io::write_png(
            &out.join(format!("env-{name}.png")),
            f.image.width,
            f.image.height,
            &f.image.rgb,
        )?;
        images.push(f.image);
    }
    let (differing, rmse) = images[0].difference(&images[1]);
    raykit_io::write_png(
        &out.join("env-box-vs-map-x4.png"),
        width,
        height,
        &images[0].difference_rgb(&images[1]),
    )?;
    Ok(EnvTable {
        rows,
        pixels_differing_pct: 100.0 * differing as f64 / (width * height) as f64,
        rmse,
    })
}

/// The table as a Markdown section.
pub fn markdown(t: &EnvTable, reps: usize) -> String {
    let mut md = format!(
        "\n## Environment box against environment mapping ({DEPTH} bounces)\n\n\
         The {}-triangle dragon (dragon_vrip_res4) in glass in the courtyard map, one directional \
         light, traced primaries, shadow rays, recursive integrator, depth {DEPTH} (camera ray + 4 \
         reflection/refraction bounces), median of {reps} frames. Box: rays leaving the scene hit a \
         grounded box around it; map: a direction lookup.\n\n\
         | environment | ms | noise | rays (M) | paths ending in the environment (M) |\n\
         |---|---:|---:|---:|---:|\n",
        t.rows.first().map_or(0, |r| r.triangles)
    );
    for r in &t.rows {
        md += &format!(
            "| {} | {:.1} | {} | {:.2} | {:.2} |\n",
            r.environment,
            r.ms,
            spread_percent(r.noise),
            r.rays_millions,
            r.environment_hits_millions
        );
    }
    if let [b, m] = &t.rows[..] {
        md += &format!(
            "\nBox ÷ map frame time: {:.2}×. Box vs map images: {:.2}% of pixels differ (a channel \
             more than 2 of 255), RMSE {:.4} (env-box.png, env-map.png, env-box-vs-map-x4.png).\n",
            b.ms / m.ms.max(1e-9),
            t.pixels_differing_pct,
            t.rmse
        );
    }
    md
}
