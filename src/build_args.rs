//! Build options shared by the commands that build a BVH.

use clap::Args;
use raykit_core::accel::BuildOptions;

/// BVH build options on the command line.
#[derive(Args, Clone, Debug)]
pub struct BuildArgs {
    /// Most triangles per BVH leaf (1-31; 1 gives paper 001's one-triangle leaves).
    #[arg(long, default_value_t = BuildOptions::default().max_leaf_size as u32, value_parser = clap::value_parser!(u32).range(1..=31))]
    max_leaf: u32,
    /// SAH bins per axis (2-256).
    #[arg(long, default_value_t = BuildOptions::default().bins as u32, value_parser = clap::value_parser!(u32).range(2..=256))]
    bins: u32,
    /// SAH cost of a node traversal relative to one triangle test.
    #[arg(long, default_value_t = BuildOptions::default().traversal_cost)]
    traversal_cost: f32,
}

impl BuildArgs {
    /// The library's options.
    pub fn options(&self) -> BuildOptions {
        BuildOptions {
            max_leaf_size: self.max_leaf as usize,
            bins: self.bins as usize,
            traversal_cost: self.traversal_cost.clamp(0.0, 1e3),
            ..BuildOptions::default()
        }
    }
}
