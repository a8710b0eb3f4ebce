// The compressed wide BVH of Ylitie, Karras and Laine (2017), made on the
// CPU from raykit's 8-wide BVH (crates/gpu/src/cwbvh.rs has the 80-byte
// node layout). Traversal keeps two groups, as in the paper: a node group
// (the first inner child's index, the inner children still to visit as bits
// 24-31 in octant order, imask in bits 0-7) and a triangle group (the
// first triangle's index, the triangles still to test as bits 0-23); node
// groups with children left wait on a per-thread stack of CW_STACK entries.
// A child's box is decoded in f32 (p + q * 2^e) and tested as the CPU tests
// its exact box; the decoded box contains the exact one, so no hit is lost.

@group(0) @binding(0) var<storage, read> cw_nodes: array<vec4u>;

const CW_STACK: u32 = 32u;

// The byte of slot s in the pair of words (lo, hi) holding eight bytes.
fn cw_byte(lo: u32, hi: u32, s: u32) -> f32 {
    let w = select(lo, hi, s >= 4u);
    return f32((w >> (8u * (s & 3u))) & 0xffu);
}

// One node: the children whose boxes the ray enters within [tnear, tfar],
// as the hit bits of a node group (inner children at 24 + (slot ^ oct_inv))
// and a triangle group (each leaf's triangles at their offsets).
fn cw_node(n: u32, r: RayIn, tfar: f32, oct_inv: u32) -> array<vec2u, 2> {
    let q0 = cw_nodes[5u * n];
    let q1 = cw_nodes[5u * n + 1u];
    let q2 = cw_nodes[5u * n + 2u];
    let q3 = cw_nodes[5u * n + 3u];
    let q4 = cw_nodes[5u * n + 4u];
    note_node(80u);
    let p = vec3f(bitcast<f32>(q0.x), bitcast<f32>(q0.y), bitcast<f32>(q0.z));
    let ew = q0.w;
    let scale = vec3f(
        bitcast<f32>((ew & 0xffu) << 23u),
        bitcast<f32>(((ew >> 8u) & 0xffu) << 23u),
        bitcast<f32>(((ew >> 16u) & 0xffu) << 23u),
    );
    let imask = ew >> 24u;
    let child_base = q1.x;
    let tri_base = q1.y;
    var hits = 0u;
    var s = 0u;
    for (; s < 8u; s++) {
        let child_meta = (select(q1.z, q1.w, s >= 4u) >> (8u * (s & 3u))) & 0xffu;
        if child_meta == 0u {
            continue;
        }
        // lo_x q2.xy, lo_y q2.zw, lo_z q3.xy, hi_x q3.zw, hi_y q4.xy, hi_z q4.zw.
        let lo = p + vec3f(cw_byte(q2.x, q2.y, s), cw_byte(q2.z, q2.w, s), cw_byte(q3.x, q3.y, s)) * scale;
        let hi = p + vec3f(cw_byte(q3.z, q3.w, s), cw_byte(q4.x, q4.y, s), cw_byte(q4.z, q4.w, s)) * scale;
        let t0 = (lo - r.o) * r.inv;
        let t1 = (hi - r.o) * r.inv;
        let enter = fmax(fmax(fmax(fmin(t0.x, t1.x), fmin(t0.y, t1.y)), fmin(t0.z, t1.z)), r.tnear);
        let exit = fmin(fmin(fmin(fmax(t0.x, t1.x), fmax(t0.y, t1.y)), fmax(t0.z, t1.z)) * ROBUST_EXIT, tfar);
        if enter <= exit {
            if ((imask >> s) & 1u) != 0u {
                hits |= 1u << (24u + (s ^ oct_inv));
            } else {
                hits |= (child_meta >> 5u) << (child_meta & 31u);
            }
        }
    }
    if s < 8u {
        loop_cut = true;
    }
    return array<vec2u, 2>(vec2u(child_base, (hits & 0xff000000u) | imask), vec2u(tri_base, hits & 0x00ffffffu));
}

fn cw_trace(r: RayIn, any: bool) -> Hit {
    var best = miss_hit();
    if accel.num_tris == 0u {
        return best;
    }
    let rd = tri_prepare(r);
    let oct = select(0u, 1u, r.d.x < 0.0) | select(0u, 2u, r.d.y < 0.0) | select(0u, 4u, r.d.z < 0.0);
    let oct_inv = 7u - oct;
    var stack: array<vec2u, CW_STACK>;
    var sp = 0u;
    // The root as the only inner child of an imaginary node: bit 31,
    // imask 0, so it is node 0 + 0.
    var group = vec2u(0u, 0x80000000u);
    loop {
        var tris = vec2u(0u, 0u);
        if group.y > 0x00ffffffu {
            let bit = firstLeadingBit(group.y);
            group.y &= ~(1u << bit);
            if group.y > 0x00ffffffu {
                stack[sp] = group;
                sp += 1u;
            }
            let slot = (bit - 24u) ^ oct_inv;
            let node = group.x + countOneBits(group.y & 0xffu & ((1u << slot) - 1u));
            let g = cw_node(node, r, fmin(best.t, r.tfar), oct_inv);
            group = g[0];
            tris = g[1];
        }
        while tris.y != 0u {
            let bit = firstLeadingBit(tris.y);
            tris.y &= ~(1u << bit);
            if test_triangle(tris.x + bit, r, rd, any, &best) {
                return Hit(0.0, 0.0, 0.0, 0u);
            }
        }
        if tris.y != 0u {
            loop_cut = true;
        }
        if group.y <= 0x00ffffffu {
            if sp == 0u {
                break;
            }
            sp -= 1u;
            group = stack[sp];
        }
    }
    // The loop ends by break once no node group is left.
    if group.y > 0x00ffffffu {
        loop_cut = true;
    }
    return best;
}

fn scene_intersect(r: RayIn) -> Hit {
    return cw_trace(r, false);
}

fn scene_occluded(r: RayIn) -> bool {
    return cw_trace(r, true).prim != MISS;
}
