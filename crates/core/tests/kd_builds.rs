//! The kd-tree builds checked against independent references: Kim's (2013)
//! score recomputed by brute force for the root plane, the spatial median,
//! and the cut mesh of the game build against the original surface.

use raykit_core::accel::kdtree::{
    build_game, build_tree, cut_mesh, KdBuildNode, KdOptions, KdSplit,
};
use raykit_core::TriangleMesh;

mod soup;

fn soup(n: usize, seed: u64) -> TriangleMesh {
    soup::soup(n, seed, 0.01, 0.2, 2)
}

#[path = "tjunction_support/mod.rs"]
mod support;

/// A closed, shared-vertex sphere (an octahedron subdivided `level` times).
fn closed_mesh(level: u32) -> TriangleMesh {
    support::sphere(level)
}

/// Kim's (2013) score of the plane `x[axis] = pos`, from the triangles'
/// corners: `None` when the plane leaves no whole triangle on a side.
fn brute_score(mesh: &TriangleMesh, axis: usize, pos: f32, h: i64) -> Option<i64> {
    let (mut front, mut back, mut split) = (0i64, 0i64, 0i64);
    for i in 0..mesh.num_triangles() {
        let c = mesh.triangle(i).map(|v| v[axis]);
        let (lo, hi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
        if hi <= pos {
            back += 1;
        } else if lo >= pos {
            front += 1;
        } else {
            split += 1;
        }
    }
    (front > 0 && back > 0).then_some((front - back).abs() * (20 - h) + split * h)
}

#[test]
fn game_root_plane_has_the_lowest_brute_force_score() {
    for (seed, h) in [(1u64, 0u8), (2, 4), (3, 10), (4, 17), (5, 20)] {
        let mesh = soup(200, seed);
        let opts = KdOptions {
            split: KdSplit::Game(h),
            max_depth: 1,
            ..KdOptions::default()
        };
        let (root, cell) = build_tree(&mesh, &opts);
        let KdBuildNode::Inner { axis, split, .. } = root else {
            panic!("H={h}: root is a leaf");
        };
        let got =
            brute_score(&mesh, axis as usize, split, h as i64).expect("chosen plane is valid");
        let mut best = i64::MAX;
        for axis in 0..3 {
            for p in &mesh.positions {
                if p[axis] > cell.min[axis] && p[axis] < cell.max[axis] {
                    if let Some(s) = brute_score(&mesh, axis, p[axis], h as i64) {
                        best = best.min(s);
                    }
                }
            }
        }
        assert_eq!(
            got, best,
            "H={h}: chosen plane scores {got}, best candidate {best}"
        );
    }
}

#[test]
fn median_root_splits_the_longest_axis_in_the_middle() {
    let mesh = soup(300, 9);
    let opts = KdOptions {
        split: KdSplit::Median,
        max_depth: 1,
        ..KdOptions::default()
    };
    let (root, cell) = build_tree(&mesh, &opts);
    let KdBuildNode::Inner { axis, split, .. } = root else {
        panic!("root is a leaf");
    };
    let e = cell.extent();
    let longest = (0..3)
        .max_by(|&a, &b| e[a].partial_cmp(&e[b]).unwrap())
        .unwrap();
    assert_eq!(axis as usize, longest);
    assert_eq!(split, 0.5 * (cell.min[longest] + cell.max[longest]));
}

/// Every piece lies in its source triangle (barycentrics within rounding),
/// the pieces of a triangle add up to its area, and lower H cuts more.
#[test]
fn cut_mesh_pieces_tile_their_triangles() {
    let mesh = closed_mesh(3);
    let mut splits = Vec::new();
    for h in [0u8, 5, 10, 15, 20] {
        let opts = KdOptions {
            split: KdSplit::Game(h),
            max_leaf_size: 2,
            ..KdOptions::default()
        };
        let (_, _, game) = build_game(&mesh, h, &opts);
        let cut = cut_mesh(&mesh, &game);
        assert_eq!(cut.source.len(), cut.mesh.num_triangles());
        let mut area = vec![0f64; mesh.num_triangles()];
        for (i, &s) in cut.source.iter().enumerate() {
            let [a, b, c] = mesh.triangle(s as usize).map(|v| v.as_dvec3());
            let n = (b - a).cross(c - a);
            for p in cut.mesh.triangle(i) {
                let p = p.as_dvec3();
                // Barycentrics of p in the source triangle.
                let u = (p - a).cross(c - a).dot(n) / n.length_squared();
                let v = (b - a).cross(p - a).dot(n) / n.length_squared();
                let dist = (p - a).dot(n.normalize()).abs();
                assert!(
                    u >= -1e-5 && v >= -1e-5 && u + v <= 1.0 + 1e-5 && dist < 1e-5,
                    "H={h}: piece corner outside its triangle"
                );
            }
            let [pa, pb, pc] = cut.mesh.triangle(i).map(|v| v.as_dvec3());
            area[s as usize] += 0.5 * (pb - pa).cross(pc - pa).length();
        }
        for (t, got) in area.iter().enumerate() {
            let [a, b, c] = mesh.triangle(t).map(|v| v.as_dvec3());
            let want = 0.5 * (b - a).cross(c - a).length();
            assert!(
                (got - want).abs() <= 1e-5 * want,
                "H={h}: triangle {t} pieces cover {got}, want {want}"
            );
        }
        splits.push(cut.split_triangles);
    }
    assert!(splits[0] > 0, "balance-only build cuts triangles");
    assert!(
        splits[4] <= splits[0],
        "H=20 cuts no more than H=0: {splits:?}"
    );
}

/// Vertices lying strictly inside another triangle's edge (distance to the
/// line at most 1e-6 of the edge length), by brute force in f64. Points
/// closer than 4 f32 ulps of the mesh's largest coordinate count as the same
/// point (a cut point one rounding step from a corner is that corner).
fn t_junctions_brute(mesh: &TriangleMesh) -> usize {
    let used: std::collections::BTreeSet<u32> = mesh.indices.iter().flatten().copied().collect();
    let m = mesh
        .positions
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0f32, f32::max) as f64;
    let same = 4.0 * m * f32::EPSILON as f64;
    let mut count = 0;
    for tri in &mesh.indices {
        for k in 0..3 {
            let a = mesh.positions[tri[k] as usize].as_dvec3();
            let b = mesh.positions[tri[(k + 1) % 3] as usize].as_dvec3();
            let ab = b - a;
            let len2 = ab.length_squared();
            for &v in &used {
                let p = mesh.positions[v as usize].as_dvec3();
                if (p - a).length() <= same || (p - b).length() <= same {
                    continue;
                }
                let t = (p - a).dot(ab) / len2;
                if t > 0.0 && t < 1.0 && (a + ab * t - p).length() <= 1e-6 * len2.sqrt() {
                    count += 1;
                }
            }
        }
    }
    count
}

/// Undirected edges used by a number of triangles other than 2, with
/// vertices within 4 ulps of the largest coordinate taken as one point (as
/// in [`t_junctions_brute`]); edges between two such points are ignored.
fn open_edges(mesh: &TriangleMesh) -> usize {
    let m = mesh
        .positions
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0f32, f32::max) as f64;
    let same = 4.0 * m * f32::EPSILON as f64;
    // Cluster by brute force: each vertex takes the smallest index within
    // `same` of it.
    let n = mesh.positions.len();
    let point: Vec<usize> = (0..n)
        .map(|i| {
            let p = mesh.positions[i].as_dvec3();
            (0..=i)
                .find(|&j| (mesh.positions[j].as_dvec3() - p).length() <= same)
                .unwrap()
        })
        .collect();
    let mut edges = std::collections::HashMap::new();
    for tri in &mesh.indices {
        for k in 0..3 {
            let (a, b) = (point[tri[k] as usize], point[tri[(k + 1) % 3] as usize]);
            if a != b {
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
    }
    edges.values().filter(|&&c| c != 2).count()
}

/// Kim's (2013) pipeline end to end: the game build cuts a closed mesh,
/// leaving T-junctions (and so open edges); elimination removes every one
/// and the surface is closed again. Naive and fast forms agree.
#[test]
fn t_junction_elimination_closes_the_game_cut_mesh() {
    use raykit_core::tjunction::{eliminate, Method, TJunctionOptions};
    let mesh = closed_mesh(2);
    assert_eq!(open_edges(&mesh), 0);
    for h in [0u8, 6, 14] {
        let opts = KdOptions {
            split: KdSplit::Game(h),
            max_leaf_size: 3,
            ..KdOptions::default()
        };
        let (_, _, game) = build_game(&mesh, h, &opts);
        let cut = cut_mesh(&mesh, &game);
        let before = t_junctions_brute(&cut.mesh);
        assert!(before > 0, "H={h}: the cut mesh has T-junctions to remove");
        assert!(open_edges(&cut.mesh) > 0);
        let (fixed, report) =
            eliminate(&cut.mesh, Method::Fast, &TJunctionOptions::default()).unwrap();
        let (naive, _) = eliminate(&cut.mesh, Method::Naive, &TJunctionOptions::default()).unwrap();
        assert_eq!(
            fixed.indices, naive.indices,
            "H={h}: naive and fast outputs differ"
        );
        assert!(
            report.t_junctions > 0,
            "H={h}: the finder found none of the {before}"
        );
        assert_eq!(t_junctions_brute(&fixed), 0, "H={h}: T-junctions left");
        assert_eq!(
            open_edges(&fixed),
            0,
            "H={h}: the repaired surface is not closed"
        );
    }
}
