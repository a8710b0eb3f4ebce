// The scene's bindings (group 0), shared by every kernel that traces the
// triangle mesh: the structure's nodes and index list, the precomputed
// triangle records in leaf order and their mesh triangle indices. Records
// beyond one storage binding's limit continue in up to three more bindings
// of chunk_words words each (whole records); a scene that fits one binding
// has chunk_words = 0xffffffff and never reads the others.
// Binding 8 holds the kd-tree's leaf records with ropes (kd_ropes.wgsl
// declares it; empty for the other structures).
// Accel files (kd_stack.wgsl, bvh_threaded.wgsl, cwbvh.wgsl, brute.wgsl)
// declare binding 0 (the nodes, as words or as 16-byte vectors) and define
// scene_intersect(ray) -> Hit and scene_occluded(ray) -> bool over them.
// Every triangle record fetched is noted (note_tri, see count_off.wgsl).
// Every traversal loop is followed by a check that it ended because its
// condition failed (or by return or break); one that ended with its
// condition still true was cut short by the driver, and sets loop_cut.
// Mesa's lavapipe ends every loop of an invocation once the invocation has
// made 65,535 loop passes in all, and goes on after the loop: without the
// check, the traversal would return a wrong answer. The entry kernels
// report loop_cut to the host, which refuses the results; on a GPU without
// such a limit the checks never fire.

struct AccelParams {
    root_min: vec3f,
    num_indices: u32,
    root_max: vec3f,
    num_nodes: u32,
    num_tris: u32,
    chunk_words: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(1) var<storage, read> indices: array<u32>;
@group(0) @binding(2) var<storage, read> tri_words: array<u32>;
@group(0) @binding(3) var<storage, read> prims: array<u32>;
@group(0) @binding(4) var<uniform> accel: AccelParams;
@group(0) @binding(5) var<storage, read> tri_words1: array<u32>;
@group(0) @binding(6) var<storage, read> tri_words2: array<u32>;
@group(0) @binding(7) var<storage, read> tri_words3: array<u32>;

var<private> loop_cut: bool;

struct TriHit {
    hit: bool,
    t: f32,
    u: f32,
    v: f32,
}

fn tw(i: u32) -> f32 {
    let c = accel.chunk_words;
    if i < c {
        return bitcast<f32>(tri_words[i]);
    }
    if i - c < c {
        return bitcast<f32>(tri_words1[i - c]);
    }
    if i - 2u * c < c {
        return bitcast<f32>(tri_words2[i - 2u * c]);
    }
    return bitcast<f32>(tri_words3[i - 3u * c]);
}

fn tw3(i: u32) -> vec3f {
    return vec3f(tw(i), tw(i + 1u), tw(i + 2u));
}

// glam's operation order, so results round as on the CPU.
fn dot3(a: vec3f, b: vec3f) -> f32 {
    return (a.x * b.x + a.y * b.y) + a.z * b.z;
}

fn cross3(a: vec3f, b: vec3f) -> vec3f {
    return vec3f(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// Test the triangle record at position i; nearest-hit mode keeps the
// nearest hit in best (ties keep the earlier triangle) and returns false;
// any-hit mode returns true at a hit.
fn test_triangle(i: u32, r: RayIn, rd: TriRay, any: bool, best: ptr<function, Hit>) -> bool {
    let tfar = (*best).t;
    note_tri(TRI_BYTES);
    if any {
        return tri_occluded(i, r, rd, fmin(tfar, r.tfar));
    }
    let h = tri_intersect(i, r, rd, fmin(tfar, r.tfar));
    if h.hit && ((*best).prim == MISS || h.t < (*best).t) {
        *best = Hit(h.t, h.u, h.v, prims[i]);
    }
    return false;
}
