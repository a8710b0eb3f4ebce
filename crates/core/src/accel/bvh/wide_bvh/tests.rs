//! Both widths and every box kernel this CPU runs against brute force.

use super::*;
use crate::accel::BruteForce;
use crate::rng::Pcg32;
use crate::tri::{Moller, Plucker};
use glam::Vec3;

fn agree(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (Some(x), Some(y)) => (x.t - y.t).abs() <= 1e-5 * x.t.abs().max(y.t.abs()).max(1e-6),
        (x, y) => x.is_some() == y.is_some(),
    }
}

/// Triangles shrinking geometrically towards the origin: the SAH peels
/// them off one at a time, so the tree is a deep chain whose traversal
/// needs the large stack; every box kernel gives the same answers, equal
/// to brute force up to ties.
fn deep_chain_every_kernel_agrees_with_brute_force<N: NodeWidth>() {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..200u32 {
        let s = 0.8f32.powi(i as i32);
        positions.extend([
            Vec3::new(s, 0.0, 0.0),
            Vec3::new(s * 1.1, s, 0.0),
            Vec3::new(s, 0.0, s),
        ]);
        indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let mesh = TriangleMesh::new(positions, indices);
    let opts = BuildOptions {
        max_leaf_size: 1,
        packed_leaf_size: 1,
        ..Default::default()
    };
    let brute = BruteForce::<Moller>::new(&mesh);
    let trees: Vec<WideBvh<N, Moller>> = BoxPath::available()
        .iter()
        .map(|&p| WideBvh::<N, Moller>::build(&mesh, &opts).with_path(p))
        .collect();
    assert!(
        !trees[0].small_stack,
        "the chain should need the large stack"
    );
    let mut rng = Pcg32::new(8);
    let mut hits = 0;
    for _ in 0..5000 {
        let target = rng.in_box(Vec3::ZERO, Vec3::splat(0.3)) * 0.8f32.powi(rng.below(60) as i32);
        let origin = target + rng.unit_vector() * 2.0;
        let ray = Ray::new(origin, target - origin);
        let want = brute.intersect(&ray);
        let first = trees[0].intersect(&ray);
        assert!(agree(first, want), "{ray:?} {first:?} {want:?}");
        for t in &trees {
            let got = t.intersect(&ray);
            assert_eq!(
                got.map(|h| (h.t.to_bits(), h.prim)),
                first.map(|h| (h.t.to_bits(), h.prim)),
                "{:?} {ray:?}",
                t.path
            );
            assert_eq!(t.occluded(&ray), want.is_some(), "{ray:?}");
        }
        hits += want.is_some() as usize;
    }
    assert!(hits > 100, "{hits}");
}

#[test]
fn deep_chain_every_kernel_agrees_with_brute_force_4() {
    deep_chain_every_kernel_agrees_with_brute_force::<Node4>();
}

#[test]
fn deep_chain_every_kernel_agrees_with_brute_force_8() {
    deep_chain_every_kernel_agrees_with_brute_force::<Node8>();
}

/// A random soup, packed (Möller) and single-triangle (Plücker) leaves,
/// every kernel: the same answers as brute force up to ties, and the
/// kernels bit-identical to each other.
fn random_soup_every_kernel_and_leaf_kind_agrees_with_brute_force<N: NodeWidth>() {
    let mut rng = Pcg32::new(81);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..3000u32 {
        let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
        let size = 0.002 + 0.08 * rng.next_f32().powi(3);
        for _ in 0..3 {
            positions.push(c + rng.unit_vector() * size);
        }
        indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let mesh = TriangleMesh::new(positions, indices);
    let opts = BuildOptions::default();
    let brute = BruteForce::<Moller>::new(&mesh);
    let brute_p = BruteForce::<Plucker>::new(&mesh);
    let paths = BoxPath::available();
    let moller: Vec<WideBvh<N, Moller>> = paths
        .iter()
        .map(|&p| WideBvh::<N, Moller>::build(&mesh, &opts).with_path(p))
        .collect();
    let plucker: Vec<WideBvh<N, Plucker>> = paths
        .iter()
        .map(|&p| WideBvh::<N, Plucker>::build(&mesh, &opts).with_path(p))
        .collect();
    let mut hits = 0;
    for i in 0..20_000 {
        let target = rng.in_box(Vec3::ZERO, Vec3::ONE);
        let origin = if i % 3 == 0 {
            rng.in_box(Vec3::ZERO, Vec3::ONE)
        } else {
            Vec3::splat(0.5) + rng.unit_vector() * 2.0
        };
        let ray = if i % 5 == 0 {
            Ray::segment(origin, target - origin, 0.1 * rng.next_f32(), 0.5)
        } else {
            Ray::new(origin, target - origin)
        };
        let want = brute.intersect(&ray);
        let want_p = brute_p.intersect(&ray);
        hits += want.is_some() as usize;
        let m0 = moller[0].intersect(&ray);
        let p0 = plucker[0].intersect(&ray);
        assert!(agree(m0, want), "{ray:?} {m0:?} {want:?}");
        assert!(agree(p0, want_p), "{ray:?} {p0:?} {want_p:?}");
        for (m, p) in moller.iter().zip(&plucker) {
            assert_eq!(
                m.intersect(&ray).map(|h| h.t.to_bits()),
                m0.map(|h| h.t.to_bits())
            );
            assert_eq!(
                p.intersect(&ray).map(|h| h.t.to_bits()),
                p0.map(|h| h.t.to_bits())
            );
            assert_eq!(m.occluded(&ray), want.is_some(), "{ray:?}");
            assert_eq!(p.occluded(&ray), want_p.is_some(), "{ray:?}");
        }
    }
    assert!(hits > 2000, "{hits}");
}

#[test]
fn random_soup_every_kernel_and_leaf_kind_agrees_with_brute_force_4() {
    random_soup_every_kernel_and_leaf_kind_agrees_with_brute_force::<Node4>();
}

#[test]
fn random_soup_every_kernel_and_leaf_kind_agrees_with_brute_force_8() {
    random_soup_every_kernel_and_leaf_kind_agrees_with_brute_force::<Node8>();
}
