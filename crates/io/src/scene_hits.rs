//! The hit file of an instanced scene (`raykit trace` with several meshes
//! or `--instanced`): per ray `f32 t, u32 prim, u32 geometry, u32 instance`
//! (16 bytes, little-endian); a miss is `t = +inf` and all three ids
//! `u32::MAX`. `prim` is the triangle's index in its geometry's mesh. The
//! single-mesh hit file (8 bytes per ray, [`crate::write_hits`]) is its
//! first two fields.

use crate::atomic::write_atomic;
use crate::error::LoadError;
use crate::input::read_file;
use raykit_core::instancing::SceneHit;
use std::io::{self, Write};
use std::path::Path;

/// Bytes per ray in an instanced scene's hit file.
pub const SCENE_HIT_RECORD_SIZE: usize = 16;

/// The ids of a hit as stored: `(t, prim, geometry, instance)`; a miss as
/// `(+inf, u32::MAX, u32::MAX, u32::MAX)`.
pub type SceneHitRecord = (f32, u32, u32, u32);

/// The record of `hit`.
pub fn scene_hit_record(hit: &Option<SceneHit>) -> SceneHitRecord {
    match hit {
        Some(h) => (h.t, h.prim, h.geometry, h.instance),
        None => (f32::INFINITY, u32::MAX, u32::MAX, u32::MAX),
    }
}

/// Write one record.
pub fn write_scene_hit_record(w: &mut dyn Write, r: SceneHitRecord) -> io::Result<()> {
    w.write_all(&r.0.to_le_bytes())?;
    w.write_all(&r.1.to_le_bytes())?;
    w.write_all(&r.2.to_le_bytes())?;
    w.write_all(&r.3.to_le_bytes())
}

/// Write an instanced scene's hit file, atomically.
pub fn write_scene_hits(path: &Path, hits: &[Option<SceneHit>]) -> io::Result<()> {
    write_atomic(path, |w| {
        hits.iter()
            .try_for_each(|h| write_scene_hit_record(w, scene_hit_record(h)))
    })
}

/// Read an instanced scene's hit file. A size that is not a multiple of the
/// record, or a miss whose fields are not all the miss values, is an error
/// naming the byte offset.
pub fn read_scene_hits(path: &Path) -> Result<Vec<SceneHitRecord>, LoadError> {
    let data = read_file(path)?;
    let n = SCENE_HIT_RECORD_SIZE;
    if !data.len().is_multiple_of(n) {
        return Err(LoadError::at_byte(
            path,
            (data.len() - data.len() % n) as u64,
            format!(
                "file size {} is not a multiple of the {n}-byte scene hit record (truncated?)",
                data.len()
            ),
        ));
    }
    let mut out = Vec::with_capacity(data.len() / n);
    for (i, r) in data.chunks_exact(n).enumerate() {
        let u = |k: usize| u32::from_le_bytes([r[k], r[k + 1], r[k + 2], r[k + 3]]);
        let rec = (f32::from_bits(u(0)), u(4), u(8), u(12));
        let miss = [rec.1, rec.2, rec.3].map(|x| x == u32::MAX);
        if miss.iter().any(|&m| m) && (miss != [true; 3] || rec.0 != f32::INFINITY) {
            return Err(LoadError::at_byte(
                path,
                (i * n) as u64,
                format!(
                    "record {i}: a miss must have t = +inf and every id 4294967295, got {rec:?}"
                ),
            ));
        }
        out.push(rec);
    }
    Ok(out)
}
