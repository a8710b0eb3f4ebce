//! One module per subcommand.

pub mod bench;
#[cfg(feature = "embree")]
pub mod bench_compare;
#[cfg(feature = "embree")]
pub mod bench_compare_print;
pub mod bench_gpu;
pub mod cull;
pub mod experiment;
pub mod export;
pub mod info;
pub mod merge_tiles;
pub mod query;
pub mod rays;
pub mod render;
pub mod serve;
pub mod terrain;
pub mod tjunctions;
pub mod trace;
