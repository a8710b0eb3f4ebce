//! Errors of the GPU backend, each saying what was wanted and what the
//! device offers.

use std::fmt;

/// What can go wrong on the GPU path.
#[derive(Debug, Clone, PartialEq)]
pub enum GpuError {
    /// No adapter (GPU or software rasterizer) was found.
    NoAdapter(String),
    /// The adapter refused to open a device.
    Device(String),
    /// The scene or batch needs more than a device limit allows.
    Limit {
        /// What was being allocated or dispatched.
        what: String,
        /// How much it needs.
        needed: u64,
        /// The device's limit.
        limit: u64,
        /// The limit's name in `wgpu::Limits`.
        name: &'static str,
    },
    /// A shader failed to compile or a pipeline to build (a bug in raykit,
    /// or a driver that rejects valid WGSL).
    Shader(String),
    /// Reading results back from the device failed.
    Readback(String),
    /// The request cannot run on the GPU backend (an unsupported option).
    Unsupported(String),
    /// The driver cut a kernel's loop short (Mesa's lavapipe ends every
    /// loop once an invocation has made 65,535 loop passes), so the
    /// answers would be wrong; the kernel detected it and the results were
    /// refused.
    LoopLimit {
        /// What was cut short, e.g. "a ray's traversal".
        what: String,
        /// The adapter's name.
        adapter: String,
        /// Whether the adapter is a software rasterizer.
        software: bool,
    },
}

impl fmt::Display for GpuError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GpuError::NoAdapter(why) => write!(
                f,
                "no GPU adapter found ({why}); install a Vulkan, Metal or DX12 driver, \
                 or Mesa's software driver (apt-get install mesa-vulkan-drivers libvulkan1), \
                 or use the CPU backend (--backend cpu)"
            ),
            GpuError::Device(why) => write!(f, "the GPU adapter could not open a device: {why}"),
            GpuError::Limit {
                what,
                needed,
                limit,
                name,
            } => write!(
                f,
                "{what} needs {needed} but the GPU allows {limit} ({name}); \
                 use a smaller scene or batch, or the CPU backend (--backend cpu)"
            ),
            GpuError::Shader(why) => write!(f, "GPU pipeline creation failed: {why}"),
            GpuError::Readback(why) => write!(f, "reading results back from the GPU failed: {why}"),
            GpuError::Unsupported(why) => write!(f, "not supported by --backend gpu: {why}"),
            GpuError::LoopLimit {
                what,
                adapter,
                software,
            } => {
                let kind = if *software {
                    ", a software rasterizer"
                } else {
                    ""
                };
                write!(
                    f,
                    "the GPU adapter ({adapter}{kind}) stopped {what} at its limit on loop \
                     passes (65,535 per thread in Mesa's lavapipe); the answers would be wrong: \
                     use the CPU backend (--backend cpu)"
                )
            }
        }
    }
}

impl std::error::Error for GpuError {}

/// Result with a [`GpuError`].
pub type GpuResult<T> = Result<T, GpuError>;
