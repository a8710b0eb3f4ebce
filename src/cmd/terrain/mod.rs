//! `raykit terrain`: DEMs — rendering by height-field ray casting (per-frame
//! quadtree boxes, maximum mipmap) and shadow masks (Min 2008).

pub mod dem_arg;
pub mod render;
pub mod shadow;

use anyhow::Result;
use clap::{Args, Subcommand};
use std::process::ExitCode;

/// Arguments of `raykit terrain`.
#[derive(Args)]
pub struct TerrainArgs {
    #[command(subcommand)]
    which: Which,
}

#[derive(Subcommand)]
enum Which {
    /// Shadow mask of a point light or the sun (GeoTIFF with the DEM's
    /// georeferencing, plus a PNG preview), or hours of sun over a day.
    Shadow(shadow::ShadowArgs),
    /// Render a DEM to a PNG by exact height-field ray casting (per-frame
    /// quadtree boxes, maximum mipmap or per-cell march) with Phong shading and shadows.
    Render(render::TerrainRenderArgs),
}

/// Run the chosen terrain command.
pub fn run(args: TerrainArgs) -> Result<ExitCode> {
    match args.which {
        Which::Shadow(a) => shadow::run(a),
        Which::Render(a) => render::run(a),
    }
}
