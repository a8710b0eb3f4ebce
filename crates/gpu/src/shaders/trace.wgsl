// Batch ray queries: one thread per ray of a ray buffer (8 floats per
// ray: origin, direction, tnear, tfar, as in raykit's ray files).
// Nearest hits are written as 4 words (t, prim, u, v), occlusion as 1 word.
// Word 4 * count of the output is the status word: any ray whose traversal
// loop was cut short (loop_cut, see scene.wgsl) writes 1 there.

struct TraceParams {
    count: u32,
    row: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(1) @binding(0) var<storage, read> rays: array<f32>;
@group(1) @binding(1) var<storage, read_write> out: array<u32>;
@group(1) @binding(2) var<uniform> tp: TraceParams;

fn load_ray(i: u32) -> RayIn {
    let b = 8u * i;
    return make_ray(vec3f(rays[b], rays[b + 1u], rays[b + 2u]), vec3f(rays[b + 3u], rays[b + 4u], rays[b + 5u]), rays[b + 6u], rays[b + 7u]);
}

@compute @workgroup_size(64)
fn trace_nearest(@builtin(global_invocation_id) gid: vec3u) {
    let i = gid.x + gid.y * tp.row;
    if i >= tp.count {
        return;
    }
    let h = scene_intersect(load_ray(i));
    out[4u * i] = bitcast<u32>(h.t);
    out[4u * i + 1u] = h.prim;
    out[4u * i + 2u] = bitcast<u32>(h.u);
    out[4u * i + 3u] = bitcast<u32>(h.v);
    if loop_cut {
        out[4u * tp.count] = 1u;
    }
    flush_counts();
}

@compute @workgroup_size(64)
fn trace_any(@builtin(global_invocation_id) gid: vec3u) {
    let i = gid.x + gid.y * tp.row;
    if i >= tp.count {
        return;
    }
    out[i] = select(0u, 1u, scene_occluded(load_ray(i)));
    if loop_cut {
        out[4u * tp.count] = 1u;
    }
    flush_counts();
}
