//! Mesh writers for every loadable format, so tools can write results (for
//! example culled meshes) in the format they read, and OpenEXR writers for
//! float images. All file output goes through
//! [`write_atomic`](crate::write_atomic) or
//! [`write_atomic_file`](crate::write_atomic_file).

mod exr;
mod gltf;
mod gltf_scene;
mod json;
mod obj;
mod off;
mod ply;
mod stl;

pub use self::exr::{write_exr_channels, write_exr_rgb};
pub use self::gltf::{write_gltf, write_gltf_scene};
pub use obj::{write_mtl, write_obj};
pub use off::write_off;
pub use ply::write_ply;
pub use stl::write_stl;

use crate::atomic::write_atomic;
use crate::format::{is_gzip_path, MeshFormat};
use flate2::write::GzEncoder;
use flate2::Compression;
use raykit_core::TriangleMesh;
use std::io::{self, Write};
use std::path::Path;

/// Write `mesh` in `format` to `w`. OBJ is written without a material library.
pub fn write_mesh(w: &mut dyn Write, mesh: &TriangleMesh, format: MeshFormat) -> io::Result<()> {
    match format {
        MeshFormat::Obj => write_obj(w, mesh, None),
        MeshFormat::Ply(enc) => write_ply(w, mesh, enc),
        MeshFormat::Stl(enc) => write_stl(w, mesh, enc),
        MeshFormat::Off => write_off(w, mesh),
        MeshFormat::Gltf => write_gltf(w, mesh, false),
        MeshFormat::Glb => write_gltf(w, mesh, true),
    }
}

/// Save `mesh` to `path` in the format its extension names (binary
/// little-endian PLY, binary STL; gzip-compressed when the name ends in `.gz`).
pub fn save_mesh(path: &Path, mesh: &TriangleMesh) -> io::Result<()> {
    let format = MeshFormat::from_path(path).ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: unknown mesh file extension", path.display()),
        )
    })?;
    save_mesh_as(path, mesh, format)
}

/// Save `mesh` to `path` in `format`, atomically; gzip-compressed when `path`
/// ends in `.gz`. For OBJ with materials, a material library `<stem>.mtl` is
/// written next to it and referenced with `mtllib`.
pub fn save_mesh_as(path: &Path, mesh: &TriangleMesh, format: MeshFormat) -> io::Result<()> {
    check(mesh)?;
    let gz = is_gzip_path(path);
    let mut mtllib = None;
    if format == MeshFormat::Obj && !mesh.materials.is_empty() && !gz {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "materials".into());
        let name = format!("{stem}.mtl");
        write_atomic(&path.with_file_name(&name), |w| {
            write_mtl(w, &mesh.materials)
        })?;
        mtllib = Some(name);
    }
    write_atomic(path, |w| {
        if gz {
            let mut z = GzEncoder::new(w, Compression::default());
            write_format(&mut z, mesh, format, mtllib.as_deref())?;
            z.finish()?;
            Ok(())
        } else {
            write_format(w, mesh, format, mtllib.as_deref())
        }
    })
}

fn write_format(
    w: &mut dyn Write,
    mesh: &TriangleMesh,
    format: MeshFormat,
    mtllib: Option<&str>,
) -> io::Result<()> {
    match format {
        MeshFormat::Obj => write_obj(w, mesh, mtllib),
        f => write_mesh(w, mesh, f),
    }
}

/// The mesh must be valid to be written.
pub(crate) fn check(mesh: &TriangleMesh) -> io::Result<()> {
    mesh.validate().map_err(|e| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("cannot write an invalid mesh: {e}"),
        )
    })
}
