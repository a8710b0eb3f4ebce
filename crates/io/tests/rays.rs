//! Ray, hit and occlusion files: round trips of random data, the byte layout
//! checked by decoding the files by hand, and bad sizes and records.

mod common;

use raykit_core::rng::Pcg32;
use raykit_core::{Hit, Ray, Vec3};
use raykit_io::{
    read_hits, read_occlusion, read_rays, write_hits, write_occlusion, write_rays, ErrorKind,
    Location,
};

fn random_rays(n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Pcg32::new(seed);
    (0..n)
        .map(|i| {
            let o = rng.in_box(Vec3::splat(-10.0), Vec3::splat(10.0));
            let d = rng.unit_vector() * rng.range_f32(0.5, 2.0);
            let tfar = if i % 3 == 0 {
                f32::INFINITY
            } else {
                rng.range_f32(1.0, 100.0)
            };
            Ray::segment(o, d, rng.range_f32(0.0, 0.01), tfar)
        })
        .collect()
}

fn le_f32(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

#[test]
fn rays_round_trip_and_match_the_layout() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("rays.bin");
    let rays = random_rays(1000, 7);
    write_rays(&p, &rays).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(bytes.len(), 32 * rays.len());
    for (i, r) in rays.iter().enumerate() {
        let f: Vec<f32> = (0..8).map(|k| le_f32(&bytes, 32 * i + 4 * k)).collect();
        let expect = [
            r.origin.x,
            r.origin.y,
            r.origin.z,
            r.dir().x,
            r.dir().y,
            r.dir().z,
            r.tnear,
            r.tfar,
        ];
        assert_eq!(f, expect, "ray {i}");
    }
    let back = read_rays(&p).unwrap();
    assert_eq!(back, rays);
    // inv_dir is rebuilt by Ray::segment.
    assert_eq!(back[5].inv_dir(), Vec3::ONE / rays[5].dir());
    // Empty file: no rays.
    write_rays(&p, &[]).unwrap();
    assert!(read_rays(&p).unwrap().is_empty());
}

#[test]
fn bad_ray_files_name_the_ray_or_byte() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad_rays.bin");
    let rays = random_rays(10, 1);
    write_rays(&p, &rays).unwrap();
    let good = std::fs::read(&p).unwrap();
    for cut in [1, 31, 33, 100, 319] {
        std::fs::write(&p, &good[..cut]).unwrap();
        let e = read_rays(&p).unwrap_err();
        let whole = cut - cut % 32;
        assert_eq!(e.location(), &Location::Byte(whole as u64));
        assert!(
            e.to_string()
                .contains(&format!("bad_rays.bin: byte {whole}: file size {cut} is not a multiple of the 32-byte ray record")),
            "{e}"
        );
    }
    for (field, value, what) in [
        (1, f32::NAN, "origin is NaN or infinite"),
        (2, f32::INFINITY, "origin is NaN or infinite"),
        (4, f32::NAN, "direction is NaN or infinite"),
        (6, f32::NAN, "tnear or tfar is NaN"),
    ] {
        let mut b = good.clone();
        b[32 * 7 + 4 * field..32 * 7 + 4 * field + 4].copy_from_slice(&value.to_le_bytes());
        std::fs::write(&p, &b).unwrap();
        let e = read_rays(&p).unwrap_err().to_string();
        assert!(
            e.contains(&format!("bad_rays.bin: byte 224: ray 7: {what}")),
            "{e}"
        );
    }
    let mut b = good.clone();
    b[32 * 3 + 12..32 * 3 + 24].fill(0);
    std::fs::write(&p, &b).unwrap();
    let e = read_rays(&p).unwrap_err().to_string();
    assert!(e.contains("byte 96: ray 3: direction is zero"), "{e}");
    let e = read_rays(&dir.path().join("none.bin")).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Io);
}

#[test]
fn hits_round_trip_with_misses() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("hits.bin");
    let mut rng = Pcg32::new(3);
    let hits: Vec<Option<Hit>> = (0..500)
        .map(|i| {
            (i % 4 != 0).then(|| Hit {
                t: rng.range_f32(0.0, 50.0),
                u: rng.next_f32(),
                v: rng.next_f32(),
                prim: rng.below(1_000_000),
            })
        })
        .collect();
    write_hits(&p, &hits).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(bytes.len(), 8 * hits.len());
    // Miss records: t = +inf, prim = u32::MAX.
    assert_eq!(le_f32(&bytes, 0), f32::INFINITY);
    assert_eq!(&bytes[4..8], &[0xff; 4]);
    let back = read_hits(&p).unwrap();
    assert_eq!(back.len(), hits.len());
    for (a, b) in back.iter().zip(&hits) {
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                assert_eq!((a.t, a.prim), (b.t, b.prim));
                assert_eq!((a.u, a.v), (0.0, 0.0), "u, v are not stored");
            }
            _ => panic!("hit/miss mismatch"),
        }
    }
}

#[test]
fn bad_hit_files() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad_hits.bin");
    let hit = Some(Hit {
        t: 1.0,
        u: 0.0,
        v: 0.0,
        prim: 4,
    });
    write_hits(&p, &[hit, None, hit]).unwrap();
    let good = std::fs::read(&p).unwrap();
    std::fs::write(&p, &good[..20]).unwrap();
    let e = read_hits(&p).unwrap_err().to_string();
    assert!(
        e.contains(
            "bad_hits.bin: byte 16: file size 20 is not a multiple of the 8-byte hit record"
        ),
        "{e}"
    );
    let mut b = good.clone();
    b[8..12].copy_from_slice(&2.0f32.to_le_bytes());
    std::fs::write(&p, &b).unwrap();
    let e = read_hits(&p).unwrap_err().to_string();
    assert!(
        e.contains("byte 8: record 1: prim is u32::MAX (a miss) but t is 2"),
        "{e}"
    );
    let mut b = good;
    b[16..20].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(&p, &b).unwrap();
    let e = read_hits(&p).unwrap_err().to_string();
    assert!(
        e.contains("byte 16: record 2: hit on triangle 4 has t = NaN"),
        "{e}"
    );
}

#[test]
fn occlusion_round_trip_and_bad_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("occ.bin");
    let mut rng = Pcg32::new(9);
    let occ: Vec<bool> = (0..777).map(|_| rng.below(2) == 1).collect();
    write_occlusion(&p, &occ).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(bytes, occ.iter().map(|&o| o as u8).collect::<Vec<u8>>());
    assert_eq!(read_occlusion(&p).unwrap(), occ);
    let mut b = bytes;
    b[500] = 2;
    std::fs::write(&p, &b).unwrap();
    let e = read_occlusion(&p).unwrap_err().to_string();
    assert!(
        e.contains("occ.bin: byte 500: ray 500: occlusion byte is 2; expected 0 or 1"),
        "{e}"
    );
}

#[test]
fn writers_never_clobber_on_failure() {
    // A failing write (the destination's folder is missing) leaves nothing;
    // writing over an existing file replaces it only when complete.
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/dir/rays.bin");
    assert!(write_rays(&missing, &random_rays(3, 1)).is_err());
    let p = dir.path().join("rays.bin");
    write_rays(&p, &random_rays(3, 1)).unwrap();
    write_rays(&p, &random_rays(5, 2)).unwrap();
    assert_eq!(read_rays(&p).unwrap(), random_rays(5, 2));
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("rays.bin")]);
}
