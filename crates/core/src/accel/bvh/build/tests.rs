//! The BVH builders (binned SAH after Wald 2007 / Embree,
//! linear BVH after Karras 2012) give valid trees: every triangle in exactly
//! one leaf, every leaf's box the exact bounds of its triangles (recomputed
//! from the mesh), every inner box the union of its children's; and the same
//! tree whatever the number of threads.

use super::{build, tree_shape, BuildNode, BuildOptions, BuildQuality, BuildTree};
use crate::aabb::Aabb;
use crate::mesh::TriangleMesh;
use crate::rng::Pcg32;
use crate::test_soup;
use glam::Vec3;

const QUALITIES: [BuildQuality; 2] = [BuildQuality::Sah, BuildQuality::Fast];

/// `n` random triangles of varied size in the unit cube.
fn soup(n: usize, seed: u64) -> TriangleMesh {
    test_soup::soup(n, seed, 0.001, 0.05, 3)
}

/// `n` copies of one triangle (every centroid equal), plus a clustered
/// cloud: the degenerate inputs that force median splits.
fn degenerate(n: usize) -> TriangleMesh {
    let mut positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    let mut indices = vec![[0, 1, 2]; n];
    let mut rng = Pcg32::new(99);
    for _ in 0..n {
        let b = positions.len() as u32;
        let c = Vec3::splat(0.5) + rng.unit_vector() * 1e-6;
        positions.extend([c, c + Vec3::X * 1e-3, c + Vec3::Z * 1e-3]);
        indices.push([b, b + 1, b + 2]);
    }
    TriangleMesh::new(positions, indices)
}

/// Check the tree against the mesh; returns the number of leaves.
fn check_tree(mesh: &TriangleMesh, tree: &BuildTree, opts: &BuildOptions) -> usize {
    let n = mesh.num_triangles();
    let mut sorted = tree.order.clone();
    sorted.sort_unstable();
    assert!(
        sorted.iter().copied().eq(0..n as u32),
        "order is a permutation of the triangles"
    );
    let mut covered = vec![0u32; n];
    let mut leaves = 0;
    let mut stack = vec![(&tree.root, 0usize)];
    while let Some((node, depth)) = stack.pop() {
        assert!(depth <= crate::accel::bvh::MAX_DEPTH, "too deep");
        match node {
            BuildNode::Leaf {
                bounds,
                first,
                count,
            } => {
                leaves += 1;
                let range = *first as usize..(*first + *count) as usize;
                assert!(
                    *count as usize <= opts.max_leaf_size.max(1) || n == 0,
                    "leaf of {count} over max {}",
                    opts.max_leaf_size
                );
                let mut want = Aabb::EMPTY;
                for i in range {
                    covered[i] += 1;
                    want = want.union(mesh.triangle_bounds(tree.order[i] as usize));
                }
                assert_eq!(*bounds, want, "leaf box is its triangles' bounds");
            }
            BuildNode::Inner {
                bounds,
                children,
                leaf_ok,
            } => {
                if *leaf_ok {
                    assert!(opts.fill_wide_nodes, "marked only when filling");
                    let (_, count) = node.triangle_range();
                    assert!(count as usize <= opts.max_leaf_size, "a marked leaf fits");
                }
                let (first, count) = node.triangle_range();
                assert_eq!(
                    (first, count),
                    (children[0].triangle_range().0, leaf_total(node)),
                    "the subtree's range starts at its first leaf and holds every leaf's triangles"
                );
                let u = children[0].bounds().union(children[1].bounds());
                assert_eq!(*bounds, u, "inner box is its children's union");
                for c in children.iter() {
                    let b = c.bounds();
                    assert!(
                        bounds.min.cmple(b.min).all() && b.max.cmple(bounds.max).all(),
                        "child box inside its parent"
                    );
                    stack.push((c, depth + 1));
                }
            }
        }
    }
    assert!(
        covered.iter().all(|&c| c == 1),
        "every triangle in one leaf"
    );
    leaves
}

/// Structural equality of two trees (`BuildNode` has no `PartialEq`).
fn same_tree(a: &BuildNode, b: &BuildNode) -> bool {
    match (a, b) {
        (
            BuildNode::Leaf {
                bounds: b1,
                first: f1,
                count: c1,
            },
            BuildNode::Leaf {
                bounds: b2,
                first: f2,
                count: c2,
            },
        ) => b1 == b2 && f1 == f2 && c1 == c2,
        (
            BuildNode::Inner {
                bounds: b1,
                children: k1,
                leaf_ok: o1,
            },
            BuildNode::Inner {
                bounds: b2,
                children: k2,
                leaf_ok: o2,
            },
        ) => b1 == b2 && o1 == o2 && same_tree(&k1[0], &k2[0]) && same_tree(&k1[1], &k2[1]),
        _ => false,
    }
}

#[test]
fn every_builder_gives_valid_trees() {
    let meshes = [
        soup(0, 1),
        soup(1, 2),
        soup(2, 3),
        soup(33, 4),
        soup(5000, 5),
        soup(150_000, 6),
        degenerate(3000),
    ];
    for quality in QUALITIES {
        for (max_leaf_size, leaf_block, fill_wide_nodes) in [
            (1, 1, false),
            (4, 1, false),
            (4, 4, false),
            (8, 4, false),
            (31, 3, false),
            (16, 4, true),
            (31, 3, true),
        ] {
            let opts = BuildOptions {
                quality,
                max_leaf_size,
                leaf_block,
                fill_wide_nodes,
                ..BuildOptions::default()
            };
            for mesh in &meshes {
                let tree = build(mesh, &opts);
                let leaves = check_tree(mesh, &tree, &opts);
                let (_, l, _, _) = tree_shape(&tree.root, 1.0);
                assert_eq!(l, leaves);
            }
        }
    }
}

#[test]
fn builds_do_not_depend_on_threads() {
    let mesh = soup(200_000, 7);
    for (quality, fill_wide_nodes) in QUALITIES
        .map(|q| (q, false))
        .into_iter()
        .chain([(BuildQuality::Sah, true)])
    {
        let opts = BuildOptions {
            quality,
            fill_wide_nodes,
            leaf_block: if fill_wide_nodes { 4 } else { 1 },
            max_leaf_size: if fill_wide_nodes { 16 } else { 4 },
            ..BuildOptions::default()
        };
        let sequential = BuildOptions {
            parallel_threshold: usize::MAX,
            ..opts.clone()
        };
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        let a = pool(1).install(|| build(&mesh, &sequential));
        let b = pool(4).install(|| build(&mesh, &opts));
        let c = pool(3).install(|| build(&mesh, &opts));
        assert_eq!(a.order, b.order, "{quality:?}");
        assert!(same_tree(&a.root, &b.root), "{quality:?}");
        assert_eq!(b.order, c.order, "{quality:?}");
        assert!(same_tree(&b.root, &c.root), "{quality:?}");
    }
}

/// The SAH builder's tree costs less than the linear BVH's, and the linear
/// BVH stays within a small factor of it (a broken Morton order or split
/// search costs many times more).
#[test]
fn fast_build_costs_more_but_not_much_more() {
    let mesh = soup(60_000, 8);
    let cost = |quality| {
        let opts = BuildOptions {
            quality,
            ..BuildOptions::default()
        };
        tree_shape(&build(&mesh, &opts).root, opts.traversal_cost as f64).3
    };
    let (sah, fast) = (cost(BuildQuality::Sah), cost(BuildQuality::Fast));
    assert!(sah < fast, "SAH {sah} vs LBVH {fast}");
    assert!(fast < 2.0 * sah, "SAH {sah} vs LBVH {fast}");
}

/// The triangles of every leaf under `node`, summed over the whole subtree.
fn leaf_total(node: &BuildNode) -> u32 {
    match node {
        BuildNode::Leaf { count, .. } => *count,
        BuildNode::Inner { children, .. } => leaf_total(&children[0]) + leaf_total(&children[1]),
    }
}
