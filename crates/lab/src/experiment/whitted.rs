//! `raykit experiment whitted`: time per frame for {traced, rasterized primaries} × {shadow rays, shadow maps}
//! × {recursive, wavefront} × passes 1 and 2, with the speed-ups next to the
//! 1.6× (1 pass) and 1.2× (2 passes) that GPU hybrid renderers reported, and the image differences
//! between the variants; and the environment box against environment
//! mapping at 5 bounces.

use super::{shared_data, shared_mesh, write_csv, write_text};
use crate::args::scene::{setup, RenderSetup, SceneArgs};
use crate::measure::{median_ms, pool, spread_percent, timed};
use anyhow::{Context, Result};
use clap::Args;
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_render::scene_setup::SceneOptions;
use raykit_render::shadowmap::{ShadowMapOptions, ShadowMaps};
use raykit_render::whitted::{
    render_whitted, Frame, IntegratorKind, PrimaryMode, ShadowMode, WhittedOptions, WhittedScene,
};
use raykit_render::Image;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Arguments of `raykit experiment whitted`.
#[derive(Args)]
#[command(
    after_help = "Scenes: whitted (the built-in Cornell box with a mirror and a glass sphere),\n\
dragon (the 202k-triangle dragon in plastic — diffuse with reflectivity 0.08 — in the courtyard\n\
HDR map, environment box) and engine (the 2CylinderEngine glTF assembly, 121k triangles, its\n\
materials given reflectivity 0.1, two lights), all from the repository's data/ folder: every\n\
scene casts shadow rays and reflection rays. Then the environment table: the 11k-triangle\n\
glass dragon (dragon_vrip_res4) in the courtyard map at depth 5, environment box against\n\
environment mapping. Writes results.md, results.csv, results.json and the images compared into --out."
)]
pub struct WhittedExperimentArgs {
    /// Scenes to run: whitted, dragon, engine.
    #[arg(long, value_delimiter = ',', default_value = "whitted,dragon,engine")]
    scenes: Vec<String>,
    /// Image width.
    #[arg(long, default_value_t = 512)]
    width: u32,
    /// Image height.
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// Repetitions per configuration (medians are reported).
    #[arg(long, default_value_t = 5)]
    reps: usize,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Output folder.
    #[arg(long, default_value = "experiments/whitted")]
    out: PathBuf,
    /// Leave out the environment box against environment mapping table.
    #[arg(long)]
    skip_env_table: bool,
}

#[derive(Serialize, Clone)]
struct Row {
    scene: String,
    triangles: usize,
    primary: String,
    shadows: String,
    integrator: String,
    passes: u32,
    ms: f64,
    noise: Option<f64>,
    raster_ms: f64,
    /// Rays traced per frame, millions.
    rays_millions: f64,
}

#[derive(Serialize)]
struct SceneSummary {
    scene: String,
    triangles: usize,
    lights: usize,
    build_ms: f64,
    shadow_map_ms: f64,
    shadow_map_mib: f64,
    maps_vs_rays_pixels_differing_pct: f64,
    maps_vs_rays_rmse: f64,
    raster_vs_traced_pixels_differing: usize,
    wavefront_vs_recursive_pixels_differing: usize,
}

/// Reflectivity given to the engine assembly's materials.
const ENGINE_REFLECTIVITY: f32 = 0.1;

/// The scene arguments of one named experiment scene.
fn scene_args(name: &str) -> Result<SceneArgs> {
    let mut a = SceneArgs::new(String::new(), SceneOptions::default());
    match name {
        "whitted" => a.scene = "builtin:whitted".into(),
        "dragon" => {
            a.scene = shared_mesh("dragon_vrip_res2.ply.gz");
            a.material = Some("plastic".into());
            a.env = shared_data()
                .join("envmaps/courtyard.exr")
                .to_string_lossy()
                .into_owned();
            a.env_box = true;
            a.light = vec!["dir:-0.4,-1,-0.5:0.9,0.85,0.8".into()];
        }
        "engine" => {
            a.scene = shared_mesh("2CylinderEngine.glb");
            a.light = vec![
                "dir:-0.3,-1,-0.6:0.8,0.8,0.8".into(),
                "dir:0.6,-0.4,0.7:0.3,0.3,0.35".into(),
            ];
        }
        _ => anyhow::bail!("unknown scene '{name}': expected whitted, dragon or engine"),
    }
    Ok(a)
}

/// An image of |a − b| × 4, for looking at where two renders differ.
fn difference_png(path: &Path, a: &Image, b: &Image) -> Result<()> {
    raykit_io::write_png(path, a.width, a.height, &a.difference_rgb(b))?;
    Ok(())
}

fn run_scene(
    args: &WhittedExperimentArgs,
    name: &str,
    rows: &mut Vec<Row>,
) -> Result<SceneSummary> {
    let sa = scene_args(name)?;
    let RenderSetup {
        mut scene,
        camera,
        lights,
        environment,
    } = setup(&sa, args.width as f32 / args.height as f32)
        .with_context(|| format!("scene {name}"))?;
    if name == "engine" {
        // The assembly's own materials are matte: a little reflectivity
        // makes the second pass trace reflection rays.
        for m in &mut scene.mesh.materials {
            m.reflectivity = m.reflectivity.max(ENGINE_REFLECTIVITY);
        }
    }
    let mesh = &scene.mesh;
    let (accel, build_s) = timed(|| {
        build_accel(
            AccelKind::Bvh2,
            TestKind::Moller,
            mesh,
            &BuildOptions::default(),
        )
    });
    let map_opts = ShadowMapOptions::for_mesh(mesh);
    let mut map_times = Vec::new();
    let mut maps = None;
    for _ in 0..args.reps.max(1) {
        let (m, s) = timed(|| ShadowMaps::build(mesh, &lights, &map_opts));
        map_times.push(s);
        maps = Some(m);
    }
    let maps = maps.expect("at least one build");
    let ws = WhittedScene::new(
        mesh,
        accel.as_ref(),
        TestKind::Moller,
        &lights,
        &environment,
    )
    .with_shadow_maps(Some(&maps));
    let mut keep: Vec<(String, Frame)> = Vec::new();
    for passes in [1u32, 2] {
        for shadows in [ShadowMode::Rays, ShadowMode::Maps] {
            for primary in [PrimaryMode::Traced, PrimaryMode::Rasterized] {
                for integrator in [IntegratorKind::Recursive, IntegratorKind::Wavefront] {
                    let opts = WhittedOptions {
                        width: args.width,
                        height: args.height,
                        max_depth: passes,
                        shadows,
                        primary,
                        integrator,
                        ..WhittedOptions::default()
                    };
                    let mut times = Vec::new();
                    let mut raster = Vec::new();
                    let mut last = None;
                    for _ in 0..args.reps.max(1) {
                        let f = render_whitted(&ws, &camera, &opts, &|_, _| {})?;
                        times.push(f.stats.seconds);
                        raster.push(f.stats.raster_seconds);
                        last = Some(f);
                    }
                    let f = last.expect("at least one frame");
                    let (ms, noise) = median_ms(&times);
                    let label = |m: &dyn std::fmt::Debug| format!("{m:?}").to_lowercase();
                    rows.push(Row {
                        scene: name.into(),
                        triangles: mesh.num_triangles(),
                        primary: label(&primary),
                        shadows: label(&shadows),
                        integrator: label(&integrator),
                        passes,
                        ms,
                        noise,
                        raster_ms: median_ms(&raster).0,
                        rays_millions: f.stats.rays() as f64 / 1e6,
                    });
                    eprintln!(
                        "{name}: {passes} pass(es), {:?} shadows, {:?}, {:?}: {ms:.1} ms (noise {})",
                        shadows,
                        primary,
                        integrator,
                        spread_percent(noise)
                    );
                    if passes == 2 {
                        keep.push((format!("{shadows:?}-{primary:?}-{integrator:?}"), f));
                    }
                }
            }
        }
    }
    let get = |k: &str| &keep.iter().find(|(n, _)| n == k).expect("rendered").1;
    let rays = get("Rays-Traced-Recursive");
    let maps_img = get("Maps-Traced-Recursive");
    let (diff, rmse) = rays.image.difference(&maps_img.image);
    let raster = get("Rays-Rasterized-Recursive");
    let wave = get("Rays-Traced-Wavefront");
    for (suffix, img) in [("rays", &rays.image), ("maps", &maps_img.image)] {
        raykit_io::write_png(
            &args.out.join(format!("{name}-{suffix}.png")),
            img.width,
            img.height,
            &img.rgb,
        )?;
    }
    difference_png(
        &args.out.join(format!("{name}-rays-vs-maps-x4.png")),
        &rays.image,
        &maps_img.image,
    )?;
    let pixels = (args.width * args.height) as f64;
    Ok(SceneSummary {
        scene: name.into(),
        triangles: mesh.num_triangles(),
        lights: lights.len(),
        build_ms: build_s * 1e3,
        shadow_map_ms: median_ms(&map_times).0,
        shadow_map_mib: maps.memory_bytes() as f64 / (1 << 20) as f64,
        maps_vs_rays_pixels_differing_pct: 100.0 * diff as f64 / pixels,
        maps_vs_rays_rmse: rmse,
        raster_vs_traced_pixels_differing: rays.image.difference(&raster.image).0,
        wavefront_vs_recursive_pixels_differing: rays.image.difference(&wave.image).0,
    })
}

/// The pairs of rows, alike but for the passes or but for the shadow
/// test, that traced the same number of rays: comparisons of identical work.
fn identical_ray_counts(rows: &[Row]) -> Vec<String> {
    let mut out = Vec::new();
    for (i, a) in rows.iter().enumerate() {
        for b in &rows[i + 1..] {
            let same_setting =
                a.scene == b.scene && a.primary == b.primary && a.integrator == b.integrator;
            let one_apart = (a.passes != b.passes) != (a.shadows != b.shadows);
            if same_setting && one_apart && a.rays_millions == b.rays_millions {
                out.push(format!(
                    "{} {} primaries {}: {} pass(es) {} shadows and {} pass(es) {} shadows ({:.2} M rays)",
                    a.scene,
                    a.primary,
                    a.integrator,
                    a.passes,
                    a.shadows,
                    b.passes,
                    b.shadows,
                    a.rays_millions
                ));
            }
        }
    }
    out
}

/// Median over rows matching `f` of the ratio traced / rasterized.
fn speedup(
    rows: &[Row],
    scene: &str,
    passes: u32,
    num: &str,
    den: &str,
    field: fn(&Row) -> &str,
) -> f64 {
    let mut ratios = Vec::new();
    for a in rows
        .iter()
        .filter(|r| r.scene == scene && r.passes == passes && field(r) == num)
    {
        let b = rows.iter().find(|b| {
            b.scene == scene
                && b.passes == passes
                && field(b) == den
                && [
                    (&a.primary, &b.primary),
                    (&a.shadows, &b.shadows),
                    (&a.integrator, &b.integrator),
                ]
                .iter()
                .filter(|(x, y)| x != y)
                .count()
                    == 1
        });
        if let Some(b) = b {
            ratios.push(a.ms / b.ms.max(1e-9));
        }
    }
    crate::measure::median_min_max(&ratios).0
}

/// Run every scene and write the report.
pub fn run(args: WhittedExperimentArgs) -> Result<ExitCode> {
    if args.width == 0 || args.height == 0 || args.width > 8192 || args.height > 8192 {
        anyhow::bail!("--width and --height must be between 1 and 8192");
    }
    crate::args::ranges::reps(args.reps)?;
    // Every scene name is checked before any scene renders or writes.
    for name in &args.scenes {
        scene_args(name)?;
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let pool = pool(args.threads)?;
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let mut rows = Vec::new();
    let mut summaries = Vec::new();
    for name in &args.scenes {
        summaries.push(pool.install(|| run_scene(&args, name, &mut rows))?);
    }
    let env = if args.skip_env_table {
        None
    } else {
        Some(pool.install(|| {
            super::whitted_env::env_table(args.width, args.height, args.reps, &args.out)
        })?)
    };
    let same_work = identical_ray_counts(&rows);
    for s in &same_work {
        eprintln!("same rays: {s}");
    }
    write_csv(&args.out, "results.csv", &rows)?;
    write_text(
        &args.out,
        "results.json",
        &serde_json::to_string_pretty(&serde_json::json!({
            "command": command,
            "rows": rows,
            "scenes": summaries,
            "environment": env,
            "identical_ray_counts": same_work,
        }))?,
    )?;
    let mut md = format!(
        "# Whitted experiment: traced against rasterized primaries on this CPU ({} threads)\n\n`{command}`\n\n\
         {}×{} pixels, 1 sample per pixel, median of {} frames. Passes: 1 = camera ray + shadow tests, \
         2 = plus one reflection/refraction ray. Shadow-map frames exclude the map build (listed below). \
         rays (M): rays traced per frame, in millions.\n\n\
         | scene | triangles | passes | shadows | primaries | integrator | ms | noise | raster ms | rays (M) |\n\
         |---|---:|---:|---|---|---|---:|---:|---:|---:|\n",
        rayon::current_num_threads(),
        args.width,
        args.height,
        args.reps
    );
    for r in &rows {
        md += &format!(
            "| {} | {} | {} | {} | {} | {} | {:.1} | {} | {:.1} | {:.2} |\n",
            r.scene,
            r.triangles,
            r.passes,
            r.shadows,
            r.primary,
            r.integrator,
            r.ms,
            spread_percent(r.noise),
            r.raster_ms,
            r.rays_millions
        );
    }
    md += "\n## Speed-ups (median over the other settings)\n\n\
           | scene | passes | rasterized over traced primaries | reported on the GPU | shadow maps over shadow rays | wavefront over recursive |\n\
           |---|---:|---:|---:|---:|---:|\n";
    for s in &summaries {
        for (passes, paper) in [(1, 1.6), (2, 1.2)] {
            md += &format!(
                "| {} | {passes} | {:.2}× | {paper}× | {:.2}× | {:.2}× |\n",
                s.scene,
                speedup(&rows, &s.scene, passes, "traced", "rasterized", |r| &r
                    .primary),
                speedup(&rows, &s.scene, passes, "rays", "maps", |r| &r.shadows),
                speedup(&rows, &s.scene, passes, "recursive", "wavefront", |r| &r
                    .integrator),
            );
        }
    }
    md += "\n## Scenes, shadow maps and image differences (2 passes)\n\n\
           | scene | triangles | lights | BVH build ms | shadow-map build ms | maps MiB | maps vs rays: pixels differing, % | maps vs rays: RMSE of linear radiance | rasterized vs traced: pixels differing, count | wavefront vs recursive: pixels differing, count |\n\
           |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for s in &summaries {
        md += &format!(
            "| {} | {} | {} | {:.0} | {:.0} | {:.1} | {:.2}% | {:.4} | {} | {} |\n",
            s.scene,
            s.triangles,
            s.lights,
            s.build_ms,
            s.shadow_map_ms,
            s.shadow_map_mib,
            s.maps_vs_rays_pixels_differing_pct,
            s.maps_vs_rays_rmse,
            s.raster_vs_traced_pixels_differing,
            s.wavefront_vs_recursive_pixels_differing
        );
    }
    md += "\nPixels differing: some channel off by more than 2 of 255. Images: SCENE-rays.png, SCENE-maps.png, \
           SCENE-rays-vs-maps-x4.png (difference × 4).\n";
    if let Some(env) = &env {
        md += &super::whitted_env::markdown(env, args.reps);
    }
    md += "\n## Check: compared configurations trace different rays\n\n\
           1 against 2 passes, and shadow rays against shadow maps, with the other settings equal, \
           must trace different numbers of rays, or the comparison measures identical work.\n\n";
    if same_work.is_empty() {
        md += "Every such pair traces a different number of rays.\n";
    } else {
        for s in &same_work {
            md += &format!("- identical ray counts: {s}\n");
        }
    }
    write_text(&args.out, "results.md", &md)?;
    print!("{md}");
    Ok(if same_work.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
