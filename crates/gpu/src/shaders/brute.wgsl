// Every ray against every triangle: the GPU reference.

@group(0) @binding(0) var<storage, read> nodes: array<u32>;

fn brute_trace(r: RayIn, any: bool) -> Hit {
    var best = miss_hit();
    let rd = tri_prepare(r);
    var i = 0u;
    for (; i < accel.num_tris; i++) {
        if test_triangle(i, r, rd, any, &best) {
            return Hit(0.0, 0.0, 0.0, 0u);
        }
    }
    if i < accel.num_tris {
        loop_cut = true;
    }
    return best;
}

fn scene_intersect(r: RayIn) -> Hit {
    return brute_trace(r, false);
}

fn scene_occluded(r: RayIn) -> bool {
    return brute_trace(r, true).prim != MISS;
}
