// The Purcell-style stream tracer's stream organisation: kernels chained through ray queues.
// raygen writes the camera rays into the queue; per bounce, intersect finds
// each queued ray's nearest hit, environment finishes the missed rays
// (state -1 -> -2) and shade adds each hit's local radiance and appends its
// reflection and refraction rays to the next queue with an atomic counter
// (state 1), or ends the path on the surface (-3).
// A thread whose loops were cut short by the driver (loop_cut, see
// scene.wgsl) sets the status slot counters[4], and the host refuses the
// frame.

struct StageParams {
    count: u32,
    row: u32,
    capacity: u32,
    record_first: u32,
}

struct QueuedRay {
    o: vec3f,
    pixel: u32,
    d: vec3f,
    depth: u32,
    w: vec3f,
    state: i32,
}

const STATE_ACTIVE: i32 = 0;
const STATE_MISSED: i32 = -1;
const STATE_ENVIRONMENT: i32 = -2;
const STATE_DIFFUSE: i32 = -3;
const STATE_BOUNCED: i32 = 1;

@group(2) @binding(0) var<storage, read_write> queue_in: array<QueuedRay>;
@group(2) @binding(1) var<storage, read_write> queue_out: array<QueuedRay>;
@group(2) @binding(2) var<storage, read_write> hits: array<Hit>;
@group(2) @binding(3) var<storage, read> positions: array<f32>;
@group(2) @binding(4) var<uniform> stage: StageParams;

fn thread_index(gid: vec3u) -> u32 {
    return gid.x + gid.y * stage.row;
}

@compute @workgroup_size(64)
fn raygen(@builtin(global_invocation_id) gid: vec3u) {
    let i = thread_index(gid);
    if i >= stage.count {
        return;
    }
    let r = camera_ray(positions[2u * i], positions[2u * i + 1u]);
    queue_in[i] = QueuedRay(r.o, i, r.d, 1u, vec3f(1.0), STATE_ACTIVE);
}

@compute @workgroup_size(64)
fn intersect(@builtin(global_invocation_id) gid: vec3u) {
    let i = thread_index(gid);
    if i >= stage.count {
        return;
    }
    let q = queue_in[i];
    let h = scene_intersect(make_ray(q.o, q.d, 0.0, inf()));
    hits[i] = h;
    if h.prim == MISS {
        queue_in[i].state = STATE_MISSED;
    }
    report_loop_cut();
}

@compute @workgroup_size(64)
fn miss(@builtin(global_invocation_id) gid: vec3u) {
    let i = thread_index(gid);
    if i >= stage.count || queue_in[i].state != STATE_MISSED {
        return;
    }
    let q = queue_in[i];
    atomicAdd(&counters[2], 1u);
    add_radiance(q.pixel, q.w * environment(q.o, q.d));
    queue_in[i].state = STATE_ENVIRONMENT;
    report_loop_cut();
}

fn push(q: QueuedRay, r: RayIn, w: vec3f) {
    let slot = atomicAdd(&counters[3], 1u);
    if slot < stage.capacity {
        queue_out[slot] = QueuedRay(r.o, q.pixel, r.d, q.depth + 1u, q.w * w, STATE_ACTIVE);
    }
}

@compute @workgroup_size(64)
fn shade(@builtin(global_invocation_id) gid: vec3u) {
    let i = thread_index(gid);
    if i >= stage.count || queue_in[i].state != STATE_ACTIVE {
        return;
    }
    let q = queue_in[i];
    let sc = scatter(make_ray(q.o, q.d, 0.0, inf()), hits[i], q.depth);
    add_radiance(q.pixel, q.w * sc.local);
    var state = STATE_DIFFUSE;
    if sc.has_reflect {
        push(q, sc.reflect_ray, sc.reflect_weight);
        state = STATE_BOUNCED;
    }
    if sc.has_refract {
        push(q, sc.refract_ray, sc.refract_weight);
        state = STATE_BOUNCED;
    }
    queue_in[i].state = state;
    report_loop_cut();
}
