//! Compute pipelines assembled from WGSL pieces, and their dispatch.

use crate::context::GpuContext;
use crate::error::{GpuError, GpuResult};

/// Threads per workgroup of every raykit kernel (`@workgroup_size(64)`).
pub const WORKGROUP: u32 = 64;

/// The WGSL sources, embedded in the binary.
pub mod wgsl {
    /// Ray and hit records, NaN-aware min/max.
    pub const COMMON: &str = include_str!("shaders/common.wgsl");
    /// The scene bindings (group 0) and the leaf loop.
    pub const SCENE: &str = include_str!("shaders/scene.wgsl");
    /// Möller–Trumbore.
    pub const TRI_MOLLER: &str = include_str!("shaders/tri_moller.wgsl");
    /// Plücker (the stack kd-tree GPU tracer).
    pub const TRI_PLUCKER: &str = include_str!("shaders/tri_plucker.wgsl");
    /// The stack kd-tree GPU tracer's kd-tree with a per-thread stack.
    pub const KD_STACK: &str = include_str!("shaders/kd_stack.wgsl");
    /// The stackless kd-tree with ropes and leaf boxes (Popov et al. 2007).
    pub const KD_ROPES: &str = include_str!("shaders/kd_ropes.wgsl");
    /// The Purcell-style stream tracer's threaded BVH.
    pub const BVH_THREADED: &str = include_str!("shaders/bvh_threaded.wgsl");
    /// The compressed wide BVH (Ylitie et al. 2017).
    pub const CWBVH: &str = include_str!("shaders/cwbvh.wgsl");
    /// Traversal counts switched off (the notes compile to nothing).
    pub const COUNT_OFF: &str = include_str!("shaders/count_off.wgsl");
    /// Traversal counts into group 2 (the counting kernels).
    pub const COUNT_ON: &str = include_str!("shaders/count_on.wgsl");
    /// Brute force.
    pub const BRUTE: &str = include_str!("shaders/brute.wgsl");
    /// Batch ray queries.
    pub const TRACE: &str = include_str!("shaders/trace.wgsl");
    /// Terrain bindings and the per-cell test of the declared surface.
    pub const TERRAIN_CELL: &str = include_str!("shaders/terrain_cell.wgsl");
    /// per-frame quadtree boxes: nearest box entry, then a march.
    pub const TERRAIN_BOXES: &str = include_str!("shaders/terrain_boxes.wgsl");
    /// Per-ray maximum-mipmap terrain casting (Tevs et al. 2008).
    pub const TERRAIN_MAXMIP: &str = include_str!("shaders/terrain_maxmip.wgsl");
    /// The renderer's shading data (group 1), surface, camera ray.
    pub const SHADE_DATA: &str = include_str!("shaders/render/shade_data.wgsl");
    /// Reflection, refraction, Fresnel.
    pub const OPTICS: &str = include_str!("shaders/render/optics.wgsl");
    /// Lights and Blinn-Phong with shadow rays.
    pub const LIGHTING: &str = include_str!("shaders/render/lighting.wgsl");
    /// Sky and constant environments.
    pub const ENVIRONMENT: &str = include_str!("shaders/render/environment.wgsl");
    /// The Whitted shading kernel (Tracer::scatter).
    pub const SCATTER: &str = include_str!("shaders/render/scatter.wgsl");
    /// The stack kd-tree GPU tracer's single render kernel.
    pub const MEGAKERNEL: &str = include_str!("shaders/render/megakernel.wgsl");
    /// The Purcell-style stream tracer's stream kernels.
    pub const STREAM: &str = include_str!("shaders/render/stream.wgsl");
}

/// One compute pipeline with an explicit layout.
#[derive(Clone)]
pub struct Kernel {
    /// The pipeline.
    pub pipeline: wgpu::ComputePipeline,
    /// Its bind group layouts, by group index.
    pub layouts: Vec<wgpu::BindGroupLayout>,
}

/// A bind group layout entry for a storage buffer (read-only or not) or a
/// uniform buffer at `binding`.
pub fn layout_entry(binding: u32, kind: BindingKind) -> wgpu::BindGroupLayoutEntry {
    let ty = match kind {
        BindingKind::Storage => wgpu::BufferBindingType::Storage { read_only: true },
        BindingKind::StorageRw => wgpu::BufferBindingType::Storage { read_only: false },
        BindingKind::Uniform => wgpu::BufferBindingType::Uniform,
    };
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// How a buffer is bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BindingKind {
    /// `var<storage, read>`.
    Storage,
    /// `var<storage, read_write>`.
    StorageRw,
    /// `var<uniform>`.
    Uniform,
}

/// The scene's group 0: nodes, indices, triangle records, prims (storage),
/// accel parameters (uniform), three more bindings for triangle records
/// beyond one binding's limit, and the kd-tree's leaf records with ropes;
/// see `shaders/scene.wgsl`.
pub const SCENE_GROUP: [BindingKind; 9] = [
    BindingKind::Storage,
    BindingKind::Storage,
    BindingKind::Storage,
    BindingKind::Storage,
    BindingKind::Uniform,
    BindingKind::Storage,
    BindingKind::Storage,
    BindingKind::Storage,
    BindingKind::Storage,
];

impl Kernel {
    /// Compile `sources` (concatenated in order) and build the pipeline for
    /// `entry` with one bind group layout per element of `groups`.
    pub fn new(
        ctx: &GpuContext,
        label: &str,
        sources: &[&str],
        entry: &str,
        groups: &[&[BindingKind]],
    ) -> GpuResult<Kernel> {
        let source = sources.join("\n");
        let key = {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            (&source, entry, groups).hash(&mut h);
            h.finish()
        };
        let cached = ctx.kernels.lock().unwrap().get(&key).cloned();
        if let Some(k) = cached.as_deref().and_then(|k| k.downcast_ref::<Kernel>()) {
            return Ok(k.clone());
        }
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
        let layouts: Vec<wgpu::BindGroupLayout> = groups
            .iter()
            .enumerate()
            .map(|(g, kinds)| {
                let entries: Vec<_> = kinds
                    .iter()
                    .enumerate()
                    .map(|(b, &k)| layout_entry(b as u32, k))
                    .collect();
                ctx.device
                    .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                        label: Some(&format!("{label} group {g}")),
                        entries: &entries,
                    })
            })
            .collect();
        let layout_refs: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(Some).collect();
        let pipeline_layout = ctx
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &layout_refs,
                immediate_size: 0,
            });
        let pipeline = ctx
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(format!("{label}: {e}")));
        }
        let kernel = Kernel { pipeline, layouts };
        ctx.kernels
            .lock()
            .unwrap()
            .insert(key, std::sync::Arc::new(kernel.clone()));
        Ok(kernel)
    }

    /// A bind group for group `g` over `buffers` (bindings 0, 1, ...).
    pub fn bind(&self, ctx: &GpuContext, g: usize, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        let entries: Vec<_> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.layouts[g],
            entries: &entries,
        })
    }
}

/// Workgroup counts `(x, y)` covering `threads` threads within the
/// device's per-dimension limit, and the threads per row `x · WORKGROUP`
/// that kernels use to turn `(gid.x, gid.y)` into one index.
pub fn grid(ctx: &GpuContext, threads: usize) -> GpuResult<(u32, u32, u32)> {
    let groups = threads.div_ceil(WORKGROUP as usize).max(1) as u64;
    let max = ctx.limits.max_compute_workgroups_per_dimension as u64;
    let x = groups.min(max);
    let y = groups.div_ceil(x);
    if y > max {
        return Err(GpuError::Limit {
            what: format!("a dispatch of {threads} threads"),
            needed: groups,
            limit: max * max,
            name: "max_compute_workgroups_per_dimension (squared)",
        });
    }
    Ok((x as u32, y as u32, (x * WORKGROUP as u64) as u32))
}

/// Record one dispatch of `kernel` with `groups` bound, covering `(x, y)`
/// workgroups.
pub fn dispatch(
    enc: &mut wgpu::CommandEncoder,
    kernel: &Kernel,
    groups: &[&wgpu::BindGroup],
    xy: (u32, u32),
) {
    dispatch_timed(enc, kernel, groups, xy, None);
}

/// [`dispatch`] in a pass that writes the GPU's clock into queries 0 and
/// 1 of `timestamps` at its start and end (a device with
/// `wgpu::Features::TIMESTAMP_QUERY`).
pub fn dispatch_timed(
    enc: &mut wgpu::CommandEncoder,
    kernel: &Kernel,
    groups: &[&wgpu::BindGroup],
    (x, y): (u32, u32),
    timestamps: Option<&wgpu::QuerySet>,
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: None,
        timestamp_writes: timestamps.map(|query_set| wgpu::ComputePassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }),
    });
    pass.set_pipeline(&kernel.pipeline);
    for (i, g) in groups.iter().enumerate() {
        pass.set_bind_group(i as u32, Some(*g), &[]);
    }
    pass.dispatch_workgroups(x, y, 1);
}
