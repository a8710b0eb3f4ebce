//! raykit terrain: digital elevation models and exact height-field ray
//! casting (Min 2008; per-frame quadtree boxes).
//!
//! The surface every caster intersects is declared in [`heightfield`]: two
//! triangles per grid cell, split along the cell's top-left to bottom-right
//! diagonal. Three casters give the same first hit on it:
//! - [`march::march`]: a 2D DDA over the cells, the reference;
//! - [`maxmip::trace`]: per-ray maximum-mipmap traversal (Tevs et al. 2008);
//! - [`boxes`]: the quadtree-box caster's method, one quadtree traversal per frame with
//!   view-distance LOD and frustum culling, boxes giving each pixel's ray its
//!   start, then a march from there.

pub mod boxes;
pub mod camera;
pub mod curvature;
pub mod dem;
pub mod fractal;
pub mod georef;
pub mod ground;
pub mod heightfield;
pub mod horizon;
pub mod io;
pub mod march;
pub mod mask_cells;
pub mod maxmip;
pub mod pyramid;
pub mod render_job;
pub mod shade;
pub mod shadow;
pub mod sun;
pub mod sun_hours;
pub mod view;

pub use camera::TerrainCamera;
pub use dem::{Dem, GeoRef};
pub use heightfield::{GridRay, HeightField, Steps, TerrainHit};
pub use pyramid::MaxMipmap;
