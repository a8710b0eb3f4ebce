//! Wavefront MTL material libraries.
//!
//! Read statements: `newmtl`, `Kd`, `Ks`, `Ke`, `Ns`, `Ni`, `d`, `Tr`, `illum`,
//! `map_Kd`; others are ignored. Mapping to [`Material`]: `diffuse = Kd`,
//! `specular = Ks`, `shininess = Ns`, `ior = Ni`, `emission = Ke`,
//! `transmission = 1 - d` (or `Tr`), `reflectivity = max(Ks)` for the
//! reflective illumination models 3 to 7 and 0 otherwise. `map_Kd` options
//! (`-o`, `-s`, `-bm`, …) are skipped and the texture path is resolved against
//! the MTL file's folder.
//!
//! The `map_Kd` image (PNG or JPEG) is decoded into `base_texture`, once per
//! file name and shared between the materials naming it; an image that
//! cannot be read or decoded gives a warning. OBJ texture coordinates have
//! `v = 0` at the bottom of the image while [`raykit_core::Texture`] puts
//! `v = 0` in its first row, so the decoded rows are stored bottom first:
//! the file's texture coordinates are kept as they are and sample the image
//! the right way up.

use crate::error::{show, LoadError};
use crate::text::{parse_f32, parse_i64, Lines, Tokens};
use crate::texture_image::{decode_texture, Rows};
use crate::uri::read_external;
use raykit_core::{Material, Texture};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Largest texture file read (the decoders bound what it decodes to).
pub(crate) const MAX_TEXTURE_FILE: u64 = 1 << 30;

/// Largest MTL library read.
pub(crate) const MAX_LIBRARY_FILE: u64 = 1 << 28;

/// Decoded `map_Kd` textures by file (canonical path where it resolves),
/// shared by every library of one OBJ file, so that an image named twice,
/// under two spellings or by two libraries, is decoded once; none where it
/// could not be.
pub(crate) type TextureCache = HashMap<PathBuf, Option<Arc<Texture>>>;

/// Parse the MTL library `data` read from `path`: materials and warnings;
/// textures come from and go to `textures`.
pub(crate) fn parse_mtl(
    path: &Path,
    data: &[u8],
    textures: &mut TextureCache,
) -> Result<(Vec<Material>, Vec<String>), LoadError> {
    let mut warnings = Vec::new();
    let mut out: Vec<Material> = Vec::new();
    let mut illum: i64 = 2;
    let dir = path.parent().unwrap_or(Path::new(""));
    for (line, text) in Lines::new(data, 1) {
        let mut toks = Tokens::new(text);
        let Some(key) = toks.next() else { continue };
        if key.starts_with(b"#") {
            continue;
        }
        if key == b"newmtl" {
            if let Some(m) = out.last_mut() {
                apply_illum(m, illum);
            }
            illum = 2;
            out.push(Material {
                name: String::from_utf8_lossy(toks.rest()).into_owned(),
                ..Material::default()
            });
            continue;
        }
        let known = matches!(
            key,
            b"Kd" | b"Ks" | b"Ke" | b"Ns" | b"Ni" | b"d" | b"Tr" | b"illum" | b"map_Kd"
        );
        if !known {
            continue;
        }
        let key_str = String::from_utf8_lossy(key);
        let Some(m) = out.last_mut() else {
            return Err(LoadError::at_line(
                path,
                line,
                format!("'{key_str}' before the first 'newmtl'"),
            ));
        };
        let number = |t: Option<&[u8]>| -> Result<f32, LoadError> {
            match t.and_then(parse_f32) {
                Some(v) if v.is_finite() => Ok(v),
                _ => Err(LoadError::at_line(
                    path,
                    line,
                    format!("expected a number after '{key_str}', found {}", show(t)),
                )),
            }
        };
        match key {
            b"Kd" | b"Ks" | b"Ke" => {
                let first = toks.clone().next();
                if matches!(first, Some(b"spectral") | Some(b"xyz")) {
                    continue; // Spectral and CIE XYZ colours are not read.
                }
                let r = number(toks.next())?;
                let rest = toks.next();
                let rgb = if rest.is_none() {
                    [r; 3]
                } else {
                    [r, number(rest)?, number(toks.next())?]
                };
                // Reflectances are fractions; emission is not negative.
                match key {
                    b"Kd" => m.diffuse = rgb.map(|x| x.clamp(0.0, 1.0)),
                    b"Ks" => m.specular = rgb.map(|x| x.clamp(0.0, 1.0)),
                    _ => m.emission = rgb.map(|x| x.max(0.0)),
                }
            }
            b"Ns" => m.shininess = number(toks.next())?.clamp(0.0, 1e4),
            // Exporters write `Ni 0` for "not set"; an index below 1 would
            // bend rays away from the normal, so it is read as 1.
            b"Ni" => m.ior = number(toks.next())?.clamp(1.0, 10.0),
            b"d" => {
                let mut t = toks.next();
                if t == Some(b"-halo") {
                    t = toks.next();
                }
                m.transmission = (1.0 - number(t)?).clamp(0.0, 1.0);
            }
            b"Tr" => m.transmission = number(toks.next())?.clamp(0.0, 1.0),
            b"illum" => {
                let t = toks.next();
                illum = t.and_then(parse_i64).ok_or_else(|| {
                    LoadError::at_line(
                        path,
                        line,
                        format!("expected an integer after 'illum', found {}", show(t)),
                    )
                })?;
            }
            _ => {
                let file = texture_path(toks);
                if file.is_empty() {
                    return Err(LoadError::at_line(
                        path,
                        line,
                        "expected a file name after 'map_Kd'",
                    ));
                }
                let file = String::from_utf8_lossy(file).into_owned();
                let joined = dir.join(file);
                let full = joined.to_string_lossy().into_owned();
                let key = std::fs::canonicalize(&joined).unwrap_or(joined);
                m.base_texture = textures
                    .entry(key)
                    .or_insert_with(|| match load_texture(&full) {
                        Ok(t) => Some(Arc::new(t)),
                        Err(why) => {
                            warnings.push(format!(
                                "{}:{line}: map_Kd texture not loaded: {why}",
                                path.display()
                            ));
                            None
                        }
                    })
                    .clone();
                m.diffuse_texture = Some(full);
            }
        }
    }
    if let Some(m) = out.last_mut() {
        apply_illum(m, illum);
    }
    Ok((out, warnings))
}

/// Read and decode the texture file `file` (rows bottom first, see the
/// module documentation).
fn load_texture(file: &str) -> Result<Texture, String> {
    let bytes = read_external(Path::new(file), MAX_TEXTURE_FILE)?;
    decode_texture(file, &bytes, Rows::BottomFirst)
        .map_err(|e| format!("cannot decode {file}: {e}"))
}

fn apply_illum(m: &mut Material, illum: i64) {
    m.reflectivity = if (3..=7).contains(&illum) {
        m.specular
            .iter()
            .fold(0.0f32, |a, &b| a.max(b))
            .clamp(0.0, 1.0)
    } else {
        0.0
    };
}

/// The file name of a `map_*` statement after its options.
pub(crate) fn texture_path(mut toks: Tokens<'_>) -> &[u8] {
    loop {
        let before = toks.clone();
        let Some(t) = toks.next() else {
            return b"";
        };
        let args = match t {
            b"-blendu" | b"-blendv" | b"-bm" | b"-boost" | b"-cc" | b"-clamp" | b"-imfchan"
            | b"-texres" | b"-type" => 1,
            b"-mm" => 2,
            b"-o" | b"-s" | b"-t" => {
                // One to three numbers.
                for _ in 0..3 {
                    let peek = toks.clone().next();
                    if peek.and_then(parse_f32).is_some() {
                        toks.next();
                    } else {
                        break;
                    }
                }
                0
            }
            _ => return before.rest(),
        };
        for _ in 0..args {
            toks.next();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_every_mapped_statement() {
        let src = b"# lib\nnewmtl red\nKd 1 0 0\nKs 0.5 0.5 0.5\nNs 10\nNi 1.33\nd 0.25\n\
illum 3\nKe 0 0 2\nmap_Kd -o 0.1 0.2 -bm 1.0 tex/red wood.png\n\
newmtl gray\nKd 0.3\nTr 0.5\n";
        let (m, w) = parse_mtl(Path::new("dir/a.mtl"), src, &mut TextureCache::new()).unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with(
                "dir/a.mtl:10: map_Kd texture not loaded: cannot read dir/tex/red wood.png"
            ),
            "{w:?}"
        );
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].name, "red");
        assert_eq!(m[0].diffuse, [1.0, 0.0, 0.0]);
        assert_eq!(m[0].specular, [0.5; 3]);
        assert_eq!(m[0].shininess, 10.0);
        assert_eq!(m[0].ior, 1.33);
        assert_eq!(m[0].transmission, 0.75);
        assert_eq!(m[0].reflectivity, 0.5);
        assert_eq!(m[0].emission, [0.0, 0.0, 2.0]);
        let tex = Path::new("dir").join("tex/red wood.png");
        assert_eq!(m[0].diffuse_texture.as_deref(), Some(tex.to_str().unwrap()));
        assert_eq!(m[1].diffuse, [0.3; 3]);
        assert_eq!(m[1].transmission, 0.5);
        assert_eq!(m[1].reflectivity, 0.0);
    }

    #[test]
    fn values_outside_their_ranges_are_clamped() {
        let src =
            b"newmtl odd\nKd -1 2 0.5\nKs 3\nKe -1 0 5\nNs -20\nNi 0\nnewmtl big\nNs 1e9\nNi 40\n";
        let (m, _) = parse_mtl(Path::new("a.mtl"), src, &mut TextureCache::new()).unwrap();
        assert_eq!(m[0].diffuse, [0.0, 1.0, 0.5]);
        assert_eq!(m[0].specular, [1.0; 3]);
        assert_eq!(m[0].emission, [0.0, 0.0, 5.0]);
        assert_eq!((m[0].shininess, m[0].ior), (0.0, 1.0));
        assert_eq!((m[1].shininess, m[1].ior), (1e4, 10.0));
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse_mtl(
            Path::new("a.mtl"),
            b"newmtl x\nKd 1 zz 0\n",
            &mut TextureCache::new(),
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.mtl:2: expected a number after 'Kd', found 'zz'"
        );
        let e = parse_mtl(Path::new("a.mtl"), b"Kd 1 1 1\n", &mut TextureCache::new()).unwrap_err();
        assert!(e.to_string().starts_with("a.mtl:1: "));
        let e = parse_mtl(
            Path::new("a.mtl"),
            b"newmtl x\nNs nan\n",
            &mut TextureCache::new(),
        )
        .unwrap_err();
        assert!(e.to_string().starts_with("a.mtl:2: "));
    }
}
