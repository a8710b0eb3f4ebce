//! Argument groups shared by the commands: the scene or mesh to load, BVH
//! and kd-tree build options, the CPU or GPU backend, and a scene with its
//! camera, light and environment overrides, and the range checks of
//! numeric options.

pub mod backend;
pub mod build_args;
pub mod ranges;
pub mod scene;
pub mod scene_arg;
