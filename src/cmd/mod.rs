//! One module per subcommand.

pub mod cull;
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
