//! `raykit experiment whitted-structures`: the acceleration table and
//! frame-rate figure of Kim et al.'s GPU stream ray tracer (its Table 1 and
//! Fig. 9) on this CPU — no acceleration, the linear BVH of eight triangles
//! per box, the complete threaded BVH built bottom-up in mesh order, and
//! for contrast the SAH-built threaded BVH — in triangle tests per ray and
//! frames per second of the Whitted renderer at 2 passes.

use super::{shared_mesh, write_csv, write_text};
use crate::args::scene::{setup, RenderSetup, SceneArgs};
use crate::measure::{median_min_max, pool, spread, spread_percent, timed};
use anyhow::{Context, Result};
use clap::Args;
use raykit_core::accel::{Accel, BruteForce, BuildOptions, LinearBoxes, ThreadedBvh};
use raykit_core::tri::{Moller, TestKind, TriHit, TriangleTest};
use raykit_core::{Ray, Vec3};
use raykit_render::whitted::{render_whitted, WhittedOptions, WhittedScene};
use serde::Serialize;
use std::cell::Cell;
use std::marker::PhantomData;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `raykit experiment whitted-structures`.
#[derive(Args)]
#[command(
    after_help = "Scenes (from the repository's data/meshes): teapot (992 triangles), bunny (3,674)\n\
and dragon (dragon_vrip_res4, 11,102), each in the plastic material (diffuse with a small\n\
reflectivity, so every hit casts shadow rays and one reflection ray) under two directional\n\
lights in the sky environment. Frames: 2 passes = camera ray + one shadow ray per light +\n\
one reflection ray, traced primaries, recursive integrator, one thread per core.\n\
Writes structures.md, structures.csv and structures.json into --out."
)]
pub struct WhittedStructuresArgs {
    /// Scenes to run: teapot, bunny, dragon.
    #[arg(long, value_delimiter = ',', default_value = "teapot,bunny,dragon")]
    scenes: Vec<String>,
    /// Image width and height.
    #[arg(long, default_value_t = 512)]
    size: u32,
    /// Timed frames per structure (the median is reported).
    #[arg(long, default_value_t = 5)]
    reps: usize,
    /// No acceleration is run only on scenes of at most this many triangles
    /// (above it a frame takes minutes here, as the paper's third scene
    /// could not run without acceleration).
    #[arg(long, default_value_t = 5000)]
    brute_max_triangles: usize,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Output folder.
    #[arg(long, default_value = "experiments/whitted")]
    out: PathBuf,
}

thread_local! {
    /// Triangle tests made on this thread by [`Counted`].
    static TRIANGLE_TESTS: Cell<u64> = const { Cell::new(0) };
}

/// A triangle test that counts its calls in a thread-local counter and
/// delegates to `T`.
struct Counted<T>(PhantomData<T>);

impl<T: TriangleTest> TriangleTest for Counted<T> {
    const NAME: &'static str = T::NAME;
    type Tri = T::Tri;
    type RayData = T::RayData;
    const WORDS: usize = T::WORDS;

    fn precompute(a: Vec3, b: Vec3, c: Vec3) -> Self::Tri {
        T::precompute(a, b, c)
    }

    fn prepare(ray: &Ray) -> Self::RayData {
        T::prepare(ray)
    }

    fn intersect(tri: &Self::Tri, ray: &Ray, rd: &Self::RayData, tfar: f32) -> Option<TriHit> {
        TRIANGLE_TESTS.with(|c| c.set(c.get() + 1));
        T::intersect(tri, ray, rd, tfar)
    }

    fn occluded(tri: &Self::Tri, ray: &Ray, rd: &Self::RayData, tfar: f32) -> bool {
        TRIANGLE_TESTS.with(|c| c.set(c.get() + 1));
        T::occluded(tri, ray, rd, tfar)
    }

    fn write_words(tri: &Self::Tri, out: &mut Vec<u32>) {
        T::write_words(tri, out)
    }
}

/// The structures compared, in the paper's order and then the contrast.
#[derive(Clone, Copy, PartialEq)]
enum Structure {
    None,
    LinearBoxes,
    CompleteBvh,
    SahThreaded,
}

impl Structure {
    const ALL: [Structure; 4] = [
        Structure::None,
        Structure::LinearBoxes,
        Structure::CompleteBvh,
        Structure::SahThreaded,
    ];

    fn name(self) -> &'static str {
        match self {
            Structure::None => "no acceleration",
            Structure::LinearBoxes => "linear BVH, 8 tris/box",
            Structure::CompleteBvh => "complete threaded BVH (paper)",
            Structure::SahThreaded => "SAH threaded BVH",
        }
    }

    fn build<T: TriangleTest>(self, mesh: &raykit_core::TriangleMesh) -> Box<dyn Accel> {
        match self {
            Structure::None => Box::new(BruteForce::<T>::new(mesh)),
            Structure::LinearBoxes => Box::new(LinearBoxes::<T>::new(mesh)),
            Structure::CompleteBvh => Box::new(ThreadedBvh::<T>::complete(mesh)),
            Structure::SahThreaded => Box::new(ThreadedBvh::<T>::build(
                mesh,
                &BuildOptions {
                    max_leaf_size: 1,
                    ..BuildOptions::default()
                },
            )),
        }
    }
}

#[derive(Serialize)]
struct Row {
    scene: String,
    triangles: usize,
    structure: String,
    /// Triangle tests per ray (camera, shadow and reflection rays).
    triangle_tests_per_ray: Option<f64>,
    /// Rays per frame, millions.
    rays_millions: f64,
    build_ms: Option<f64>,
    ms: Option<f64>,
    fps: Option<f64>,
    /// (max − min) / median of the frame times; `None` (empty in the CSV,
    /// null in the JSON) when not run or timed fewer than twice.
    noise: Option<f64>,
    nodes: Option<usize>,
}

/// The scene arguments of one named scene.
fn scene_args(name: &str) -> Result<SceneArgs> {
    let file = match name {
        "teapot" => "teapot_992.obj",
        "bunny" => "bunny_3674.obj",
        "dragon" => "dragon_vrip_res4.ply.gz",
        _ => anyhow::bail!("unknown scene '{name}': expected teapot, bunny or dragon"),
    };
    Ok(SceneArgs {
        scene: shared_mesh(file),
        eye: None,
        target: None,
        up: Vec3::Y,
        fov: None,
        light: vec![
            "dir:-0.4,-1,-0.5:0.8,0.78,0.75".into(),
            "dir:0.6,-0.5,0.4:0.35,0.35,0.4".into(),
        ],
        env: "sky".into(),
        env_box: false,
        env_box_scale: raykit_render::env::DEFAULT_BOX_SCALE,
        env_intensity: 1.0,
        env_rotate: 0.0,
        material: Some("plastic".into()),
    })
}

/// Triangle tests of every thread of `pool` and of this thread since the
/// last call, and the counters reset.
fn take_triangle_tests(pool: &rayon::ThreadPool) -> u64 {
    let here = TRIANGLE_TESTS.with(|c| c.replace(0));
    here + pool
        .broadcast(|_| TRIANGLE_TESTS.with(|c| c.replace(0)))
        .into_iter()
        .sum::<u64>()
}

fn run_scene(
    args: &WhittedStructuresArgs,
    pool: &rayon::ThreadPool,
    name: &str,
    rows: &mut Vec<Row>,
) -> Result<()> {
    let RenderSetup {
        scene,
        camera,
        lights,
        environment,
    } = setup(&scene_args(name)?, 1.0).with_context(|| format!("scene {name}"))?;
    let mesh = &scene.mesh;
    let opts = WhittedOptions {
        width: args.size,
        height: args.size,
        max_depth: 2,
        ..WhittedOptions::default()
    };
    let render = |accel: &dyn Accel| {
        let ws = WhittedScene::new(mesh, accel, TestKind::Moller, &lights, &environment);
        pool.install(|| render_whitted(&ws, &camera, &opts, &|_, _| {}))
    };
    let mut reference_rays = None;
    for s in Structure::ALL {
        if s == Structure::None && mesh.num_triangles() > args.brute_max_triangles {
            let rays = reference_rays.unwrap_or(0) as f64 / 1e6;
            rows.push(Row {
                scene: name.into(),
                triangles: mesh.num_triangles(),
                structure: s.name().into(),
                triangle_tests_per_ray: None,
                rays_millions: rays,
                build_ms: None,
                ms: None,
                fps: None,
                noise: None,
                nodes: None,
            });
            eprintln!("{name}: {}: not run (over --brute-max-triangles)", s.name());
            continue;
        }
        // One frame through the counting test, for the tests per ray.
        let counted = pool.install(|| s.build::<Counted<Moller>>(mesh));
        take_triangle_tests(pool);
        let f = render(counted.as_ref())?;
        let tests = take_triangle_tests(pool);
        drop(counted);
        let rays = f.stats.rays();
        if let Some(r) = reference_rays.filter(|&r| r != rays) {
            // Ties (two triangles at one distance) may change a hit's normal
            // and so which lights cast shadow rays.
            eprintln!(
                "{name}: {} traced {rays} rays, the previous structure {r}",
                s.name()
            );
        }
        reference_rays = Some(rays);
        // Timed frames through the plain test.
        let (accel, build_s) = timed(|| pool.install(|| s.build::<Moller>(mesh)));
        let mut times = Vec::new();
        for _ in 0..args.reps.max(1) {
            times.push(render(accel.as_ref())?.stats.seconds);
        }
        let ms = median_min_max(&times).0 * 1e3;
        let noise = spread(&times);
        eprintln!(
            "{name}: {}: {:.1} triangle tests per ray, {ms:.1} ms (noise {})",
            s.name(),
            tests as f64 / rays as f64,
            spread_percent(noise)
        );
        rows.push(Row {
            scene: name.into(),
            triangles: mesh.num_triangles(),
            structure: s.name().into(),
            triangle_tests_per_ray: Some(tests as f64 / rays.max(1) as f64),
            rays_millions: rays as f64 / 1e6,
            build_ms: Some(build_s * 1e3),
            ms: Some(ms),
            fps: Some(1e3 / ms),
            noise,
            nodes: Some(accel.stats().nodes),
        });
    }
    if let Some(r) = rows.iter_mut().find(|r| r.scene == name && r.ms.is_none()) {
        r.rays_millions = reference_rays.unwrap_or(0) as f64 / 1e6;
    }
    Ok(())
}

/// Run every scene and write the report.
pub fn run(args: WhittedStructuresArgs) -> Result<ExitCode> {
    if args.size == 0 || args.size > 8192 {
        anyhow::bail!("--size must be between 1 and 8192");
    }
    let pool = pool(args.threads)?;
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let mut rows = Vec::new();
    for name in &args.scenes {
        run_scene(&args, &pool, name, &mut rows)?;
    }
    write_csv(&args.out, "structures.csv", &rows)?;
    write_text(
        &args.out,
        "structures.json",
        &serde_json::to_string_pretty(&serde_json::json!({"command": command, "rows": rows}))?,
    )?;
    let opt = |v: Option<f64>, digits: usize| match v {
        Some(x) => format!("{x:.digits$}"),
        None => "not run".into(),
    };
    let mut md = format!(
        "# Acceleration structures in the Whitted renderer ({} threads)\n\n`{command}`\n\n\
         {}×{} pixels, 2 passes (camera ray, one shadow ray per light, one reflection ray), \
         traced primaries, recursive integrator, Möller–Trumbore, median of {} frames. \
         Triangle tests per ray: all triangle tests of one frame (counted by a wrapper around \
         the test) over all its rays. No acceleration runs only up to {} triangles.\n\n\
         | scene | triangles | structure | triangle tests per ray | rays (M) | build ms | ms | fps | noise | nodes |\n\
         |---|---:|---|---:|---:|---:|---:|---:|---:|---:|\n",
        pool.current_num_threads(),
        args.size,
        args.size,
        args.reps,
        args.brute_max_triangles
    );
    for r in &rows {
        md += &format!(
            "| {} | {} | {} | {} | {:.2} | {} | {} | {} | {} | {} |\n",
            r.scene,
            r.triangles,
            r.structure,
            opt(r.triangle_tests_per_ray, 1),
            r.rays_millions,
            opt(r.build_ms, 1),
            opt(r.ms, 1),
            opt(r.fps, 2),
            if r.ms.is_some() {
                spread_percent(r.noise)
            } else {
                "—".into()
            },
            r.nodes.map_or("—".into(), |n| n.to_string()),
        );
    }
    write_text(&args.out, "structures.md", &md)?;
    print!("{md}");
    Ok(ExitCode::SUCCESS)
}
