// The Purcell-style stream tracer's stackless BVH (crates/core/src/accel/bvh/threaded.rs): nodes
// in pre-order, eight words each (padded box, escape index, leaf range with
// the count in the top 5 bits); one loop, hit -> next node, miss or leaf ->
// escape.

@group(0) @binding(0) var<storage, read> nodes: array<u32>;

const BVH_COUNT_SHIFT: u32 = 27u;
const BVH_FIRST_MASK: u32 = 0x07ffffffu;

// Entry distance into node n's box within [tnear, tfar], or +inf
// (NodeBox::entry: the exit widened by 3 ulps, NaNs from 0 * inf dropped).
fn box_entry(n: u32, r: RayIn, tnear: f32, tfar: f32) -> f32 {
    let b = 8u * n;
    note_node(32u);
    let lo = vec3f(bitcast<f32>(nodes[b]), bitcast<f32>(nodes[b + 1u]), bitcast<f32>(nodes[b + 2u]));
    let hi = vec3f(bitcast<f32>(nodes[b + 3u]), bitcast<f32>(nodes[b + 4u]), bitcast<f32>(nodes[b + 5u]));
    let t0 = (lo - r.o) * r.inv;
    let t1 = (hi - r.o) * r.inv;
    let enter = fmax(fmax(fmax(fmin(t0.x, t1.x), fmin(t0.y, t1.y)), fmin(t0.z, t1.z)), tnear);
    let exit = fmin(fmin(fmin(fmax(t0.x, t1.x), fmax(t0.y, t1.y)), fmax(t0.z, t1.z)) * ROBUST_EXIT, tfar);
    if enter <= exit {
        return enter;
    }
    return inf();
}

fn bvh_trace(r: RayIn, any: bool) -> Hit {
    var best = miss_hit();
    if accel.num_tris == 0u {
        return best;
    }
    let rd = tri_prepare(r);
    let end = accel.num_nodes;
    var idx = 0u;
    while idx < end {
        let tfar = fmin(best.t, r.tfar);
        if box_entry(idx, r, r.tnear, tfar) == inf() {
            idx = nodes[8u * idx + 6u];
            continue;
        }
        let packed = nodes[8u * idx + 7u];
        let count = packed >> BVH_COUNT_SHIFT;
        if count > 0u {
            let first = packed & BVH_FIRST_MASK;
            var k = 0u;
            for (; k < count; k++) {
                if test_triangle(first + k, r, rd, any, &best) {
                    return Hit(0.0, 0.0, 0.0, 0u);
                }
            }
            if k < count {
                loop_cut = true;
            }
            idx = nodes[8u * idx + 6u];
        } else {
            idx += 1u;
        }
    }
    if idx < end {
        loop_cut = true;
    }
    return best;
}

fn scene_intersect(r: RayIn) -> Hit {
    return bvh_trace(r, false);
}

fn scene_occluded(r: RayIn) -> bool {
    return bvh_trace(r, true).prim != MISS;
}
