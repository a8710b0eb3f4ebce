//! Storage buffers: upload with the device's limits checked, and read back.

use crate::context::GpuContext;
use crate::error::{GpuError, GpuResult};
use wgpu::util::DeviceExt;

/// Check that `bytes` fit one storage binding and one buffer of `ctx`.
pub fn check_binding(ctx: &GpuContext, what: &str, bytes: u64) -> GpuResult<()> {
    let l = &ctx.limits;
    if bytes > l.max_storage_buffer_binding_size {
        return Err(GpuError::Limit {
            what: what.to_string(),
            needed: bytes,
            limit: l.max_storage_buffer_binding_size,
            name: "max_storage_buffer_binding_size",
        });
    }
    if bytes > l.max_buffer_size {
        return Err(GpuError::Limit {
            what: what.to_string(),
            needed: bytes,
            limit: l.max_buffer_size,
            name: "max_buffer_size",
        });
    }
    Ok(())
}

/// A read-only storage buffer holding `words` (one zero word if empty: a
/// binding may not be empty).
pub fn storage(ctx: &GpuContext, what: &str, words: &[u32]) -> GpuResult<wgpu::Buffer> {
    let data: &[u32] = if words.is_empty() { &[0] } else { words };
    check_binding(ctx, what, std::mem::size_of_val(data) as u64)?;
    Ok(ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(what),
            contents: bytemuck::cast_slice(data),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        }))
}

/// A uniform buffer holding `value`.
pub fn uniform<T: bytemuck::Pod>(ctx: &GpuContext, what: &str, value: &T) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(what),
            contents: bytemuck::bytes_of(value),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        })
}

/// A zeroed read-write storage buffer of `words` words that can be copied
/// out.
pub fn output(ctx: &GpuContext, what: &str, words: usize) -> GpuResult<wgpu::Buffer> {
    let bytes = (words.max(1) * 4) as u64;
    check_binding(ctx, what, bytes)?;
    Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(what),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    }))
}

/// Copy the first `words` words of `buffer` back to the host (waits for
/// the queue).
pub fn read_words(ctx: &GpuContext, buffer: &wgpu::Buffer, words: usize) -> GpuResult<Vec<u32>> {
    read_words_at(ctx, buffer, 0, words)
}

/// Copy `words` words of `buffer`, from word `first` on, back to the host
/// (waits for the queue).
pub(crate) fn read_words_at(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    first: usize,
    words: usize,
) -> GpuResult<Vec<u32>> {
    if words == 0 {
        return Ok(Vec::new());
    }
    let bytes = (words * 4) as u64;
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
    enc.copy_buffer_to_buffer(buffer, (first * 4) as u64, &staging, 0, bytes);
    ctx.queue.submit([enc.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.wait()?;
    rx.recv()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    ctx.take_error()?;
    let view = staging
        .slice(..)
        .get_mapped_range()
        .map_err(|e| GpuError::Readback(format!("{e:?}")))?;
    let out = bytemuck::cast_slice::<u8, u32>(&view).to_vec();
    drop(view);
    staging.unmap();
    Ok(out)
}
