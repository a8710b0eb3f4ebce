//! Mesh writers for every loadable format, so tools can write results (for
//! example culled meshes) in the format they read, and OpenEXR writers for
//! float images. All file output goes through
//! [`write_atomic`](crate::write_atomic) or
//! [`write_atomic_file`](crate::write_atomic_file).

mod exr;
mod gltf;
mod gltf_placed;
mod gltf_scene;
mod json;
mod obj;
mod off;
mod ply;
mod stl;

pub use self::exr::{write_exr_channels, write_exr_rgb};
pub use self::gltf::{write_gltf, write_gltf_scene};
pub use self::gltf_placed::{write_gltf_placed, PlacedMesh};
pub use obj::{write_mtl, write_obj};
pub use off::write_off;
pub use ply::write_ply;
pub use stl::write_stl;

use crate::atomic::OutputSet;
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
/// ends in `.gz`. For OBJ with materials, a material library `<stem>.mtl`
/// (the name without `.gz` and `.obj`) is written next to it, uncompressed,
/// and referenced with `mtllib`; the two are put in place together.
pub fn save_mesh_as(path: &Path, mesh: &TriangleMesh, format: MeshFormat) -> io::Result<()> {
    let mut set = OutputSet::new();
    stage_mesh_as(&mut set, path, mesh, format)?;
    set.commit()
}

/// [`save_mesh`] into `set`: the mesh (and its material library) are put in
/// place with the set's other outputs, when the set is committed.
pub fn stage_mesh(set: &mut OutputSet, path: &Path, mesh: &TriangleMesh) -> io::Result<()> {
    let format = MeshFormat::from_path(path).ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{}: unknown mesh file extension", path.display()),
        )
    })?;
    stage_mesh_as(set, path, mesh, format)
}

fn stage_mesh_as(
    set: &mut OutputSet,
    path: &Path,
    mesh: &TriangleMesh,
    format: MeshFormat,
) -> io::Result<()> {
    check(mesh)?;
    let gz = is_gzip_path(path);
    let mut mtllib = None;
    if format == MeshFormat::Obj && !mesh.materials.is_empty() {
        let plain = if gz {
            path.with_extension("")
        } else {
            path.to_path_buf()
        };
        let stem = plain
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "materials".into());
        let name = format!("{stem}.mtl");
        set.write(&path.with_file_name(&name), |w| {
            write_mtl(w, &mesh.materials)
        })?;
        mtllib = Some(name);
    }
    stage_compressed(set, path, |w| {
        write_format(w, mesh, format, mtllib.as_deref())
    })
}

/// Meshes stored once and placed by nodes ([`write_gltf_placed`]) into
/// `set`, as GLB or `.gltf` by the extension of `path` (gzip-compressed when
/// it ends in `.gz`); any other extension is refused.
pub fn stage_gltf_placed(
    set: &mut OutputSet,
    path: &Path,
    meshes: &[TriangleMesh],
    nodes: &[PlacedMesh],
) -> io::Result<()> {
    let binary = match MeshFormat::from_path(path) {
        Some(MeshFormat::Glb) => true,
        Some(MeshFormat::Gltf) => false,
        _ => {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "{}: placed meshes are written as .gltf or .glb",
                    path.display()
                ),
            ))
        }
    };
    stage_compressed(set, path, |w| {
        write_gltf_placed(w, meshes, nodes, None, &[], binary)
    })
}

/// `write` into `set` at `path`, through gzip when `path` ends in `.gz`.
fn stage_compressed(
    set: &mut OutputSet,
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    let gz = is_gzip_path(path);
    set.write(path, |w| {
        if gz {
            let mut z = GzEncoder::new(w, Compression::default());
            write(&mut z)?;
            z.finish()?;
            Ok(())
        } else {
            write(w)
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
