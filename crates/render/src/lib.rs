//! raykit renderer: one primary ray per sample through a pinhole camera,
//! Blinn-Phong shading (Phong's model as used in the stack kd-tree GPU tracer, with Blinn's half
//! vector) of barycentrically interpolated vertex normals, point lights with
//! `1/d²` falloff, hard shadows by shadow rays, a sky gradient behind,
//! rendered tile by tile in parallel and encoded as 8-bit sRGB.
//!
//! ```
//! use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
//! use raykit_core::tri::TestKind;
//! use raykit_render::{render, RenderOptions};
//!
//! let scene = raykit_scene::builtin("shirley6").unwrap();
//! let accel = build_accel(AccelKind::Bvh2, TestKind::Moller, &scene.mesh, &BuildOptions::default());
//! let opts = RenderOptions { width: 16, height: 12, ..RenderOptions::default() };
//! let camera = scene.camera_or_framing(45.0);
//! let image = render(&scene.mesh, &scene.lights, accel.as_ref(), &camera, &opts, &|_| {});
//! assert_eq!(image.rgb.len(), 16 * 12 * 3);
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod animation;
pub mod aov;
pub mod env;
mod image;
pub mod light_spec;
pub mod lighting;
mod options;
pub mod output;
mod primary;
pub mod raster;
mod render;
pub mod scene_setup;
pub mod shade;
pub mod shadowmap;
pub mod sky;
mod surface;
mod tiles;
pub mod whitted;

pub use image::{Encoding, Image};
pub use options::RenderOptions;
pub use primary::primary_hits;
pub use raykit_scene::{Light, LightSample, PointLight};
pub use render::render;
pub use shade::{shadow_bias, Shader, Surface};
pub use tiles::{tiles, Tile, TILE_SIZE};
