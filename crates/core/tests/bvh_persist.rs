//! Saved wide BVHs: a tree saved and loaded gives the freshly built tree's
//! answers bit for bit, ray for ray (and both agree with brute force), on
//! the shared data's meshes; corrupt, truncated, foreign and mismatched
//! files are refused with an error naming the field, never a panic.

mod shared_meshes;

use raykit_core::accel::{Accel, BruteForce, BuildOptions, Bvh4, Bvh8, PersistError};
use raykit_core::rng::Pcg32;
use raykit_core::tri::{Moller, Plucker, Projection, TriangleTest};
use raykit_core::{Hit, Icosphere, Ray, TriangleMesh};
use shared_meshes::{agree, bits, deformed, rays, shared_obj};
use std::path::PathBuf;

/// A fresh file path in the test's scratch folder.
fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bvh_persist");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn small_sphere() -> TriangleMesh {
    let s = Icosphere::new(2);
    TriangleMesh::new(s.positions, s.indices)
}

/// Every answer of `a` and `b` identical (nearest hits bit for bit,
/// occlusion, the batch path), and `a`'s nearest hits agree with brute
/// force.
fn same_answers(a: &dyn Accel, b: &dyn Accel, brute: &dyn Accel, rays: &[Ray]) {
    let mut hits = 0;
    for ray in rays {
        let (x, y) = (a.intersect(ray), b.intersect(ray));
        assert_eq!(bits(x), bits(y), "{ray:?}");
        assert_eq!(a.occluded(ray), b.occluded(ray), "{ray:?}");
        let want = brute.intersect(ray);
        assert!(agree(x, want), "{ray:?} {x:?} {want:?}");
        hits += x.is_some() as usize;
    }
    assert!(hits > rays.len() / 10, "{hits} hits of {}", rays.len());
    let mut ha: Vec<Option<Hit>> = vec![None; rays.len()];
    let mut hb = ha.clone();
    a.intersect_batch(rays, &mut ha);
    b.intersect_batch(rays, &mut hb);
    assert!(ha.iter().zip(&hb).all(|(x, y)| bits(*x) == bits(*y)));
    assert_eq!(a.stats(), b.stats());
}

fn round_trip<T: TriangleTest>(mesh: &TriangleMesh, name: &str) {
    let opts = BuildOptions::default();
    let brute = BruteForce::<T>::new(mesh);
    let rays = rays(mesh, 20_000, 35);

    let built8 = Bvh8::<T>::build(mesh, &opts);
    let path = scratch(&format!("{name}-{}.bvh8", T::NAME));
    built8.save(&path, mesh).unwrap();
    let loaded8 = Bvh8::<T>::load(&path, mesh).unwrap();
    same_answers(&built8, &loaded8, &brute, &rays);
    // SAFETY: the file stays as it is while the tree lives.
    let mapped8 = unsafe { Bvh8::<T>::load_mapped(&path, mesh) }.unwrap();
    same_answers(&built8, &mapped8, &brute, &rays);

    let built4 = Bvh4::<T>::build(mesh, &opts);
    let path = scratch(&format!("{name}-{}.bvh4", T::NAME));
    built4.save(&path, mesh).unwrap();
    let loaded4 = Bvh4::<T>::load(&path, mesh).unwrap();
    same_answers(&built4, &loaded4, &brute, &rays);
    // SAFETY: as above.
    let mapped4 = unsafe { Bvh4::<T>::load_mapped(&path, mesh) }.unwrap();
    same_answers(&built4, &mapped4, &brute, &rays);
}

#[test]
fn bunny_round_trips_with_identical_hits_every_test() {
    let bunny = shared_obj("bunny_3674.obj");
    round_trip::<Moller>(&bunny, "bunny");
    round_trip::<Plucker>(&bunny, "bunny");
    round_trip::<Projection>(&bunny, "bunny");
}

#[test]
fn teapot_round_trips_with_identical_hits() {
    round_trip::<Moller>(&shared_obj("teapot_992.obj"), "teapot");
}

/// A refit tree saved and loaded over the deformed mesh answers as the
/// refit tree, and keeps its reference SAH cost.
#[test]
fn refit_tree_round_trips() {
    let bunny = shared_obj("bunny_3674.obj");
    let moved = deformed(&bunny, 1.3, 0.05);
    let mut tree = Bvh8::<Moller>::build(&bunny, &BuildOptions::default());
    let report = tree.refit(&moved).unwrap();
    let path = scratch("bunny-refit.bvh8");
    tree.save(&path, &moved).unwrap();
    let loaded = Bvh8::<Moller>::load(&path, &moved).unwrap();
    same_answers(
        &tree,
        &loaded,
        &BruteForce::<Moller>::new(&moved),
        &rays(&moved, 10_000, 7),
    );
    assert_eq!(loaded.sah_costs(), tree.sah_costs());
    assert_eq!(loaded.sah_costs().1, report.built_sah);

    // A mapped tree refits (into its own copy, the file unchanged) as the
    // tree it was saved from.
    let path = scratch("bunny-built.bvh8");
    let mut built = Bvh8::<Moller>::build(&bunny, &BuildOptions::default());
    built.save(&path, &bunny).unwrap();
    let before = std::fs::read(&path).unwrap();
    // SAFETY: the file stays as it is while the tree lives.
    let mut mapped = unsafe { Bvh8::<Moller>::load_mapped(&path, &bunny) }.unwrap();
    assert_eq!(mapped.refit(&moved).unwrap(), built.refit(&moved).unwrap());
    same_answers(
        &built,
        &mapped,
        &BruteForce::<Moller>::new(&moved),
        &rays(&moved, 10_000, 8),
    );
    drop(mapped);
    assert!(std::fs::read(&path).unwrap() == before);
}

/// Saving with a mesh the tree was not built over is refused.
#[test]
fn save_refuses_another_mesh() {
    let bunny = shared_obj("bunny_3674.obj");
    let moved = deformed(&bunny, 0.5, 0.02);
    let tree = Bvh8::<Moller>::build(&bunny, &BuildOptions::default());
    let err = tree.save(scratch("never.bvh8"), &moved).unwrap_err();
    assert!(err.to_string().contains("not the mesh's triangle"), "{err}");
    let tree = Bvh4::<Plucker>::build(&bunny, &BuildOptions::default());
    let err = tree.save(scratch("never.bvh4"), &moved).unwrap_err();
    assert!(err.to_string().contains("not the mesh's triangle"), "{err}");
    let err = tree
        .save(scratch("never.bvh4"), &small_sphere())
        .unwrap_err();
    assert!(err.to_string().contains("triangles"), "{err}");
    assert!(!scratch("never.bvh8").exists() && !scratch("never.bvh4").exists());
}

fn expect_err(r: Result<Bvh8<Moller>, PersistError>, field: &str) -> String {
    match r {
        Ok(_) => panic!("a bad file was accepted (expected an error on {field})"),
        Err(e) => {
            let s = e.to_string();
            assert!(s.contains("offset") && s.contains(field), "{s}");
            s
        }
    }
}

/// The small sphere's tree as saved bytes, the tree and the rays to check.
fn saved_sphere() -> (TriangleMesh, Bvh8<Moller>, Vec<u8>, Vec<Ray>) {
    let mesh = small_sphere();
    let tree = Bvh8::<Moller>::build(&mesh, &BuildOptions::default());
    let path = scratch("sphere-ref.bvh8");
    tree.save(&path, &mesh).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let rays = rays(&mesh, 2000, 11);
    (mesh, tree, bytes, rays)
}

/// Offsets to damage: every byte of the header and the payload's first
/// record, then every `stride`-th byte and the last 64.
fn offsets(len: usize, stride: usize) -> Vec<usize> {
    let mut at: Vec<usize> = (0..192.min(len)).collect();
    at.extend((192..len).step_by(stride));
    at.extend(len.saturating_sub(64).max(192)..len);
    at
}

/// A byte changed, one at a time, at many offsets over the whole file:
/// always refused (a CRC-32 catches every error of up to 32 bits).
#[test]
fn every_flipped_byte_is_refused() {
    let (mesh, _, bytes, _) = saved_sphere();
    let path = scratch("sphere-flip.bvh8");
    let mut rng = Pcg32::new(3);
    for at in offsets(bytes.len(), 5) {
        let mut bad = bytes.clone();
        bad[at] ^= 1 + rng.below(255) as u8;
        std::fs::write(&path, &bad).unwrap();
        assert!(
            Bvh8::<Moller>::load(&path, &mesh).is_err(),
            "byte {at} flipped was accepted"
        );
    }
}

/// Several bytes changed at random places, many times: refused, or (had a
/// checksum missed it) the same answers as the saved tree.
#[test]
fn random_corruption_is_refused_or_harmless() {
    let (mesh, tree, bytes, rays) = saved_sphere();
    let path = scratch("sphere-noise.bvh8");
    let mut rng = Pcg32::new(5);
    let mut refused = 0;
    for _ in 0..3000 {
        let mut bad = bytes.clone();
        for _ in 0..1 + rng.below(8) {
            let at = rng.below(bad.len() as u32) as usize;
            bad[at] = rng.next_u32() as u8;
        }
        std::fs::write(&path, &bad).unwrap();
        match Bvh8::<Moller>::load(&path, &mesh) {
            Err(_) => refused += 1,
            Ok(t) => {
                assert_eq!(bad, bytes, "a changed file was accepted");
                for r in &rays {
                    assert_eq!(bits(t.intersect(r)), bits(tree.intersect(r)));
                }
            }
        }
    }
    assert!(refused > 2900, "{refused}");
}

/// Truncations at many lengths, and bytes appended, are refused as such.
#[test]
fn truncated_and_extended_files_are_refused() {
    let (mesh, _, bytes, _) = saved_sphere();
    let path = scratch("sphere-cut.bvh8");
    for len in offsets(bytes.len(), 37) {
        std::fs::write(&path, &bytes[..len]).unwrap();
        let s = expect_err(Bvh8::<Moller>::load(&path, &mesh), "truncated");
        assert!(s.contains(&format!("offset {len}")), "{s}");
        // SAFETY: the file is rewritten only after the result is dropped.
        let s = expect_err(
            unsafe { Bvh8::<Moller>::load_mapped(&path, &mesh) },
            "truncated",
        );
        assert!(s.contains(&format!("offset {len}")), "{s}");
    }
    let mut longer = bytes.clone();
    longer.extend_from_slice(&[0; 5]);
    std::fs::write(&path, &longer).unwrap();
    expect_err(
        Bvh8::<Moller>::load(&path, &mesh),
        "5 bytes after the payload",
    );
}

/// Other files: a mesh file, an empty file, a missing one, a tree of
/// another structure or test, another version, the other byte order, and a
/// tree for another mesh or for moved vertices.
#[test]
fn foreign_and_mismatched_files_are_refused() {
    let mesh = small_sphere();
    let path = scratch("sphere-foreign.bvh8");
    let obj = shared_data_file("meshes/bunny_3674.obj");
    expect_err(Bvh8::<Moller>::load(&obj, &mesh), "not a raykit BVH file");
    std::fs::write(&path, b"").unwrap();
    expect_err(Bvh8::<Moller>::load(&path, &mesh), "truncated");
    let missing = Bvh8::<Moller>::load(scratch("no-such-file.bvh8"), &mesh);
    assert!(matches!(missing, Err(PersistError::Io { .. })));

    let opts = BuildOptions::default();
    Bvh4::<Moller>::build(&mesh, &opts)
        .save(&path, &mesh)
        .unwrap();
    expect_err(Bvh8::<Moller>::load(&path, &mesh), "structure");
    Bvh8::<Plucker>::build(&mesh, &opts)
        .save(&path, &mesh)
        .unwrap();
    expect_err(Bvh8::<Moller>::load(&path, &mesh), "triangle test");

    let tree = Bvh8::<Moller>::build(&mesh, &opts);
    tree.save(&path, &mesh).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let with_header_crc = |mut b: Vec<u8>| {
        let crc = crc32(&b[..88]);
        b[88..92].copy_from_slice(&crc.to_le_bytes());
        b
    };
    let mut v2 = bytes.clone();
    v2[8..12].copy_from_slice(&2u32.to_le_bytes());
    std::fs::write(&path, with_header_crc(v2)).unwrap();
    expect_err(Bvh8::<Moller>::load(&path, &mesh), "version 2");
    let mut be = bytes.clone();
    be[12..16].reverse();
    std::fs::write(&path, with_header_crc(be)).unwrap();
    expect_err(Bvh8::<Moller>::load(&path, &mesh), "big-endian");

    std::fs::write(&path, &bytes).unwrap();
    expect_err(
        Bvh8::<Moller>::load(&path, &shared_obj("teapot_992.obj")),
        "mesh size",
    );
    let moved = deformed(&mesh, 0.7, 0.01);
    expect_err(Bvh8::<Moller>::load(&path, &moved), "mesh checksum");
    assert!(Bvh8::<Moller>::load(&path, &mesh).is_ok());
}

/// Files whose checksums were made to match a changed tree (as a crafted
/// file would): child references and leaf triangles set at random are
/// refused by the topology checks, or load into a tree that traces without
/// a panic.
#[test]
fn crafted_trees_are_refused_or_traceable() {
    let (mesh, _, bytes, rays) = saved_sphere();
    let path = scratch("sphere-crafted.bvh8");
    let nodes = u64::from_le_bytes(bytes[64..72].try_into().unwrap()) as usize;
    let units = u64::from_le_bytes(bytes[72..80].try_into().unwrap()) as usize;
    let node_start = 96 + 96;
    let unit_start = node_start + nodes * 256;
    let mut rng = Pcg32::new(9);
    let (mut refused, mut loaded) = (0, 0);
    for round in 0..4000 {
        let mut bad = bytes.clone();
        let at = match round % 3 {
            // A child reference's index or count.
            0 => {
                node_start
                    + 256 * rng.below(nodes as u32) as usize
                    + 192
                    + 4 * rng.below(16) as usize
            }
            // A pack lane's triangle.
            1 => {
                unit_start
                    + 192 * rng.below(units as u32) as usize
                    + 176
                    + 4 * rng.below(4) as usize
            }
            // The root reference.
            _ => 96 + 4 * rng.below(2) as usize,
        };
        let value = match rng.below(4) {
            0 => u32::MAX,
            1 => rng.below(8),
            2 => rng.below(2 * nodes.max(units) as u32),
            _ => rng.next_u32(),
        };
        bad[at..at + 4].copy_from_slice(&value.to_le_bytes());
        let crc = crc32(&bad[96..]);
        bad[60..64].copy_from_slice(&crc.to_le_bytes());
        let crc = crc32(&bad[..88]);
        bad[88..92].copy_from_slice(&crc.to_le_bytes());
        std::fs::write(&path, &bad).unwrap();
        let result = match round % 2 {
            0 => Bvh8::<Moller>::load(&path, &mesh),
            // SAFETY: the file is rewritten only after the tree is dropped.
            _ => unsafe { Bvh8::<Moller>::load_mapped(&path, &mesh) },
        };
        match result {
            Err(e) => {
                assert!(e.to_string().contains("offset"), "{e}");
                refused += 1;
            }
            Ok(t) => {
                loaded += 1;
                // A hit names one of the mesh's triangles, never an
                // unused lane's u32::MAX.
                let named =
                    |h: Option<Hit>| h.is_none_or(|h| (h.prim as usize) < mesh.num_triangles());
                for r in &rays[..200] {
                    assert!(named(t.intersect(r)), "round {round}");
                    let _ = t.occluded(r);
                }
                let mut out = vec![None; 200];
                t.intersect_batch(&rays[..200], &mut out);
                assert!(out.iter().all(|h| named(*h)), "round {round}");
                t.visit_regions(&mut |_| true, &mut |_| {});
            }
        }
    }
    assert!(
        refused > 1000 && loaded > 0,
        "{refused} refused, {loaded} loaded"
    );
}

fn shared_data_file(rel: &str) -> PathBuf {
    shared_meshes::shared_data().join(rel)
}

/// CRC-32 (IEEE), written out bit by bit: the test's own reference for the
/// checksums it forges.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Through the registry: every structure and test built by kind, saved
/// through the `Accel` trait and loaded by `load_accel` from the header's
/// kind answers as built; the structures without a saved form say so.
#[test]
fn registry_round_trip_every_kind_and_test() {
    use raykit_core::accel::{build_accel, load_accel, AccelKind};
    use raykit_core::tri::TestKind;
    let mesh = shared_obj("teapot_992.obj");
    let rays = rays(&mesh, 3000, 21);
    for kind in AccelKind::ALL {
        for test in TestKind::ALL {
            let built = build_accel(kind, test, &mesh, &BuildOptions::default());
            let path = scratch(&format!("registry-{}-{}.bin", kind.name(), test.name()));
            let saved = built.save(&path, &mesh);
            if !matches!(kind, AccelKind::Bvh4 | AccelKind::Bvh8) {
                assert!(
                    matches!(saved, Err(PersistError::Unsupported { .. })),
                    "{kind:?}"
                );
                assert!(!path.exists());
                continue;
            }
            saved.unwrap();
            let (k, t, loaded) = load_accel(&path, &mesh).unwrap();
            assert_eq!((k, t), (kind, test));
            for ray in &rays {
                assert_eq!(bits(loaded.intersect(ray)), bits(built.intersect(ray)));
            }
        }
    }
}

/// Meshes of no, one and two triangles (an empty tree, a root leaf, a
/// small tree) save, load and refit.
#[test]
fn tiny_meshes_round_trip_and_refit() {
    use raykit_core::Vec3;
    let tri = |n: u32| {
        let mut pos = Vec::new();
        let mut idx = Vec::new();
        for i in 0..n {
            let o = Vec3::new(i as f32, 0.0, 0.0);
            pos.extend([o, o + Vec3::X * 0.5, o + Vec3::Y]);
            idx.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        TriangleMesh::new(pos, idx)
    };
    for n in [0, 1, 2, 9] {
        let mesh = tri(n);
        let mut tree = Bvh8::<Moller>::build(&mesh, &BuildOptions::default());
        let path = scratch(&format!("tiny-{n}.bvh8"));
        tree.save(&path, &mesh).unwrap();
        let loaded = Bvh8::<Moller>::load(&path, &mesh).unwrap();
        let brute = BruteForce::<Moller>::new(&mesh);
        let mut moved = mesh.clone();
        for p in &mut moved.positions {
            p.z += 0.25 * p.x;
        }
        let report = tree.refit(&moved).unwrap();
        assert!(
            n == 0 || report.degradation().is_finite(),
            "{n}: {report:?}"
        );
        let brute_moved = BruteForce::<Moller>::new(&moved);
        let mut rng = Pcg32::new(n as u64);
        for _ in 0..500 {
            let o = Vec3::new(rng.range_f32(-1.0, 10.0), rng.range_f32(-1.0, 2.0), 5.0);
            let ray = Ray::new(o, Vec3::new(0.01, 0.02, -1.0));
            assert_eq!(
                bits(loaded.intersect(&ray)),
                bits(brute.intersect(&ray)),
                "{n}"
            );
            assert!(
                agree(tree.intersect(&ray), brute_moved.intersect(&ray)),
                "{n}"
            );
        }
    }
}

/// A tree `build_accel` made over a tiny mesh (scaled to unit size) or a far
/// one (moved to the origin for Plücker and projection), refit to moved
/// vertices or not, loads again through `load_accel` over the mesh as given,
/// with the built tree's answers; the structure's own `load` refuses such a
/// file by name, and `load_accel` loads a file the structure saved itself.
#[test]
fn scaled_and_moved_trees_load_through_load_accel() {
    use raykit_core::accel::{build_accel, load_accel, AccelKind};
    use raykit_core::tri::TestKind;
    use raykit_core::Vec3;
    let sphere = small_sphere();
    let placed = |scale: f32, offset: Vec3| {
        let mut m = sphere.clone();
        for p in &mut m.positions {
            *p = *p * scale + offset;
        }
        m
    };
    let cases = [
        ("tiny", placed(1e-6, Vec3::ZERO), TestKind::Moller),
        (
            "far",
            placed(1.0, Vec3::new(1e5, 1e5, 0.0)),
            TestKind::Plucker,
        ),
        (
            "far-projection",
            placed(1.0, Vec3::new(-3e5, 0.0, 2e5)),
            TestKind::Projection,
        ),
    ];
    for (name, mesh, test) in cases {
        let mut moved = mesh.clone();
        let lo = mesh.bounds();
        let shift = (lo.max - lo.min) * 0.125;
        for p in &mut moved.positions {
            *p += Vec3::new(shift.x * (p.y - lo.min.y).signum(), 0.0, 0.0);
        }
        for (refit, now) in [(false, &mesh), (true, &moved)] {
            let mut built = build_accel(AccelKind::Bvh8, test, &mesh, &BuildOptions::default());
            if refit {
                built.refit(&moved).unwrap();
            }
            let path = scratch(&format!("scaled-{name}-{refit}.bvh8"));
            built.save(&path, now).unwrap();
            let (_, _, loaded) =
                load_accel(&path, now).unwrap_or_else(|e| panic!("{name}, refit {refit}: {e}"));
            let brute = BruteForce::<Moller>::new(now);
            let rays = rays(now, 2000, 5);
            same_answers(&*loaded, &*built, &brute, &rays);
            let plain = match test {
                TestKind::Moller => Bvh8::<Moller>::load(&path, now).map(|_| ()),
                TestKind::Plucker => Bvh8::<Plucker>::load(&path, now).map(|_| ()),
                TestKind::Projection => Bvh8::<Projection>::load(&path, now).map(|_| ()),
            };
            let e = plain
                .expect_err("a scaled tree through the plain load")
                .to_string();
            assert!(e.contains("load it with load_accel"), "{name}: {e}");
        }
        // Saved by the structure itself, over the mesh as given.
        let own = Bvh8::<Moller>::build(&mesh, &BuildOptions::default());
        let path = scratch(&format!("scaled-{name}-own.bvh8"));
        own.save(&path, &mesh).unwrap();
        let (_, _, loaded) = load_accel(&path, &mesh).unwrap_or_else(|e| panic!("{name}: {e}"));
        let brute = BruteForce::<Moller>::new(&mesh);
        same_answers(&*loaded, &own, &brute, &rays(&mesh, 2000, 6));
    }
}
