//! The project's binary ray, hit and occlusion files (all little-endian):
//!
//! * ray file: per ray 8 × f32 `ox oy oz dx dy dz tnear tfar` (32 bytes);
//! * hit file: per ray `f32 t, u32 prim` (8 bytes); a miss is `t = +inf,
//!   prim = u32::MAX`; barycentrics are not stored;
//! * occlusion file: one byte per ray, 1 occluded, 0 not.

use crate::atomic::write_atomic;
use crate::error::LoadError;
use crate::input::read_file;
use raykit_core::{Hit, Ray, Vec3};
use std::io;
use std::path::Path;

/// Bytes per ray in a ray file.
pub const RAY_RECORD_SIZE: usize = 32;
/// Bytes per ray in a hit file.
pub const HIT_RECORD_SIZE: usize = 8;

fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

fn check_size(path: &Path, len: usize, record: usize, what: &str) -> Result<(), LoadError> {
    if !len.is_multiple_of(record) {
        return Err(LoadError::at_byte(
            path,
            (len - len % record) as u64,
            format!(
                "file size {len} is not a multiple of the {record}-byte {what} record: \
                 {} bytes left over after {} records (truncated?)",
                len % record,
                len / record
            ),
        ));
    }
    Ok(())
}

/// Read a ray file. Rays with a NaN or infinite origin or direction, a zero
/// direction or a NaN `tnear`/`tfar` are errors naming the ray and its byte
/// offset.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>, LoadError> {
    let data = read_file(path)?;
    check_size(path, data.len(), RAY_RECORD_SIZE, "ray")?;
    let mut rays = Vec::with_capacity(data.len() / RAY_RECORD_SIZE);
    for (i, r) in data.chunks_exact(RAY_RECORD_SIZE).enumerate() {
        let v: [f32; 8] = std::array::from_fn(|k| f32_at(r, 4 * k));
        let origin = Vec3::new(v[0], v[1], v[2]);
        let dir = Vec3::new(v[3], v[4], v[5]);
        let problem = if !origin.is_finite() {
            Some("origin is NaN or infinite")
        } else if !dir.is_finite() {
            Some("direction is NaN or infinite")
        } else if dir == Vec3::ZERO {
            Some("direction is zero")
        } else if v[6].is_nan() || v[7].is_nan() {
            Some("tnear or tfar is NaN")
        } else {
            None
        };
        if let Some(p) = problem {
            return Err(LoadError::at_byte(
                path,
                (i * RAY_RECORD_SIZE) as u64,
                format!("ray {i}: {p} ({v:?})"),
            ));
        }
        rays.push(Ray::segment(origin, dir, v[6], v[7]));
    }
    Ok(rays)
}

/// Write a ray file, atomically.
pub fn write_rays(path: &Path, rays: &[Ray]) -> io::Result<()> {
    write_atomic(path, |w| {
        for r in rays {
            let v = r.to_array();
            for x in v {
                w.write_all(&x.to_le_bytes())?;
            }
        }
        Ok(())
    })
}

/// Write a hit file (one record per ray, `None` for a miss), atomically.
pub fn write_hits(path: &Path, hits: &[Option<Hit>]) -> io::Result<()> {
    write_atomic(path, |w| {
        for h in hits {
            let (t, prim) = match h {
                Some(h) => (h.t, h.prim),
                None => (f32::INFINITY, u32::MAX),
            };
            w.write_all(&t.to_le_bytes())?;
            w.write_all(&prim.to_le_bytes())?;
        }
        Ok(())
    })
}

/// Read a hit file; `u` and `v` are not stored and read as 0. A record with
/// `prim = u32::MAX` must have `t = +inf` (a miss), and a hit must have a
/// non-NaN `t`.
pub fn read_hits(path: &Path) -> Result<Vec<Option<Hit>>, LoadError> {
    let data = read_file(path)?;
    check_size(path, data.len(), HIT_RECORD_SIZE, "hit")?;
    let mut hits = Vec::with_capacity(data.len() / HIT_RECORD_SIZE);
    for (i, r) in data.chunks_exact(HIT_RECORD_SIZE).enumerate() {
        let t = f32_at(r, 0);
        let prim = u32::from_le_bytes([r[4], r[5], r[6], r[7]]);
        let at = (i * HIT_RECORD_SIZE) as u64;
        if prim == u32::MAX {
            if t != f32::INFINITY {
                return Err(LoadError::at_byte(
                    path,
                    at,
                    format!("record {i}: prim is u32::MAX (a miss) but t is {t}, not +inf"),
                ));
            }
            hits.push(None);
        } else {
            if t.is_nan() {
                return Err(LoadError::at_byte(
                    path,
                    at,
                    format!("record {i}: hit on triangle {prim} has t = NaN"),
                ));
            }
            hits.push(Some(Hit {
                t,
                u: 0.0,
                v: 0.0,
                prim,
            }));
        }
    }
    Ok(hits)
}

/// Write an occlusion file (1 byte per ray), atomically.
pub fn write_occlusion(path: &Path, occluded: &[bool]) -> io::Result<()> {
    write_atomic(path, |w| {
        let bytes: Vec<u8> = occluded.iter().map(|&o| o as u8).collect();
        w.write_all(&bytes)
    })
}

/// Read an occlusion file; a byte other than 0 or 1 is an error naming its offset.
pub fn read_occlusion(path: &Path) -> Result<Vec<bool>, LoadError> {
    let data = read_file(path)?;
    data.iter()
        .enumerate()
        .map(|(i, &b)| match b {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(LoadError::at_byte(
                path,
                i as u64,
                format!("ray {i}: occlusion byte is {b}; expected 0 or 1"),
            )),
        })
        .collect()
}

/// Write `data` as the raw bytes of `path` (test helper for bad files).
#[cfg(test)]
fn raw(path: &Path, data: &[u8]) {
    std::fs::write(path, data).unwrap();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_ray_records_are_located() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.bin");
        let good = [0.0f32, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, f32::INFINITY];
        let mut bytes: Vec<u8> = good.iter().flat_map(|x| x.to_le_bytes()).collect();
        raw(&p, &bytes);
        assert_eq!(read_rays(&p).unwrap().len(), 1);
        let mut zero = good;
        zero[5] = 0.0;
        bytes.extend(zero.iter().flat_map(|x| x.to_le_bytes()));
        raw(&p, &bytes);
        let e = read_rays(&p).unwrap_err().to_string();
        assert!(
            e.contains("r.bin: byte 32: ray 1: direction is zero"),
            "{e}"
        );
        raw(&p, &bytes[..40]);
        let e = read_rays(&p).unwrap_err().to_string();
        assert!(
            e.contains("byte 32: file size 40 is not a multiple of the 32-byte"),
            "{e}"
        );
        let e = read_occlusion(&dir.path().join("missing.bin"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.bin: cannot read the file"), "{e}");
    }
}
