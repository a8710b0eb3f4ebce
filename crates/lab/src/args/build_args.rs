//! Build options shared by the commands that build a BVH or a kd-tree.

use clap::Args;
use raykit_core::accel::{BuildOptions, BuildQuality, KdOptions, KdSplit};
use std::str::FromStr;

/// The structure `trace`, `bench` and `render` use on the CPU when
/// `--accel` is not given: the fastest (BENCHMARKS.md), an 8-wide BVH over
/// packs of four triangles.
pub const DEFAULT_ACCEL: &str = "bvh8";

/// BVH build options on the command line.
#[derive(Args, Clone, Debug)]
pub struct BuildArgs {
    /// Most triangles per BVH leaf (1-31; 1 gives one-triangle leaves).
    #[arg(long, default_value_t = BuildOptions::default().max_leaf_size as u32, value_parser = clap::value_parser!(u32).range(1..=31))]
    max_leaf: u32,
    /// Most triangles per leaf of the wide BVHs with leaves of four-triangle
    /// packs (bvh4 and bvh8 over moller), in place of --max-leaf (1-31). The
    /// SAH, which counts a leaf's pack tests, picks smaller leaves below it,
    /// as Embree's builders do.
    #[arg(long, default_value_t = BuildOptions::default().packed_leaf_size as u32, value_parser = clap::value_parser!(u32).range(1..=31))]
    max_packed_leaf: u32,
    /// SAH bins per axis (2-256).
    #[arg(long, default_value_t = BuildOptions::default().bins as u32, value_parser = clap::value_parser!(u32).range(2..=256))]
    bins: u32,
    /// SAH cost of a node traversal relative to one triangle test (0-1000).
    #[arg(long, default_value_t = BuildOptions::default().traversal_cost, value_parser = traversal_cost)]
    traversal_cost: f32,
    /// BVH builder: `sah` (binned SAH), `high` (the binned SAH, and bvh4 and
    /// bvh8 over moller fill every node's free slots with the halves of their
    /// largest children, as Embree's builders do: a few percent faster rays,
    /// about 8% slower to build) or `fast` (linear BVH after Karras 2012:
    /// Morton codes, radix sort; several times faster to build, for dynamic
    /// scenes, a worse tree).
    #[arg(long, default_value = "sah", value_parser = BuildQuality::from_str)]
    bvh_build: BuildQuality,
    /// kd-tree split rule: `sah` (Wald & Havran's O(N log N) SAH with perfect
    /// splits; the default), `median` (spatial median) or `game:H` (Kim's
    /// (2013) score |front-back|·(20-H) + splits·H, H in 0..=20).
    #[arg(long, value_name = "RULE", value_parser = KdSplit::from_str)]
    kd_split: Option<KdSplit>,
    /// kd-tree SAH cost of one triangle test relative to a node traversal
    /// (0.001-1000).
    #[arg(long, default_value_t = KdOptions::default().intersection_cost, value_parser = kd_isect_cost)]
    kd_isect_cost: f32,
    /// kd-tree node layout: subtrees of this many levels, each laid out
    /// breadth-first; 0 lays the whole tree out breadth-first.
    #[arg(long, default_value_t = KdOptions::default().subtree_levels)]
    kd_subtree_levels: u32,
}

/// A number in `lo..=hi` (NaN and infinities refused) for a clap option.
pub fn number_in(text: &str, lo: f32, hi: f32) -> Result<f32, String> {
    let v: f32 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    if !(lo..=hi).contains(&v) {
        return Err(format!("must be between {lo} and {hi}, got {text}"));
    }
    Ok(v)
}

fn traversal_cost(text: &str) -> Result<f32, String> {
    number_in(text, 0.0, 1e3)
}

fn kd_isect_cost(text: &str) -> Result<f32, String> {
    number_in(text, 1e-3, 1e3)
}

impl BuildArgs {
    /// The kd-tree split rule when `--kd-split` was given, so that commands
    /// tracing a structure that is no kd-tree can say it goes unused.
    pub fn kd_split_given(&self) -> Option<KdSplit> {
        self.kd_split
    }

    /// The library's options.
    pub fn options(&self) -> BuildOptions {
        BuildOptions {
            max_leaf_size: self.max_leaf as usize,
            packed_leaf_size: self.max_packed_leaf as usize,
            bins: self.bins as usize,
            traversal_cost: self.traversal_cost,
            quality: self.bvh_build,
            kd: KdOptions {
                split: self.kd_split.unwrap_or(KdOptions::default().split),
                intersection_cost: self.kd_isect_cost,
                subtree_levels: self.kd_subtree_levels,
                ..KdOptions::default()
            },
            ..BuildOptions::default()
        }
    }
}
