//! The binary glTF (GLB) container: a 12-byte header, a JSON chunk and an
//! optional BIN chunk, checked with byte-located errors.

use crate::error::LoadError;
use std::path::Path;

const MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// True when `data` starts with the GLB magic.
pub(crate) fn is_glb(data: &[u8]) -> bool {
    data.starts_with(MAGIC)
}

/// The JSON and BIN chunks of a GLB file, and the byte offset of the JSON.
pub(crate) struct Glb<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
}

fn u32_at(data: &[u8], at: usize) -> Option<u32> {
    let b = data.get(at..at + 4)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Split a GLB file into its chunks.
pub(crate) fn split_glb<'a>(
    path: &Path,
    data: &'a [u8],
) -> Result<(Glb<'a>, Vec<String>), LoadError> {
    let err = |at: usize, msg: String| LoadError::at_byte(path, at as u64, msg);
    let mut warnings = Vec::new();
    if data.len() < 12 {
        return Err(err(
            data.len(),
            format!(
                "file ends inside the 12-byte GLB header ({} bytes, truncated?)",
                data.len()
            ),
        ));
    }
    let version = u32_at(data, 4).unwrap_or(0);
    if version != 2 {
        return Err(err(
            4,
            format!("GLB version {version}; only version 2 is supported"),
        ));
    }
    let declared = u32_at(data, 8).unwrap_or(0) as usize;
    if declared > data.len() {
        return Err(err(
            8,
            format!(
                "the header says the file has {declared} bytes, but it has {} (truncated?)",
                data.len()
            ),
        ));
    }
    if declared < data.len() {
        warnings.push(format!(
            "{} bytes after the GLB length given in the header ignored",
            data.len() - declared
        ));
    }
    let data = &data[..declared];
    let mut json = None;
    let mut bin = None;
    let mut pos = 12;
    while pos < data.len() {
        let (Some(len), Some(ty)) = (u32_at(data, pos), u32_at(data, pos + 4)) else {
            return Err(err(
                pos,
                "file ends inside a chunk header (truncated?)".into(),
            ));
        };
        let start = pos + 8;
        let end = start.checked_add(len as usize).filter(|&e| e <= data.len());
        let Some(end) = end else {
            return Err(err(
                pos,
                format!(
                    "chunk of {len} bytes runs past the end of the file ({} bytes left, truncated?)",
                    data.len() - start
                ),
            ));
        };
        match ty {
            CHUNK_JSON if json.is_none() && pos == 12 => json = Some(&data[start..end]),
            CHUNK_BIN if bin.is_none() && json.is_some() => bin = Some(&data[start..end]),
            _ if pos == 12 => {
                return Err(err(pos + 4, "the first chunk is not the JSON chunk".into()));
            }
            _ => {} // Unknown chunks are skipped, as the specification asks.
        }
        pos = end;
    }
    let json = json.ok_or_else(|| err(12, "no JSON chunk".into()))?;
    Ok((Glb { json, bin }, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
        let mut v = b"glTF".to_vec();
        v.extend_from_slice(&2u32.to_le_bytes());
        let total = 12 + 8 + json.len() + 8 + bin.len();
        v.extend_from_slice(&(total as u32).to_le_bytes());
        v.extend_from_slice(&(json.len() as u32).to_le_bytes());
        v.extend_from_slice(&CHUNK_JSON.to_le_bytes());
        v.extend_from_slice(json);
        v.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        v.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        v.extend_from_slice(bin);
        v
    }

    #[test]
    fn splits_and_rejects_truncation() {
        let p = Path::new("a.glb");
        let d = glb(b"{}  ", b"12345678");
        let (g, w) = split_glb(p, &d).unwrap();
        assert_eq!(g.json, b"{}  ");
        assert_eq!(g.bin, Some(&b"12345678"[..]));
        assert!(w.is_empty());
        for cut in 0..d.len() {
            let e = split_glb(p, &d[..cut]).err().unwrap().to_string();
            assert!(e.starts_with("a.glb: byte "), "{e}");
        }
        let mut bad = d.clone();
        bad[24] = 200; // BIN chunk length
        let mut fixed = bad.clone();
        fixed[8] = 200;
        let e = split_glb(p, &bad).err().unwrap().to_string();
        assert!(e.contains("byte 24: chunk of 200 bytes"), "{e}");
        let e = split_glb(p, &fixed).err().unwrap().to_string();
        assert!(e.contains("byte 8:"), "{e}");
    }
}
