//! The binary files of point and multi-hit queries (little-endian): point
//! files in, and the answer files out — distances, inside flags, closest
//! points, hit counts and hit lists.

use crate::error::LoadError;
use crate::scene_hits::{scene_hit_record, write_scene_hit_record};
use raykit_core::instancing::SceneHit;
use raykit_core::query::{Answers, ClosestPoint};
use raykit_core::{Hit, Vec3};
use std::io::{self, Write};
use std::path::Path;

/// Bytes per point in a point file: 3 f32 x y z.
pub const POINT_RECORD_SIZE: usize = 12;

/// Read a point file: 3 little-endian f32 per point. Any values are
/// accepted (a NaN point has NaN answers); a size that is not a multiple of
/// [`POINT_RECORD_SIZE`] is an error naming the byte offset of the
/// incomplete record.
pub fn read_points(path: &Path) -> Result<Vec<Vec3>, LoadError> {
    let data = crate::input::read_file_cause_in_message(path)?;
    let rest = data.len() % POINT_RECORD_SIZE;
    if rest != 0 {
        let at = data.len() - rest;
        return Err(LoadError::at_byte(
            path,
            at as u64,
            format!(
                "file size {} is not a multiple of the {POINT_RECORD_SIZE}-byte point record: \
                 {rest} bytes left over after {} points (truncated?)",
                data.len(),
                data.len() / POINT_RECORD_SIZE
            ),
        ));
    }
    Ok(data
        .chunks_exact(POINT_RECORD_SIZE)
        .map(|r| {
            let f = |i: usize| f32::from_le_bytes([r[i], r[i + 1], r[i + 2], r[i + 3]]);
            Vec3::new(f(0), f(4), f(8))
        })
        .collect())
}

/// One f32 per point (distances).
pub fn write_f32s(w: &mut dyn Write, values: &[f32]) -> io::Result<()> {
    values
        .iter()
        .try_for_each(|x| w.write_all(&x.to_le_bytes()))
}

/// One u32 per ray (hit counts).
pub fn write_u32s(w: &mut dyn Write, values: &[u32]) -> io::Result<()> {
    values
        .iter()
        .try_for_each(|x| w.write_all(&x.to_le_bytes()))
}

/// One byte per point, 1 = inside.
pub fn write_flags(w: &mut dyn Write, flags: &[bool]) -> io::Result<()> {
    let bytes: Vec<u8> = flags.iter().map(|&x| u8::from(x)).collect();
    w.write_all(&bytes)
}

/// Per point f32 x y z distance, u32 triangle (20 bytes); NaN and
/// `u32::MAX` when there is no answer.
pub fn write_closest_points(w: &mut dyn Write, found: &[Option<ClosestPoint>]) -> io::Result<()> {
    for c in found {
        let (p, d, prim) = match c {
            Some(c) => (c.point.to_array(), c.distance, c.prim),
            None => ([f32::NAN; 3], f32::NAN, u32::MAX),
        };
        for x in p.into_iter().chain([d]) {
            w.write_all(&x.to_le_bytes())?;
        }
        w.write_all(&prim.to_le_bytes())?;
    }
    Ok(())
}

/// Per ray a u32 n, then n pairs f32 t, u32 triangle.
pub fn write_hit_lists(w: &mut dyn Write, lists: &[Vec<Hit>]) -> io::Result<()> {
    for l in lists {
        w.write_all(&(l.len() as u32).to_le_bytes())?;
        for h in l {
            w.write_all(&h.t.to_le_bytes())?;
            w.write_all(&h.prim.to_le_bytes())?;
        }
    }
    Ok(())
}

/// Per ray a u32 n, then n scene hit records (f32 t, u32 triangle, u32
/// geometry, u32 instance).
pub fn write_scene_hit_lists(w: &mut dyn Write, lists: &[Vec<SceneHit>]) -> io::Result<()> {
    for l in lists {
        w.write_all(&(l.len() as u32).to_le_bytes())?;
        for h in l {
            write_scene_hit_record(w, scene_hit_record(&Some(*h)))?;
        }
    }
    Ok(())
}

/// The answer file of `answers`: [`write_f32s`], [`write_flags`],
/// [`write_closest_points`], [`write_u32s`] or [`write_hit_lists`] by kind.
pub fn write_answers(w: &mut dyn Write, answers: &Answers) -> io::Result<()> {
    match answers {
        Answers::Distances(d) => write_f32s(w, d),
        Answers::Inside(i) => write_flags(w, i),
        Answers::Closest(c) => write_closest_points(w, c),
        Answers::Counts(c) => write_u32s(w, c),
        Answers::HitLists(l) => write_hit_lists(w, l),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_files_round_trip_and_truncation_names_the_byte() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.bin");
        let points = [Vec3::new(1.0, -2.5, 3.25), Vec3::new(f32::MAX, 0.0, -0.0)];
        let mut bytes = Vec::new();
        for p in points {
            for c in p.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(read_points(&path).unwrap(), points);
        bytes.extend_from_slice(&[0, 0, 0]);
        std::fs::write(&path, &bytes).unwrap();
        let err = read_points(&path).unwrap_err().to_string();
        assert!(err.contains("byte 24"), "{err}");
        let missing = read_points(&dir.path().join("none.bin")).unwrap_err();
        assert!(std::error::Error::source(&missing).is_none());
        assert!(
            missing.to_string().contains("none.bin: cannot read: "),
            "{missing}"
        );
    }

    #[test]
    fn hit_lists_are_counted_records() {
        let lists = vec![
            vec![],
            vec![Hit {
                t: 2.0,
                prim: 7,
                ..Default::default()
            }],
        ];
        let mut out = Vec::new();
        write_hit_lists(&mut out, &lists).unwrap();
        let mut expected = Vec::new();
        expected.extend_from_slice(&0u32.to_le_bytes());
        expected.extend_from_slice(&1u32.to_le_bytes());
        expected.extend_from_slice(&2.0f32.to_le_bytes());
        expected.extend_from_slice(&7u32.to_le_bytes());
        assert_eq!(out, expected);
    }
}
