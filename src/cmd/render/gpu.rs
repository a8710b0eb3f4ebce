//! `raykit render --backend gpu`: the same frame from raykit-gpu's WGSL
//! kernels — one kernel per ray path for `--integrator recursive`, a
//! stream of kernels (after Purcell et al. 2002) for `--integrator wavefront` — written through
//! the same image path as the CPU renderer.

use super::setup::RenderSetup;
use anyhow::{bail, Result};
use raykit_core::tri::TestKind;
use raykit_core::TriangleMesh;
use raykit_gpu::{
    check_options, render_whitted_gpu, GpuAccelKind, GpuContext, GpuScene, ShadeScene,
};
use raykit_render::whitted::{Frame, WhittedOptions};

/// The structure `--backend gpu` traverses without `--accel`: the fastest
/// on lavapipe (BENCHMARKS.md, "GPU renderer").
pub const DEFAULT_GPU_ACCEL: GpuAccelKind = GpuAccelKind::BvhThreaded;

/// A GPU frame and what made it.
pub struct GpuRun {
    /// The frame (no first hits).
    pub frame: Frame,
    /// Seconds to build and upload the structure.
    pub build_seconds: f64,
    /// "adapter, structure, test", for the summary line.
    pub describe: String,
}

/// The structure named by `--accel` for the GPU.
pub fn gpu_accel(accel: Option<&str>) -> Result<GpuAccelKind> {
    match accel {
        None => Ok(DEFAULT_GPU_ACCEL),
        Some(name) => GpuAccelKind::from_name(name).ok_or_else(|| {
            let names: Vec<_> = GpuAccelKind::ALL.iter().map(|k| k.name()).collect();
            anyhow::anyhow!(
                "not supported by --backend gpu: --accel {name}; the GPU kernels traverse {}",
                names.join(", ")
            )
        }),
    }
}

/// Refuse what the GPU renderer cannot do before anything is loaded.
pub fn check_args(opts: &WhittedOptions, test: TestKind) -> Result<()> {
    if !raykit_gpu::gpu_test_supported(test) {
        bail!(
            "not supported by --backend gpu: --test {}; the GPU kernels implement plucker and moller",
            test.name()
        );
    }
    check_options(opts)?;
    Ok(())
}

/// Build the structure, upload the scene and render the frame on the GPU.
pub fn render(
    kind: GpuAccelKind,
    test: TestKind,
    mesh: &TriangleMesh,
    setup: &RenderSetup,
    opts: &WhittedOptions,
    build: &raykit_core::accel::BuildOptions,
    progress: &dyn Fn(u64, u64),
) -> Result<GpuRun> {
    let shade = ShadeScene {
        mesh,
        lights: &setup.lights,
        environment: &setup.environment,
    };
    let ctx = GpuContext::new()?;
    eprintln!("GPU: {}", ctx.describe());
    let scene = GpuScene::build(&ctx, mesh, kind, test, build)?;
    let g = render_whitted_gpu(&ctx, &scene, &shade, &setup.camera, opts, progress)?;
    eprintln!("GPU kernels compiled in {:.0} ms", g.compile_seconds * 1e3);
    Ok(GpuRun {
        frame: g.frame,
        build_seconds: scene.build_seconds + scene.upload_seconds,
        describe: format!("{}, {}, {}", ctx.info.name, kind.name(), test.name()),
    })
}
