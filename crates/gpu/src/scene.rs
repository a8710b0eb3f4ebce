//! A triangle mesh's acceleration structure uploaded to the GPU: the
//! stack kd-tree, the kd-tree with ropes (Popov et al. 2007), the threaded BVH (Smits 1998), the compressed wide BVH
//! (Ylitie et al. 2017) or brute force, with the triangles precomputed for
//! the Plücker or Möller test.

use crate::buffers::{storage, uniform};
use crate::context::GpuContext;
use crate::cwbvh::{compress, cwbvh_build_options};
use crate::error::{GpuError, GpuResult};
use crate::kernel::{wgsl, Kernel};
use raykit_core::accel::{
    BuildOptions, Bvh8, FlatKdRopes, FlatTriangles, KdRopes, KdStack, ThreadedBvh,
};
use raykit_core::tri::{Moller, Plucker, TestKind, TriangleTest};
use raykit_core::TriangleMesh;
use std::time::Instant;

/// The structures the GPU kernels traverse.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GpuAccelKind {
    /// Stack kd-tree: kd-tree with 8-byte nodes and a fixed-size per-thread stack.
    KdStack,
    /// Kd-tree with ropes and leaf boxes (Popov, Günther, Seidel &
    /// Slusallek 2007): the same tree, no stack; each leaf record holds its
    /// cell and a link per face to the node across it, and the ray walks
    /// from leaf to leaf through the exit face's rope.
    KdRopes,
    /// Threaded BVH (Smits 1998): BVH in pre-order with escape indices, no stack.
    BvhThreaded,
    /// Compressed wide BVH (Ylitie, Karras and Laine 2017): raykit's 8-wide
    /// BVH with 80-byte nodes of quantized child boxes, traversed with a
    /// short per-thread stack in ray-octant order.
    Cwbvh,
    /// Every ray against every triangle (the reference).
    Brute,
}

impl GpuAccelKind {
    /// Every kind, fastest-first in the usual case.
    pub const ALL: [GpuAccelKind; 5] = [
        GpuAccelKind::KdStack,
        GpuAccelKind::KdRopes,
        GpuAccelKind::BvhThreaded,
        GpuAccelKind::Cwbvh,
        GpuAccelKind::Brute,
    ];

    /// The name `--accel` takes; the same as the CPU structure it mirrors.
    pub fn name(self) -> &'static str {
        match self {
            GpuAccelKind::KdStack => "kd-stack",
            GpuAccelKind::KdRopes => "kd-ropes",
            GpuAccelKind::BvhThreaded => "bvh-threaded",
            GpuAccelKind::Cwbvh => "cwbvh",
            GpuAccelKind::Brute => "brute",
        }
    }

    /// Parse a name.
    pub fn from_name(name: &str) -> Option<GpuAccelKind> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    fn wgsl(self) -> &'static str {
        match self {
            GpuAccelKind::KdStack => wgsl::KD_STACK,
            GpuAccelKind::KdRopes => wgsl::KD_ROPES,
            GpuAccelKind::BvhThreaded => wgsl::BVH_THREADED,
            GpuAccelKind::Cwbvh => wgsl::CWBVH,
            GpuAccelKind::Brute => wgsl::BRUTE,
        }
    }
}

/// Names of the triangle tests the GPU kernels implement.
pub fn gpu_test_supported(test: TestKind) -> bool {
    matches!(test, TestKind::Moller | TestKind::Plucker)
}

/// Uniform block of `shaders/scene.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct AccelParams {
    root_min: [f32; 3],
    num_indices: u32,
    root_max: [f32; 3],
    num_nodes: u32,
    num_tris: u32,
    chunk_words: u32,
    _pad: [u32; 2],
}

/// Bindings the triangle records may be spread over (`shaders/scene.wgsl`).
pub const RECORD_BINDINGS: usize = 4;

/// Words of triangle records per binding: all of them when they fit one
/// binding (`u32::MAX` then, which the kernels read as "one binding"), else
/// as many whole records as fit, with an error naming the limit when even
/// [`RECORD_BINDINGS`] bindings cannot hold them.
fn chunk_words(ctx: &GpuContext, words: usize, per_tri: usize) -> GpuResult<usize> {
    let limit = ctx
        .limits
        .max_storage_buffer_binding_size
        .min(ctx.limits.max_buffer_size)
        / 4;
    if words as u64 <= limit {
        return Ok(u32::MAX as usize);
    }
    let chunk = (limit as usize / per_tri.max(1)) * per_tri;
    if chunk == 0 || words.div_ceil(chunk) > RECORD_BINDINGS {
        return Err(GpuError::Limit {
            what: format!(
                "{} bytes of triangle records in {RECORD_BINDINGS} bindings",
                words * 4
            ),
            needed: (words * 4).div_ceil(RECORD_BINDINGS) as u64,
            limit: limit * 4,
            name: "max_storage_buffer_binding_size",
        });
    }
    Ok(chunk)
}

/// A structure and its triangles in GPU buffers (bind group 0 of every
/// tracing kernel, see `shaders/scene.wgsl`).
pub struct GpuScene {
    /// The structure.
    pub kind: GpuAccelKind,
    /// The triangle test.
    pub test: TestKind,
    /// Triangle records (a kd-tree may hold more references than records).
    pub num_tris: usize,
    /// Nodes.
    pub num_nodes: usize,
    /// Bytes uploaded (nodes, leaf records, indices, triangle records, prims).
    pub bytes: usize,
    /// Bytes of the nodes alone (with kd-ropes' leaf records).
    pub node_bytes: usize,
    /// Seconds to build the structure on the CPU.
    pub build_seconds: f64,
    /// Seconds to precompute, flatten and upload.
    pub upload_seconds: f64,
    buffers: [wgpu::Buffer; 9],
}

/// The structure's arrays before upload.
struct Flat {
    nodes: Vec<u32>,
    /// Kd-ropes' leaf records, [`ROPE_LEAF_WORDS`] words each (empty for the
    /// other structures).
    leaves: Vec<u32>,
    /// Nodes in `nodes`.
    num_nodes: usize,
    indices: Vec<u32>,
    root: ([f32; 3], [f32; 3]),
    tris: FlatTriangles,
}

/// Words per kd-ropes leaf record on the GPU: the core's record
/// ([`FlatKdRopes::LEAF_WORDS`]: cell, six ropes, first entry, entry count)
/// without the entry count, which the leaf node's second word already holds.
const ROPE_LEAF_WORDS: usize = FlatKdRopes::LEAF_WORDS - 1;

/// The GPU's leaf records from the core's.
fn rope_records(leaves: &[u32]) -> Vec<u32> {
    leaves
        .chunks_exact(FlatKdRopes::LEAF_WORDS)
        .flat_map(|r| &r[..ROPE_LEAF_WORDS])
        .copied()
        .collect()
}

/// Records of `T` for the mesh triangles `prims`, in that order.
fn records<T: TriangleTest>(mesh: &TriangleMesh, prims: Vec<u32>) -> FlatTriangles {
    let mut words = Vec::with_capacity(prims.len() * T::WORDS);
    for &p in &prims {
        let [a, b, c] = mesh.triangle(p as usize);
        T::write_words(&T::precompute(a, b, c), &mut words);
    }
    FlatTriangles {
        test: T::NAME,
        words_per_tri: T::WORDS,
        words,
        prims,
    }
}

fn flat_for<T: TriangleTest>(
    mesh: &TriangleMesh,
    kind: GpuAccelKind,
    opts: &BuildOptions,
) -> GpuResult<(Flat, f64)> {
    let start = Instant::now();
    Ok(match kind {
        GpuAccelKind::Cwbvh => {
            let accel = Bvh8::<T>::build(mesh, &cwbvh_build_options(opts));
            let secs = start.elapsed().as_secs_f64();
            let cw = compress(&accel.flat())?;
            let flat = Flat {
                num_nodes: cw.nodes.len() / crate::cwbvh::NODE_WORDS,
                nodes: cw.nodes,
                leaves: Vec::new(),
                indices: Vec::new(),
                root: ([0.0; 3], [0.0; 3]),
                tris: records::<T>(mesh, cw.prims),
            };
            (flat, secs)
        }
        GpuAccelKind::KdStack => {
            let accel = KdStack::<T>::build(mesh, &opts.kd);
            let secs = start.elapsed().as_secs_f64();
            let f = accel.tree().flat();
            let flat = Flat {
                num_nodes: f.nodes.len() / 2,
                nodes: f.nodes,
                leaves: Vec::new(),
                indices: f.indices,
                root: (f.root_min, f.root_max),
                tris: f.tris,
            };
            (flat, secs)
        }
        GpuAccelKind::KdRopes => {
            let accel = KdRopes::<T>::build(mesh, &opts.kd);
            let secs = start.elapsed().as_secs_f64();
            let f = accel.flat();
            let flat = Flat {
                num_nodes: f.nodes.len() / 2,
                nodes: f.nodes,
                leaves: rope_records(&f.leaves),
                indices: f.indices,
                root: (f.root_min, f.root_max),
                tris: f.tris,
            };
            (flat, secs)
        }
        GpuAccelKind::BvhThreaded => {
            let accel = ThreadedBvh::<T>::build(mesh, opts);
            let secs = start.elapsed().as_secs_f64();
            let f = accel.flat();
            let flat = Flat {
                num_nodes: f.nodes.len() / 8,
                nodes: f.nodes,
                leaves: Vec::new(),
                indices: Vec::new(),
                root: ([0.0; 3], [0.0; 3]),
                tris: f.tris,
            };
            (flat, secs)
        }
        GpuAccelKind::Brute => {
            let flat = Flat {
                nodes: Vec::new(),
                num_nodes: 0,
                leaves: Vec::new(),
                indices: Vec::new(),
                root: ([0.0; 3], [0.0; 3]),
                tris: records::<T>(mesh, (0..mesh.num_triangles() as u32).collect()),
            };
            (flat, 0.0)
        }
    })
}

impl GpuScene {
    /// Build `kind` over `mesh` on the CPU (the same build as the CPU
    /// structure of that name, kd-trees with `opts.kd`) and upload it with
    /// the triangles precomputed for `test`.
    pub fn build(
        ctx: &GpuContext,
        mesh: &TriangleMesh,
        kind: GpuAccelKind,
        test: TestKind,
        opts: &BuildOptions,
    ) -> GpuResult<GpuScene> {
        let (flat, build_seconds) = match test {
            TestKind::Moller => flat_for::<Moller>(mesh, kind, opts)?,
            TestKind::Plucker => flat_for::<Plucker>(mesh, kind, opts)?,
            TestKind::Projection => {
                return Err(GpuError::Unsupported(
                    "the projection test; the GPU kernels implement plucker and moller".into(),
                ))
            }
        };
        let start = Instant::now();
        let num_nodes = flat.num_nodes;
        let params = AccelParams {
            root_min: flat.root.0,
            num_indices: flat.indices.len() as u32,
            root_max: flat.root.1,
            num_nodes: num_nodes as u32,
            num_tris: flat.tris.len() as u32,
            chunk_words: 0,
            _pad: [0; 2],
        };
        let words = &flat.tris.words;
        let chunk = chunk_words(ctx, words.len(), flat.tris.words_per_tri)?;
        let part = |k: usize| {
            &words[(k * chunk).min(words.len())..((k + 1).saturating_mul(chunk)).min(words.len())]
        };
        let params = AccelParams {
            chunk_words: chunk.min(u32::MAX as usize) as u32,
            ..params
        };
        let buffers = [
            storage(ctx, "scene nodes", &flat.nodes)?,
            storage(ctx, "scene triangle-index list", &flat.indices)?,
            storage(ctx, "scene triangle records", part(0))?,
            storage(ctx, "scene triangle ids", &flat.tris.prims)?,
            uniform(ctx, "scene parameters", &params),
            storage(ctx, "scene triangle records, second binding", part(1))?,
            storage(ctx, "scene triangle records, third binding", part(2))?,
            storage(ctx, "scene triangle records, fourth binding", part(3))?,
            storage(ctx, "scene leaf records with ropes", &flat.leaves)?,
        ];
        let node_bytes = (flat.nodes.len() + flat.leaves.len()) * 4;
        let bytes =
            node_bytes + (flat.indices.len() + flat.tris.words.len() + flat.tris.prims.len()) * 4;
        ctx.wait()?;
        Ok(GpuScene {
            kind,
            test,
            num_tris: flat.tris.len(),
            num_nodes,
            bytes,
            node_bytes,
            build_seconds,
            upload_seconds: start.elapsed().as_secs_f64(),
            buffers,
        })
    }

    /// The WGSL that defines `scene_intersect(ray) -> Hit` and
    /// `scene_occluded(ray) -> bool` for this structure and test, to be
    /// placed before a kernel's own source.
    pub fn wgsl(&self) -> Vec<&'static str> {
        let tri = match self.test {
            TestKind::Plucker => wgsl::TRI_PLUCKER,
            _ => wgsl::TRI_MOLLER,
        };
        vec![
            wgsl::COMMON,
            wgsl::SCENE,
            tri,
            self.kind.wgsl(),
            wgsl::COUNT_OFF,
        ]
    }

    /// [`GpuScene::wgsl`] with the traversal counts switched on: the
    /// kernel then needs group 2 (six words of 64-bit counters, see
    /// `shaders/count_on.wgsl`).
    pub fn wgsl_counting(&self) -> Vec<&'static str> {
        let mut src = self.wgsl();
        src.pop();
        src.push(wgsl::COUNT_ON);
        src
    }

    /// Group 0 of `kernel`, bound to this scene.
    pub fn bind(&self, ctx: &GpuContext, kernel: &Kernel) -> wgpu::BindGroup {
        let refs: Vec<&wgpu::Buffer> = self.buffers.iter().collect();
        kernel.bind(ctx, 0, &refs)
    }
}
