// Stackless kd-tree traversal with ropes and leaf boxes (Popov, Günther,
// Seidel & Slusallek 2007; crates/core/src/accel/kdtree/ropes.rs): the
// 8-byte nodes of kd_stack.wgsl, a leaf's first word holding the leaf bit
// and the index of its leaf record, its second word the entry count. The
// leaf records (binding 8) are 13 words each: cell min x, y, z, cell max
// x, y, z, six ropes (the node across face 2 * axis + (1 for the max
// face), 0xffffffff on the scene boundary) and the first entry in the
// triangle-index list. The ray
// enters the leaf holding its entry point, then walks from leaf to leaf
// through the exit face's rope, descending from the rope's node to the
// leaf holding the exit point: no stack, and every step moves forward
// along the ray, so no leaf is visited twice.

@group(0) @binding(0) var<storage, read> nodes: array<u32>;
@group(0) @binding(8) var<storage, read> leaves: array<u32>;

const ROPE_LEAF: u32 = 0x80000000u;
const ROPE_OFFSET: u32 = 0x0fffffffu;
const ROPE_NONE: u32 = 0xffffffffu;
const ROPE_LEAF_WORDS: u32 = 13u;

// Descend from node start to the leaf whose cell holds p, a point on a
// split plane going to the side the ray moves into; returns the word
// offset of the leaf's record and the leaf's entry count.
fn rope_locate(start: u32, p: vec3f, d: vec3f) -> vec2u {
    var node = start;
    loop {
        let word = nodes[2u * node];
        let data = nodes[2u * node + 1u];
        note_node(8u);
        if (word & ROPE_LEAF) != 0u {
            return vec2u(ROPE_LEAF_WORDS * (word & ~ROPE_LEAF), data);
        }
        let a = (word >> 29u) & 3u;
        let s = bitcast<f32>(data);
        let above = (p[a] > s) | ((p[a] == s) & (d[a] > 0.0));
        node = (word & ROPE_OFFSET) + select(0u, 1u, above);
    }
    // The loop ends only by return.
    loop_cut = true;
    return vec2u(0u, 0u);
}

fn ropes_trace(r: RayIn, any: bool) -> Hit {
    var best = miss_hit();
    if accel.num_indices == 0u {
        return best;
    }
    // The ray's interval inside the root cell.
    var tmin = r.tnear;
    var scene_exit = inf();
    var axis = 0u;
    for (; axis < 3u; axis++) {
        let t0 = (accel.root_min[axis] - r.o[axis]) * r.inv[axis];
        let t1 = (accel.root_max[axis] - r.o[axis]) * r.inv[axis];
        tmin = fmax(tmin, fmin(t0, t1));
        scene_exit = fmin(scene_exit, fmax(t0, t1));
    }
    if axis < 3u {
        loop_cut = true;
    }
    scene_exit = fmin(scene_exit * ROBUST_EXIT, r.tfar);
    if !(tmin <= scene_exit) {
        return best;
    }
    let rd = tri_prepare(r);
    let num_leaves = arrayLength(&leaves) / ROPE_LEAF_WORDS;
    var leaf = rope_locate(0u, r.o + r.d * tmin, r.d);
    // The bound only guards against a broken tree.
    var step = 0u;
    for (; step < num_leaves; step++) {
        let rec = leaf.x;
        let count = leaf.y;
        if count > 0u {
            let first = leaves[rec + 12u];
            note_bytes(4u);
            var k = 0u;
            for (; k < count; k++) {
                note_bytes(4u);
                if test_triangle(indices[first + k], r, rd, any, &best) {
                    return Hit(0.0, 0.0, 0.0, 0u);
                }
            }
            if k < count {
                loop_cut = true;
            }
        }
        // The exit face: the nearest of the cell's faces the ray moves towards.
        var exit = inf();
        var face = 0u;
        var plane = 0.0;
        var a = 0u;
        for (; a < 3u; a++) {
            let da = r.d[a];
            if da != 0.0 {
                let up = da > 0.0;
                let pl = bitcast<f32>(leaves[rec + a + select(0u, 3u, up)]);
                note_bytes(4u);
                let te = (pl - r.o[a]) * r.inv[a];
                if !is_nan(te) && te < exit {
                    exit = te;
                    face = 2u * a + select(0u, 1u, up);
                    plane = pl;
                }
            }
        }
        if a < 3u {
            loop_cut = true;
        }
        let tfar = fmin(best.t, r.tfar);
        if (tfar <= exit) | (exit >= scene_exit) {
            return best;
        }
        let next = leaves[rec + 6u + face];
        note_bytes(4u);
        if next == ROPE_NONE {
            return best;
        }
        // The exit point, exactly on the face's plane.
        var p = r.o + r.d * exit;
        p[face / 2u] = plane;
        leaf = rope_locate(next, p, r.d);
    }
    if step < num_leaves {
        loop_cut = true;
    }
    return best;
}

fn scene_intersect(r: RayIn) -> Hit {
    return ropes_trace(r, false);
}

fn scene_occluded(r: RayIn) -> bool {
    return ropes_trace(r, true).prim != MISS;
}
