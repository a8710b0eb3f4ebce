//! What the GPU tests share: the device (failing loudly without one), the
//! test data folder, and the ray-by-ray comparison with the CPU.
#![allow(dead_code)]

use raykit_core::{Hit, Ray};
use raykit_gpu::GpuContext;
use std::path::PathBuf;
use std::sync::OnceLock;

/// The device every GPU test uses. Panics, naming what to install, when no
/// adapter exists: CI installs Mesa's lavapipe, so a missing adapter is a
/// broken setup, never a reason to skip.
pub fn gpu() -> &'static GpuContext {
    static CTX: OnceLock<GpuContext> = OnceLock::new();
    CTX.get_or_init(|| match GpuContext::new() {
        Ok(ctx) => {
            eprintln!("GPU tests run on {}", ctx.describe());
            ctx
        }
        Err(e) => panic!(
            "the GPU tests need a wgpu adapter and found none: {e}. On Debian: apt-get install \
             mesa-vulkan-drivers libvulkan1 (.ci/run does this and sets WGPU_BACKEND=vulkan, \
             VK_DRIVER_FILES and XDG_RUNTIME_DIR)"
        ),
    })
}

/// The test data folder (`data/` in the repository, or `$RAYKIT_SHARED_DATA`).
pub fn shared_data() -> PathBuf {
    let dir = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data"));
    assert!(
        dir.is_dir(),
        "test data folder not found at {} (set RAYKIT_SHARED_DATA): these tests need the real meshes",
        dir.display()
    );
    dir
}

/// How two answer sets differ.
#[derive(Debug, Default)]
pub struct Diff {
    /// Hit on one side, miss on the other.
    pub hit_miss: Vec<usize>,
    /// Both hit, `t` more than 1e-4 relative apart.
    pub distance: Vec<usize>,
    /// Both hit at the same `t`, different triangles (shared edges).
    pub ties: usize,
    /// Both hit the same triangle, barycentrics more than 1e-3 apart.
    pub bary: usize,
}

/// Compare GPU answers with the CPU's, ray by ray.
pub fn compare(cpu: &[Option<Hit>], gpu: &[Option<Hit>]) -> Diff {
    assert_eq!(cpu.len(), gpu.len());
    let mut d = Diff::default();
    for (i, (c, g)) in cpu.iter().zip(gpu).enumerate() {
        match (c, g) {
            (None, None) => {}
            (Some(c), Some(g)) => {
                if (c.t - g.t).abs() > 1e-4 * c.t.abs().max(g.t.abs()).max(1e-6) {
                    d.distance.push(i);
                } else if c.prim != g.prim {
                    d.ties += 1;
                } else if (c.u - g.u).abs() > 1e-3 || (c.v - g.v).abs() > 1e-3 {
                    d.bary += 1;
                }
            }
            _ => d.hit_miss.push(i),
        }
    }
    d
}

/// The rays of `idx`, for messages.
pub fn describe(rays: &[Ray], idx: &[usize], cpu: &[Option<Hit>], gpu: &[Option<Hit>]) -> String {
    idx.iter()
        .take(5)
        .map(|&i| format!("ray {i} {:?}: cpu {:?} gpu {:?}", rays[i], cpu[i], gpu[i]))
        .collect::<Vec<_>>()
        .join("\n")
}
