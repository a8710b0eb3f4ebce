//! The files a mesh or scene file brings in besides itself: a glTF file's
//! external buffers and images, an OBJ file's MTL libraries and their
//! `map_Kd` textures. A command that writes files refuses an output that
//! would replace one of them, as it refuses one that would replace its input.

use crate::format::is_gzip_path;
use crate::gltf_glb::{is_glb, split_glb};
use crate::input::gunzip;
use crate::mtl::{texture_path, MAX_LIBRARY_FILE};
use crate::obj::library_names;
use crate::text::{Lines, Tokens};
use crate::uri::{external_file, read_external};
use std::io::Read;
use std::path::{Path, PathBuf};

/// The files that loading `path` reads besides `path` itself: glTF and GLB
/// buffers and images named by a file URI (beside or below its folder, the
/// only ones the loader reads), OBJ `mtllib` libraries that exist and the
/// `map_Kd` textures they name (wherever they are: an OBJ file may name
/// `../textures/wood.png`, so a caller that confines its inputs, as the
/// server does, checks these). A file that cannot be read or parsed gives none (loading it
/// reports the problem); other formats read no other file.
pub fn companion_files(path: &Path) -> Vec<PathBuf> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let plain = name.strip_suffix(".gz").unwrap_or(&name);
    let dir = path.parent().unwrap_or(Path::new(""));
    if plain.ends_with(".gltf") || plain.ends_with(".glb") {
        gltf_json(path)
            .map(|json| gltf_files(dir, &json))
            .unwrap_or_default()
    } else if plain.ends_with(".obj") {
        contents(path)
            .map(|data| obj_files(dir, &data))
            .unwrap_or_default()
    } else {
        Vec::new()
    }
}

/// The whole file, decompressed when its name ends in `.gz`.
fn contents(path: &Path) -> Option<Vec<u8>> {
    let data = std::fs::read(path).ok()?;
    if is_gzip_path(path) {
        gunzip(path, &data).ok()
    } else {
        Some(data)
    }
}

/// The JSON of a glTF file, or the JSON chunk of a GLB file (read without
/// the BIN chunk that follows it).
fn gltf_json(path: &Path) -> Option<Vec<u8>> {
    if is_gzip_path(path) {
        let data = contents(path)?;
        if !is_glb(&data) {
            return Some(data);
        }
        return split_glb(path, &data)
            .ok()
            .map(|(glb, _)| glb.json.to_vec());
    }
    let mut file = std::fs::File::open(path).ok()?;
    let mut head = [0u8; 20];
    let n = file.read(&mut head).ok()?;
    if n == 20 && is_glb(&head) {
        let len = u32::from_le_bytes([head[12], head[13], head[14], head[15]]) as u64;
        let mut json = Vec::new();
        file.take(len).read_to_end(&mut json).ok()?;
        return Some(json);
    }
    std::fs::read(path).ok()
}

fn gltf_files(dir: &Path, json: &[u8]) -> Vec<PathBuf> {
    let Ok(root) = ::gltf::json::Root::from_slice(json) else {
        return Vec::new();
    };
    let buffers = root.buffers.iter().filter_map(|b| b.uri.as_deref());
    let images = root.images.iter().filter_map(|i| i.uri.as_deref());
    buffers
        .chain(images)
        .filter(|uri| !uri.starts_with("data:"))
        .filter_map(|uri| external_file(dir, uri).ok())
        .collect()
}

fn obj_files(dir: &Path, data: &[u8]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for (_, line) in Lines::new(data, 1) {
        let mut toks = Tokens::new(line);
        if toks.next() != Some(b"mtllib".as_slice()) {
            continue;
        }
        for name in library_names(dir, toks.rest()) {
            let library = dir.join(name);
            let Ok(mtl) = read_external(&library, MAX_LIBRARY_FILE) else {
                continue;
            };
            let mtl_dir = library.parent().unwrap_or(Path::new("")).to_path_buf();
            for (_, line) in Lines::new(&mtl, 1) {
                let mut toks = Tokens::new(line);
                if toks.next() == Some(b"map_Kd".as_slice()) {
                    let file = String::from_utf8_lossy(texture_path(toks)).into_owned();
                    if !file.is_empty() {
                        out.push(mtl_dir.join(file));
                    }
                }
            }
            out.push(library);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gltf_buffers_and_images_and_obj_libraries_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let gltf = d.join("s.gltf");
        std::fs::write(
            &gltf,
            br#"{"asset":{"version":"2.0"},
                "buffers":[{"uri":"s.bin","byteLength":4},{"uri":"data:,abcd","byteLength":4},
                           {"uri":"../up.bin","byteLength":4}],
                "images":[{"uri":"tex%20a.png"}]}"#,
        )
        .unwrap();
        assert_eq!(
            companion_files(&gltf),
            vec![d.join("s.bin"), d.join("tex a.png")]
        );

        let obj = d.join("m.obj");
        std::fs::write(&obj, b"mtllib m.mtl missing.mtl\nv 0 0 0\n").unwrap();
        std::fs::write(d.join("m.mtl"), b"newmtl a\nmap_Kd -s 1 1 1 wood.png\n").unwrap();
        assert_eq!(
            companion_files(&obj),
            vec![d.join("wood.png"), d.join("m.mtl")]
        );

        // A GLB's JSON chunk is read without its BIN chunk.
        let mut json = br#"{"asset":{"version":"2.0"},"images":[{"uri":"t.png"}]}"#.to_vec();
        json.resize(json.len().next_multiple_of(4), b' ');
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend((20 + json.len() as u32).to_le_bytes());
        glb.extend((json.len() as u32).to_le_bytes());
        glb.extend(0x4E4F_534Au32.to_le_bytes());
        glb.extend(&json);
        std::fs::write(d.join("b.glb"), &glb).unwrap();
        assert_eq!(companion_files(&d.join("b.glb")), vec![d.join("t.png")]);

        std::fs::write(d.join("p.ply"), b"ply\n").unwrap();
        assert!(companion_files(&d.join("p.ply")).is_empty());
        assert!(companion_files(&d.join("absent.gltf")).is_empty());
    }
}
