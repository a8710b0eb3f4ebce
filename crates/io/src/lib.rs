//! raykit-io: reading and writing the files raykit works with.
//!
//! * Meshes: [`load_mesh`] (or [`load`], which also returns warnings and the
//!   detected encoding) reads OBJ (+MTL), PLY (ASCII and binary, also `.ply.gz`),
//!   STL (ASCII and binary), glTF/GLB and OFF into a validated
//!   [`TriangleMesh`](raykit_core::TriangleMesh), with decoded base-colour
//!   textures (glTF images, MTL `map_Kd`); a glTF file also gives its
//!   `KHR_lights_punctual` lights and first perspective camera
//!   ([`LoadedMesh::lights`], [`LoadedMesh::camera`]), and features it uses
//!   that are not supported are named in [`LoadedMesh::warnings`];
//!   [`load_gltf_instances`] reads a glTF file with its instancing kept
//!   (one geometry per mesh, one instance per node) for an instanced scene;
//!   [`save_mesh`] writes OBJ, PLY,
//!   STL, OFF, glTF and GLB. Every loader error is a [`LoadError`] naming the
//!   file and the line, byte or JSON element where the problem is.
//! * Ray, hit and occlusion files in the project's fixed binary layouts
//!   ([`read_rays`], [`write_hits`], …), and the hit file of an instanced
//!   scene with geometry and instance ids ([`write_scene_hits`]).
//! * Safe output: [`write_atomic`] (temporary file + rename) under every writer,
//!   and [`write_png`] ([`write_png_indexed`] for palette images); parts of a split image ([`write_png_part`],
//!   [`read_png_part`]) carry their place in the picture.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod atomic;
mod companions;
mod error;
mod far_origin;
mod format;
mod gltf;
mod gltf_accessor;
mod gltf_draco;
mod gltf_flat_size;
mod gltf_glb;
mod gltf_gpu_instancing;
mod gltf_image;
mod gltf_instances;
mod gltf_integers;
mod gltf_meshopt;
mod gltf_node_transforms;
mod gltf_scene;
mod gltf_shared_vertices;
mod gltf_support;
mod hashing;
mod image_merge;
mod image_part;
mod input;
pub use input::not_a_regular_file;
mod load;
mod mtl;
mod obj;
mod off;
mod ply;
mod ply_header;
mod png;
mod polygon;
mod query_files;
mod rays;
mod scene_hits;
mod stl;
mod text;
mod texture_image;
mod uri;
mod validate;
mod write;

pub use atomic::{remove_unfinished_outputs, write_atomic, write_atomic_file, OutputSet};
pub use companions::companion_files;
pub use error::{ErrorKind, LoadError, Location};
pub use format::{MeshFormat, PlyEncoding, StlEncoding};
pub use gltf_instances::{
    load_gltf_instances, load_gltf_instances_of, parse_gltf_instances, GltfInstance, GltfInstances,
};
pub use image_merge::{merge_png_parts, MergeError};
pub use image_part::{read_png_part, write_png_part, ImagePart, MAX_IMAGE_SIDE, PART_KEYWORD};
pub use load::{load, load_keeping_precision, load_mesh, parse_mesh, LoadedMesh};
pub use png::{write_png, write_png_indexed};
pub use query_files::{
    read_points, write_answers, write_closest_points, write_f32s, write_flags, write_hit_lists,
    write_scene_hit_lists, write_u32s, POINT_RECORD_SIZE,
};
pub use rays::{
    read_hits, read_occlusion, read_rays, write_hits, write_occlusion, write_rays, HIT_RECORD_SIZE,
    RAY_RECORD_SIZE,
};
pub use scene_hits::{
    read_scene_hits, scene_hit_record, write_scene_hit_record, write_scene_hits, SceneHitRecord,
    SCENE_HIT_RECORD_SIZE,
};
pub use write::{
    save_mesh, save_mesh_as, stage_gltf_placed, stage_mesh, write_exr_channels, write_exr_rgb,
    write_gltf, write_gltf_placed, write_gltf_scene, write_mesh, write_mtl, write_obj, write_off,
    write_ply, write_stl, PlacedMesh,
};
