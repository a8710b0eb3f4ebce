// The stack kd-tree GPU tracer's kd-tree traversal with a fixed-size per-thread stack in
// private memory (crates/core/src/accel/kdtree/stack.rs): 8-byte nodes (leaf
// bit, 2 axis bits, 28-bit first-child offset; split or leaf count), near
// child first, far child pushed with its segment, stop at the first leaf
// whose segment holds the nearest hit; no node is visited twice.

@group(0) @binding(0) var<storage, read> nodes: array<u32>;

const KD_LEAF: u32 = 0x80000000u;
const KD_OFFSET: u32 = 0x0fffffffu;
const KD_STACK: u32 = 64u;

fn kd_trace(r: RayIn, any: bool) -> Hit {
    var best = miss_hit();
    if accel.num_indices == 0u {
        return best;
    }
    // The ray's interval inside the root cell.
    var tmin = r.tnear;
    var tmax = inf();
    var axis = 0u;
    for (; axis < 3u; axis++) {
        let t0 = (accel.root_min[axis] - r.o[axis]) * r.inv[axis];
        let t1 = (accel.root_max[axis] - r.o[axis]) * r.inv[axis];
        tmin = fmax(tmin, fmin(t0, t1));
        tmax = fmin(tmax, fmax(t0, t1));
    }
    if axis < 3u {
        loop_cut = true;
    }
    tmax = fmin(tmax * ROBUST_EXIT, r.tfar);
    if !(tmin <= tmax) {
        return best;
    }
    let rd = tri_prepare(r);
    var stack_node: array<u32, KD_STACK>;
    var stack_t0: array<f32, KD_STACK>;
    var stack_t1: array<f32, KD_STACK>;
    var sp = 0u;
    var node = 0u;
    loop {
        let word = nodes[2u * node];
        let data = nodes[2u * node + 1u];
        note_node(8u);
        if (word & KD_LEAF) == 0u {
            let a = (word >> 29u) & 3u;
            let split = bitcast<f32>(data);
            let oa = r.o[a];
            let ts = (split - oa) * r.inv[a];
            let below_first = (oa < split) | ((oa == split) & (r.d[a] <= 0.0));
            let c = word & KD_OFFSET;
            let first = select(c + 1u, c, below_first);
            let second = select(c, c + 1u, below_first);
            // A NaN (ray lying in the plane) goes to the near side only. A
            // plane at or behind the origin is crossed, in order of t, from
            // the far side to the near one (negative tnear).
            let behind = ts <= 0.0;
            let enter = select(first, second, behind);
            let leave = select(second, first, behind);
            if is_nan(ts) | (!behind & (ts > tmax)) | (behind & (ts <= tmin)) {
                node = first;
            } else if (!behind & (ts < tmin)) | (behind & (ts >= tmax)) {
                node = second;
            } else {
                if sp < KD_STACK {
                    stack_node[sp] = leave;
                    stack_t0[sp] = ts;
                    stack_t1[sp] = tmax;
                    sp += 1u;
                }
                node = enter;
                tmax = ts;
            }
            continue;
        }
        let start = word & ~KD_LEAF;
        var k = 0u;
        for (; k < data; k++) {
            note_bytes(4u);
            if test_triangle(indices[start + k], r, rd, any, &best) {
                return Hit(0.0, 0.0, 0.0, 0u);
            }
        }
        if k < data {
            loop_cut = true;
        }
        let tfar = fmin(best.t, r.tfar);
        if tfar <= tmax {
            return best;
        }
        var found = false;
        loop {
            if sp == 0u {
                break;
            }
            sp -= 1u;
            if stack_t0[sp] <= tfar {
                node = stack_node[sp];
                tmin = stack_t0[sp];
                tmax = stack_t1[sp];
                found = true;
                break;
            }
        }
        if !found {
            // The pop loop ends by break; with entries left it was cut.
            if sp != 0u {
                loop_cut = true;
            }
            return best;
        }
    }
    // The loop ends only by return.
    loop_cut = true;
    return best;
}

fn scene_intersect(r: RayIn) -> Hit {
    return kd_trace(r, false);
}

fn scene_occluded(r: RayIn) -> bool {
    return kd_trace(r, true).prim != MISS;
}
