//! The wgpu instance, adapter, device and queue, opened once.

use crate::error::{GpuError, GpuResult};
use std::sync::Arc;

/// An open GPU device with its limits and a description of the adapter.
///
/// The adapter is wgpu's choice for the backends allowed by `WGPU_BACKEND`
/// (default: all), preferring a discrete GPU; without a GPU, Mesa's
/// lavapipe (llvmpipe) serves, which is how CI runs every kernel.
#[derive(Clone)]
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's name, backend and driver.
    pub info: wgpu::AdapterInfo,
    /// The limits the device was opened with (the adapter's own).
    pub limits: wgpu::Limits,
    /// Whether the device was opened with timestamp queries
    /// (`wgpu::Features::TIMESTAMP_QUERY`, taken whenever the adapter has
    /// them): kernels are then timed on the GPU's own clock.
    pub timestamps: bool,
    errors: Arc<std::sync::Mutex<Vec<String>>>,
    /// Compiled kernels by source, entry point and layout, so a kernel is
    /// compiled once per device however many scenes use it. The kernel
    /// layer stores and downcasts its own type, so the device layer does not
    /// depend on it.
    pub(crate) kernels: Arc<std::sync::Mutex<std::collections::HashMap<u64, CachedKernel>>>,
}

/// A compiled kernel in [`GpuContext`]'s cache, type-erased.
pub(crate) type CachedKernel = Arc<dyn std::any::Any + Send + Sync>;

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext")
            .field("adapter", &self.describe())
            .finish()
    }
}

impl GpuContext {
    /// Open the default adapter's device with the adapter's full limits
    /// (large scenes need storage buffers beyond WebGPU's defaults).
    pub fn new() -> GpuResult<GpuContext> {
        let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
        if backends.is_empty() {
            let named = std::env::var("WGPU_BACKEND").unwrap_or_default();
            return Err(GpuError::NoAdapter(format!(
                "WGPU_BACKEND={named:?} names no backend; use vulkan, metal, dx12 or gl \
                 (comma-separated), or unset it to let wgpu choose"
            )));
        }
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        desc.backends = backends;
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| GpuError::NoAdapter(format!("{e} (backends {backends:?})")))?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("raykit"),
            required_features: if timestamps {
                wgpu::Features::TIMESTAMP_QUERY
            } else {
                wgpu::Features::empty()
            },
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        let errors = Arc::new(std::sync::Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock().unwrap().push(e.to_string());
        }));
        Ok(GpuContext {
            device,
            queue,
            info,
            limits,
            timestamps,
            errors,
            kernels: Arc::default(),
        })
    }

    /// One line: adapter name, device type, backend and driver.
    pub fn describe(&self) -> String {
        let i = &self.info;
        format!(
            "{} ({:?}, {:?}, {} {})",
            i.name, i.device_type, i.backend, i.driver, i.driver_info
        )
    }

    /// True when the adapter is a CPU implementation (lavapipe, WARP).
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The error for a kernel that found one of its loops cut short by the
    /// driver (`what`: what the loop was doing, e.g. "a ray's traversal").
    pub fn loop_limit(&self, what: &str) -> GpuError {
        GpuError::LoopLimit {
            what: what.to_string(),
            adapter: self.info.name.clone(),
            software: self.is_software(),
        }
    }

    /// The first validation error reported since the last call, if any.
    pub(crate) fn take_error(&self) -> GpuResult<()> {
        let mut errors = self.errors.lock().unwrap();
        if errors.is_empty() {
            return Ok(());
        }
        let first = errors.remove(0);
        errors.clear();
        Err(GpuError::Shader(first))
    }

    /// Wait until the queue is idle.
    pub fn wait(&self) -> GpuResult<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Readback(e.to_string()))
    }
}
