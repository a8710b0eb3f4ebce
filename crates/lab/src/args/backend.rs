//! `--backend cpu|gpu` and what the GPU side of a command shares: opening
//! the device with a clear message, and the GPU structure names.

use anyhow::{anyhow, Result};
use clap::ValueEnum;
use raykit_core::accel::AccelKind;
use raykit_gpu::{GpuAccelKind, GpuContext};

/// Where the rays are traced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// The CPU engine (every structure and test, all cores).
    #[default]
    Cpu,
    /// The wgpu backend: WGSL compute kernels on any Vulkan, Metal or DX12
    /// GPU, or Mesa's lavapipe without one.
    Gpu,
}

/// Open the GPU, printing which adapter serves.
pub fn open_gpu() -> Result<GpuContext> {
    let ctx = GpuContext::new().map_err(|e| anyhow!("{e}"))?;
    eprintln!("GPU: {}", ctx.describe());
    if ctx.is_software() {
        eprintln!("note: this adapter is a software rasterizer (CPU); GPU figures from it are not a GPU's");
    }
    Ok(ctx)
}

/// The GPU structure named `name` (`kd-stack`, `kd-ropes`, `bvh-threaded`, `cwbvh`,
/// `brute`).
pub fn gpu_accel(name: &str) -> Result<GpuAccelKind> {
    GpuAccelKind::from_name(name).ok_or_else(|| {
        let names: Vec<_> = GpuAccelKind::ALL.iter().map(|k| k.name()).collect();
        anyhow!(
            "--accel '{name}' has no GPU kernel; with --backend gpu use one of: {}",
            names.join(", ")
        )
    })
}

/// The CPU structure a GPU structure mirrors (same build, same answers).
pub fn cpu_twin(kind: GpuAccelKind) -> AccelKind {
    match kind {
        GpuAccelKind::KdStack => AccelKind::KdStack,
        GpuAccelKind::KdRopes => AccelKind::KdRopes,
        GpuAccelKind::BvhThreaded => AccelKind::ThreadedBvh,
        GpuAccelKind::Cwbvh => AccelKind::Bvh8,
        GpuAccelKind::Brute => AccelKind::Brute,
    }
}
