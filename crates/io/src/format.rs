//! Mesh file formats and their encodings, recognised from file names.

use std::path::Path;

/// Encoding of a PLY file body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlyEncoding {
    /// `format ascii 1.0`.
    Ascii,
    /// `format binary_little_endian 1.0`.
    BinaryLittleEndian,
    /// `format binary_big_endian 1.0`.
    BinaryBigEndian,
}

/// Encoding of an STL file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StlEncoding {
    /// `solid … endsolid` text.
    Ascii,
    /// 80-byte header, triangle count, 50 bytes per triangle.
    Binary,
}

/// A mesh file format, with its encoding where the format has several.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (materials in a separate MTL file).
    Obj,
    /// Stanford PLY.
    Ply(PlyEncoding),
    /// STL.
    Stl(StlEncoding),
    /// Object File Format (Geomview OFF).
    Off,
    /// glTF 2.0 JSON (`.gltf`), buffers external or embedded as data URIs.
    Gltf,
    /// Binary glTF 2.0 (`.glb`).
    Glb,
}

impl MeshFormat {
    /// The format named by `path`'s extension (case-insensitive; a final `.gz` is
    /// looked through), with the default encoding for writing: binary little-endian
    /// PLY and binary STL. `None` for an unknown extension.
    pub fn from_path(path: &Path) -> Option<MeshFormat> {
        let name = path.file_name()?.to_str()?.to_ascii_lowercase();
        let name = name.strip_suffix(".gz").unwrap_or(&name);
        let ext = name.rsplit_once('.')?.1;
        Some(match ext {
            "obj" => MeshFormat::Obj,
            "ply" => MeshFormat::Ply(PlyEncoding::BinaryLittleEndian),
            "stl" => MeshFormat::Stl(StlEncoding::Binary),
            "off" => MeshFormat::Off,
            "gltf" => MeshFormat::Gltf,
            "glb" => MeshFormat::Glb,
            _ => return None,
        })
    }

    /// Whether this is glTF, as JSON or binary.
    pub fn is_gltf(self) -> bool {
        matches!(self, MeshFormat::Gltf | MeshFormat::Glb)
    }

    /// The usual file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Obj => "obj",
            MeshFormat::Ply(_) => "ply",
            MeshFormat::Stl(_) => "stl",
            MeshFormat::Off => "off",
            MeshFormat::Gltf => "gltf",
            MeshFormat::Glb => "glb",
        }
    }
}

/// True when `path` ends in `.gz` (case-insensitive).
pub(crate) fn is_gzip_path(path: &Path) -> bool {
    path.file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.to_ascii_lowercase().ends_with(".gz"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions_are_case_insensitive_and_see_through_gz() {
        let f = |s: &str| MeshFormat::from_path(Path::new(s));
        assert_eq!(f("a/B.OBJ"), Some(MeshFormat::Obj));
        assert_eq!(
            f("dragon.ply.gz"),
            Some(MeshFormat::Ply(PlyEncoding::BinaryLittleEndian))
        );
        assert_eq!(f("x.Stl"), Some(MeshFormat::Stl(StlEncoding::Binary)));
        assert_eq!(f("x.glb"), Some(MeshFormat::Glb));
        assert_eq!(f("x.txt"), None);
        assert_eq!(f("noext"), None);
        assert_eq!(f("x.gz"), None);
        assert!(is_gzip_path(Path::new("a.PLY.GZ")));
        assert!(!is_gzip_path(Path::new("a.ply")));
    }
}
