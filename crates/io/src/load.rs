//! Loading a mesh file of any supported format, chosen by its extension.

use crate::error::{ErrorKind, LoadError, Location};
use crate::far_origin::FarOrigin;
use crate::format::{is_gzip_path, MeshFormat};
use crate::input::{gunzip, read_file};
use raykit_core::{Camera, Light, TriangleMesh};
use std::path::Path;

/// A loaded mesh with what the loader noticed along the way.
#[derive(Clone, Debug)]
pub struct LoadedMesh {
    /// The mesh; it has at least one triangle and passes `TriangleMesh::validate`.
    pub mesh: TriangleMesh,
    /// Things skipped or approximated (for example glTF primitives that are not
    /// triangles), one sentence each.
    pub warnings: Vec<String>,
    /// The format and encoding found in the file, e.g. to write a result in
    /// the same format with [`save_mesh_as`](crate::save_mesh_as).
    pub format: MeshFormat,
    /// True when the file was gzip-compressed.
    pub gzip: bool,
    /// Lights the file defines (glTF `KHR_lights_punctual`); empty for other
    /// formats.
    pub lights: Vec<Light>,
    /// The camera the file defines (glTF: the first perspective camera);
    /// `None` for other formats.
    pub camera: Option<Camera>,
    /// The point the positions, lights and camera are stored relative to:
    /// zero, except for a
    /// mesh loaded by [`load_keeping_precision`] whose first vertex lies far
    /// from the coordinates' origin, where the file's coordinates are
    /// `position + origin` in `f64`.
    pub origin: [f64; 3],
}

/// Load the triangle mesh in `path`, choosing the format by the extension
/// (case-insensitive): `.obj`, `.ply`, `.stl`, `.off`, `.gltf`, `.glb`, each
/// optionally followed by `.gz`.
pub fn load_mesh(path: &Path) -> Result<TriangleMesh, LoadError> {
    load(path).map(|l| l.mesh)
}

/// Like [`load_mesh`], also returning the warnings and the detected encoding.
pub fn load(path: &Path) -> Result<LoadedMesh, LoadError> {
    load_with(path, FarOrigin::new(false))
}

/// Like [`load`], but a mesh whose first vertex lies far from the
/// coordinates' origin (a coordinate of 65,536 or more, as projected GIS
/// and CAD data do) is read in `f64` and stored relative to an origin near
/// that vertex ([`LoadedMesh::origin`]), keeping the precision `f32` loses
/// there: OBJ, OFF and PLY (ASCII, or binary `double`), and glTF placed far
/// by its nodes' transforms (composed in `f64`; its lights and camera are
/// stored relative to the same origin). STL stores `f32` and loads as with
/// [`load`].
pub fn load_keeping_precision(path: &Path) -> Result<LoadedMesh, LoadError> {
    load_with(path, FarOrigin::new(true))
}

fn load_with(path: &Path, far: FarOrigin) -> Result<LoadedMesh, LoadError> {
    // Reject unknown extensions before touching the file.
    format_of(path)?;
    let bytes = read_file(path)?;
    parse_with(path, &bytes, far)
}

/// Parse `bytes`, the contents of a file named `path`. The name chooses the
/// format (as in [`load_mesh`]), appears in error messages and is the base
/// for resources the file refers to (MTL libraries, glTF buffers).
pub fn parse_mesh(path: &Path, bytes: &[u8]) -> Result<LoadedMesh, LoadError> {
    parse_with(path, bytes, FarOrigin::new(false))
}

fn parse_with(path: &Path, bytes: &[u8], far: FarOrigin) -> Result<LoadedMesh, LoadError> {
    let format = format_of(path)?;
    if is_gzip_path(path) {
        let data = gunzip(path, bytes)?;
        let mut loaded =
            parse_plain(path, &data, format, far).map_err(|e| e.in_decompressed(path))?;
        loaded.gzip = true;
        Ok(loaded)
    } else {
        parse_plain(path, bytes, format, far)
    }
}

fn format_of(path: &Path) -> Result<MeshFormat, LoadError> {
    MeshFormat::from_path(path).ok_or_else(|| {
        LoadError::new(
            path,
            ErrorKind::UnknownFormat,
            Location::File,
            "unknown mesh file extension: expected .obj, .ply, .stl, .off, .gltf or .glb \
             (optionally followed by .gz)",
        )
    })
}

fn parse_plain(
    path: &Path,
    data: &[u8],
    format: MeshFormat,
    mut far: FarOrigin,
) -> Result<LoadedMesh, LoadError> {
    let mut lights = Vec::new();
    let mut camera = None;
    let (mesh, warnings, format) = match format {
        MeshFormat::Obj => {
            let (m, w) = crate::obj::parse_obj(path, data, &mut far)?;
            (m, w, MeshFormat::Obj)
        }
        MeshFormat::Ply(_) => {
            let (m, w, enc) = crate::ply::parse_ply(path, data, &mut far)?;
            (m, w, MeshFormat::Ply(enc))
        }
        MeshFormat::Stl(_) => {
            let (m, enc) = crate::stl::parse_stl(path, data)?;
            (m, Vec::new(), MeshFormat::Stl(enc))
        }
        MeshFormat::Off => {
            let (m, w) = crate::off::parse_off(path, data, &mut far)?;
            (m, w, MeshFormat::Off)
        }
        MeshFormat::Gltf | MeshFormat::Glb => {
            let g = crate::gltf::parse_gltf(path, data, &mut far)?;
            let f = if g.glb {
                MeshFormat::Glb
            } else {
                MeshFormat::Gltf
            };
            lights = g.lights;
            camera = g.camera;
            (g.mesh, g.warnings, f)
        }
    };
    Ok(LoadedMesh {
        mesh,
        warnings,
        format,
        gzip: false,
        lights,
        camera,
        origin: far.origin(),
    })
}
