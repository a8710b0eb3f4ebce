//! `KdRopes::flat` hands a device the rope traversal's arrays: checked
//! against the cells recomputed from the flat nodes' split planes alone
//! and against the stack kd-tree's leaves of the same build.

use raykit_core::accel::{FlatKdRopes, KdOptions, KdRopes, KdStack};
use raykit_core::tri::Moller;
use raykit_core::TriangleMesh;

mod soup;

fn soup(n: usize, seed: u64) -> TriangleMesh {
    soup::soup(n, seed, 0.01, 0.2, 2)
}

const LEAF: u32 = 1 << 31;

/// Each node's cell from the root cell and the split planes.
fn cells(nodes: &[u32], root: ([f32; 3], [f32; 3])) -> Vec<([f32; 3], [f32; 3])> {
    let mut cells = vec![root; nodes.len() / 2];
    for i in 0..cells.len() {
        let word = nodes[2 * i];
        if word & LEAF == 0 {
            let a = ((word >> 29) & 3) as usize;
            let s = f32::from_bits(nodes[2 * i + 1]);
            let c = (word & ((1 << 28) - 1)) as usize;
            let (mut below, mut above) = (cells[i], cells[i]);
            below.1[a] = s;
            above.0[a] = s;
            cells[c] = below;
            cells[c + 1] = above;
        }
    }
    cells
}

#[test]
fn leaf_records_hold_the_cells_ropes_to_touching_nodes_and_the_stack_trees_entries() {
    let mesh = soup(3000, 11);
    let opts = KdOptions::default();
    let ropes = KdRopes::<Moller>::build(&mesh, &opts).flat();
    let stack = KdStack::<Moller>::build(&mesh, &opts).tree().flat();
    // The same tree: inner nodes equal, leaves differ only in their word.
    assert_eq!(ropes.nodes.len(), stack.nodes.len());
    assert_eq!(ropes.indices, stack.indices);
    assert_eq!(ropes.tris.prims, stack.tris.prims);
    let root = (ropes.root_min, ropes.root_max);
    let cell = cells(&ropes.nodes, root);
    let w = FlatKdRopes::LEAF_WORDS;
    assert_eq!(ropes.leaves.len() % w, 0);
    let mut seen = vec![false; ropes.leaves.len() / w];
    let mut ropes_checked = 0;
    for i in 0..cell.len() {
        let word = ropes.nodes[2 * i];
        if word & LEAF == 0 {
            assert_eq!(word, stack.nodes[2 * i]);
            assert_eq!(ropes.nodes[2 * i + 1], stack.nodes[2 * i + 1]);
            continue;
        }
        let k = (word & !LEAF) as usize;
        assert!(!seen[k], "leaf record {k} shared");
        seen[k] = true;
        let r = &ropes.leaves[k * w..(k + 1) * w];
        let f = |j: usize| f32::from_bits(r[j]);
        let (lo, hi) = cell[i];
        assert_eq!([f(0), f(1), f(2)], lo, "leaf {i} cell min");
        assert_eq!([f(3), f(4), f(5)], hi, "leaf {i} cell max");
        // First entry and count as the stack tree's leaf lists them.
        assert_eq!(r[12], stack.nodes[2 * i] & !LEAF);
        assert_eq!(r[13], stack.nodes[2 * i + 1]);
        assert_eq!(r[13], ropes.nodes[2 * i + 1]);
        for face in 0..6 {
            let (a, up) = (face / 2, face % 2 == 1);
            let plane = if up { hi[a] } else { lo[a] };
            let boundary = plane == if up { root.1[a] } else { root.0[a] };
            let rope = r[6 + face];
            if rope == FlatKdRopes::NO_ROPE {
                assert!(boundary, "leaf {i} face {face}: no rope inside the scene");
                continue;
            }
            assert!(!boundary, "leaf {i} face {face}: rope out of the scene");
            // The rope's node lies across the face and covers all of it.
            let (nlo, nhi) = cell[rope as usize];
            assert_eq!(
                if up { nlo[a] } else { nhi[a] },
                plane,
                "leaf {i} face {face}"
            );
            for b in (0..3).filter(|&b| b != a) {
                assert!(nlo[b] <= lo[b] && hi[b] <= nhi[b], "leaf {i} face {face}");
            }
            ropes_checked += 1;
        }
    }
    assert!(seen.iter().all(|&s| s), "a leaf record no node points at");
    assert!(ropes_checked > 1000);
}
