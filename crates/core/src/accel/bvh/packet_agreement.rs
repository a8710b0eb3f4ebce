//! The packet path of [`super::Bvh4`] and [`super::Bvh8`] against single
//! rays and brute force, on every packet width and box path.

use super::packet::*;
use crate::accel::bvh::{BuildOptions, Bvh4, Bvh8};
use crate::accel::Accel;
use crate::accel::BruteForce;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::rng::Pcg32;
use crate::tri::{Moller, TriangleTest};
use glam::Vec3;

/// A bumpy grid surface (shared edges and corners) with some triangles
/// duplicated (ties), plus a soup of small random triangles above it.
fn scene(n: usize, seed: u64) -> TriangleMesh {
    let mut rng = Pcg32::new(seed);
    let mut positions = Vec::new();
    for y in 0..=n {
        for x in 0..=n {
            let h = 0.05 * rng.next_f32();
            positions.push(Vec3::new(x as f32 / n as f32, h, y as f32 / n as f32));
        }
    }
    let w = n as u32 + 1;
    let mut indices = Vec::new();
    for y in 0..n as u32 {
        for x in 0..n as u32 {
            let a = y * w + x;
            indices.push([a, a + 1, a + w + 1]);
            indices.push([a, a + w + 1, a + w]);
        }
    }
    let dups: Vec<[u32; 3]> = indices.iter().step_by(11).copied().collect();
    indices.extend(dups);
    for _ in 0..2000 {
        let c = rng.in_box(Vec3::new(0.0, 0.1, 0.0), Vec3::new(1.0, 0.6, 1.0));
        let s = 0.005 + 0.05 * rng.next_f32().powi(2);
        let b = positions.len() as u32;
        for _ in 0..3 {
            positions.push(c + rng.unit_vector() * s);
        }
        indices.push([b, b + 1, b + 2]);
    }
    TriangleMesh::new(positions, indices)
}

/// Rays in rows of a pinhole image (coherent packets), with now and
/// then a bounded segment, an axis-parallel direction (exact zero
/// components, both signs of zero), a row of shadow-like rays towards
/// one point, or random directions (mixed octants); odd lengths leave
/// a tail packet.
fn rays(rng: &mut Pcg32, n: usize) -> Vec<Ray> {
    let mut out = Vec::with_capacity(n);
    let eye = Vec3::new(0.5, 1.5, -0.8) + rng.unit_vector() * 0.3;
    let light = Vec3::new(0.2, 2.0, 0.9);
    let w = 37;
    while out.len() < n {
        let i = out.len();
        let (x, y) = (
            (i % w) as f32 / w as f32,
            (i / w) as f32 / (n / w + 1) as f32,
        );
        let target = Vec3::new(x * 1.2 - 0.1, 0.0, y * 1.2 - 0.1);
        let mut ray = match (i / 64) % 8 {
            // Axis-parallel, straight down, zero components of either sign.
            0 => {
                let z = if rng.below(2) == 0 { 0.0 } else { -0.0 };
                Ray::new(target + Vec3::Y, Vec3::new(z, -1.0, z))
            }
            // Shadow-like: from points on and above the surface to a light.
            1 => {
                let o = target + Vec3::Y * 0.1 * rng.next_f32();
                Ray::segment(o, light - o, 1e-4, 1.0)
            }
            // Random directions from the eye.
            2 => Ray::new(eye, rng.unit_vector()),
            _ => Ray::new(eye, target - eye),
        };
        if rng.below(6) == 0 {
            let t0 = rng.range_f32(0.0, 0.8);
            ray = Ray::segment(ray.origin, ray.dir, t0, t0 + rng.range_f32(0.0, 1.0));
        }
        out.push(ray);
    }
    out
}

/// A packet's fields as bits, for comparing two packets exactly.
#[cfg(target_arch = "x86_64")]
fn packet_bits<const L: usize>(p: &Packet<L>) -> (Vec<u32>, [usize; 3]) {
    let rows = [p.origin, p.dir, p.inv_dir].into_iter().flatten();
    let rows = rows.chain([p.tnear, p.tfar, p.scale]);
    (rows.flat_map(|r| r.map(f32::to_bits)).collect(), p.near)
}

/// The vector gather of full packets forms exactly the packet that the
/// ray-by-ray copy forms, and refuses exactly the packets whose rays
/// do not share an octant: over every window of eight and of sixteen
/// rays of the test's ray sets (coherent and mixed windows, axis-parallel
/// rays with signed zeros, clipped intervals).
#[cfg(target_arch = "x86_64")]
#[test]
fn gathered_packets_equal_ray_by_ray_packets() {
    if !is_x86_feature_detected!("avx") {
        eprintln!("skipped: this CPU has no AVX (the gather needs it)");
        return;
    }
    fn check<const L: usize>(rays: &[Ray]) -> (usize, usize) {
        let (mut formed, mut refused) = (0, 0);
        for w in rays.windows(L) {
            // SAFETY: AVX checked above; `w` holds `L` rays.
            let got = unsafe { gathered::<L>(w) };
            let want = coherent(w).map(|oct| packet::<L>(w, oct));
            assert_eq!(got.is_some(), want.is_some(), "octant check, rays {w:?}");
            if let (Some(g), Some(p)) = (got, want) {
                assert_eq!(packet_bits(&g), packet_bits(&p), "rays {w:?}");
                formed += 1;
            } else {
                refused += 1;
            }
        }
        (formed, refused)
    }
    let mut rng = Pcg32::new(44);
    let mut rays = rays(&mut rng, 3000);
    // Rays whose origin or direction is not finite get a NaN `tfar`.
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    for (i, (o, d)) in [
        (Vec3::new(nan, 0.5, 0.5), Vec3::Y),
        (Vec3::new(0.5, -inf, 0.5), Vec3::Y),
        (Vec3::ZERO, Vec3::new(0.3, nan, 0.1)),
        (Vec3::ZERO, Vec3::new(inf, 1.0, 1.0)),
    ]
    .into_iter()
    .enumerate()
    {
        rays[100 + 40 * i].origin = o;
        rays[100 + 40 * i].dir = d;
    }
    for (formed, refused) in [check::<8>(&rays), check::<16>(&rays)] {
        assert!(
            formed > 500 && refused > 500,
            "{formed} formed, {refused} refused"
        );
    }
}

fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.prim))
}

/// Every ray gets the single-ray traversal's answer from the batch:
/// without packets, and with packets of each width this CPU runs (eight
/// with AVX2, sixteen with AVX-512) handing over to single rays at the
/// default counts (1 for nearest hits, 2 for occlusion), the other way
/// round, never (0: pure packets) or at once (the width): the same `t`
/// bits, and the same triangle, `u` and `v` unless
/// another triangle is hit at exactly the same `t` (a tie, checked with
/// the scalar test on the packet's triangle); the same occlusion; and
/// agreement with brute force up to ties. Over the 4-wide and the
/// 8-wide tree (the same kernel, generic over the node width), the
/// latter with each AVX path this CPU has for the single-ray traversal
/// that packets hand their last rays to (AVX2, and AVX-512 besides).
#[test]
fn packets_equal_single_rays_and_brute_force() {
    use super::box_path::BoxPath;
    check_packets(|mesh| Bvh4::<Moller>::build(mesh, &BuildOptions::default()));
    for path in BoxPath::available() {
        if matches!(path, BoxPath::Avx2 | BoxPath::Avx512) {
            check_packets(|mesh| {
                Bvh8::<Moller>::build(mesh, &BuildOptions::default()).with_path(path)
            });
        }
    }
}

fn check_packets<B: PacketTree>(build: impl Fn(&TriangleMesh) -> B) {
    let mut rng = Pcg32::new(2001);
    let (mut packets, mut hits, mut ties) = (0usize, 0usize, 0usize);
    let mut modes = vec![Mode::SINGLES];
    for lanes in widths() {
        for switch in [SWITCH, [0; 2], [lanes as u32; 2], [2, 1]] {
            modes.push(Mode { lanes, switch });
        }
    }
    if !modes.iter().any(|m| m.lanes == 16) {
        eprintln!("note: no AVX-512 on this CPU: packets of sixteen are not tested here");
    }
    if !modes.iter().any(|m| m.lanes == 8) {
        eprintln!("note: no AVX2: only the single-ray batch is tested");
    }
    for round in 0..6 {
        let mesh = scene(40 + 13 * round, round as u64);
        let bvh = build(&mesh);
        let brute = BruteForce::<Moller>::new(&mesh);
        let rays = rays(&mut rng, 5000 + 3 * round);
        // Packets of eight that form: one octant, and a full packet's rays
        // close together.
        let extent = (mesh.bounds().max - mesh.bounds().min).max_element();
        packets += rays
            .chunks(8)
            .filter(|c| coherent(c).is_some() && (c.len() < 8 || close_together(c, extent)))
            .count();
        let one: Vec<Option<Hit>> = rays.iter().map(|r| bvh.intersect(r)).collect();
        let one_occ: Vec<bool> = rays.iter().map(|r| bvh.occluded(r)).collect();
        for (i, ray) in rays.iter().enumerate() {
            assert_eq!(one_occ[i], one[i].is_some(), "single ray {i} {ray:?}");
            let want = brute.intersect(ray);
            match (one[i], want) {
                (Some(a), Some(b)) => {
                    let tol = 1e-5 * a.t.abs().max(b.t.abs()).max(1e-6);
                    assert!((a.t - b.t).abs() <= tol, "brute force, ray {i}");
                }
                (a, b) => assert_eq!(a.is_some(), b.is_some(), "brute force, ray {i}"),
            }
        }
        for &mode in &modes {
            let mut got = vec![None; rays.len()];
            intersect_batch_with(&bvh, &rays, &mut got, mode);
            let mut occ = vec![false; rays.len()];
            occluded_batch_with(&bvh, &rays, &mut occ, mode);
            for (i, ray) in rays.iter().enumerate() {
                assert_eq!(occ[i], one_occ[i], "{mode:?}: occlusion, ray {i} {ray:?}");
                match (got[i], one[i]) {
                    (Some(a), Some(b)) => {
                        assert_eq!(a.t.to_bits(), b.t.to_bits(), "{mode:?}: ray {i} {ray:?}");
                        if a.prim != b.prim {
                            // A tie: the packet's triangle is hit at the
                            // same t, with the u and v reported.
                            let [x, y, z] = mesh.triangle(a.prim as usize);
                            let tri = Moller::precompute(x, y, z);
                            let h = Moller::intersect(&tri, ray, &Moller::prepare(ray), ray.tfar)
                                .expect("the packet's triangle is hit");
                            assert_eq!(
                                [h.t.to_bits(), h.u.to_bits(), h.v.to_bits()],
                                [a.t.to_bits(), a.u.to_bits(), a.v.to_bits()],
                                "{mode:?}: ray {i} {ray:?}"
                            );
                            ties += 1;
                        } else {
                            assert_eq!(bits(got[i]), bits(one[i]), "{mode:?}: ray {i} {ray:?}");
                        }
                        hits += 1;
                    }
                    (a, b) => {
                        assert_eq!(a.is_some(), b.is_some(), "{mode:?}: ray {i} {ray:?}")
                    }
                }
            }
        }
    }
    assert!(packets > 1200, "too few coherent packets: {packets}");
    assert!(hits > 10_000, "too few hits: {hits}");
    eprintln!(
        "{}: {packets} packets, {hits} hits, {ties} ties",
        std::any::type_name::<B>()
    );
}
