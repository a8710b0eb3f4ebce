// The stack kd-tree GPU tracer's single kernel: one thread per pixel sample traces the camera
// ray, shades each hit (shadow rays to every light) and follows the
// reflection and refraction rays iteratively with a small per-thread stack
// of pending rays and their path weights, up to max_depth rays per path.
// The host refuses depths above STACK, which bounds the stack: each level
// leaves at most one pending sibling.
// A thread whose loops were cut short by the driver (loop_cut, see
// scene.wgsl) sets the status slot counters[4], and the host refuses the
// frame.

const STACK: u32 = 16u;

struct StageParams {
    count: u32,
    row: u32,
    capacity: u32,
    // 1 on the first camera sample: record the camera rays' hits (AOVs).
    record_first: u32,
}

// Sample positions of this pass, (fx, fy) per pixel.
@group(2) @binding(0) var<storage, read> positions: array<f32>;
@group(2) @binding(1) var<uniform> stage: StageParams;
// The first camera sample's nearest hit per pixel.
@group(2) @binding(2) var<storage, read_write> first_hits: array<Hit>;

struct Pending {
    o: vec3f,
    depth: u32,
    d: vec3f,
    w: vec3f,
}

@compute @workgroup_size(64)
fn render_pixel(@builtin(global_invocation_id) gid: vec3u) {
    let i = gid.x + gid.y * stage.row;
    if i >= stage.count {
        return;
    }
    let cam = camera_ray(positions[2u * i], positions[2u * i + 1u]);
    var stack: array<Pending, STACK>;
    stack[0] = Pending(cam.o, 1u, cam.d, vec3f(1.0));
    var top = 1u;
    var total = vec3f(0.0);
    while top > 0u {
        top -= 1u;
        let p = stack[top];
        let r = make_ray(p.o, p.d, 0.0, inf());
        let h = scene_intersect(r);
        if p.depth == 1u && stage.record_first != 0u {
            first_hits[i] = h;
        }
        if h.prim == MISS {
            atomicAdd(&counters[2], 1u);
            total += p.w * environment(r.o, r.d);
            continue;
        }
        let sc = scatter(r, h, p.depth);
        total += p.w * sc.local;
        // Refraction is pushed first so that reflection is followed first,
        // the CPU's order.
        if sc.has_refract && top < STACK {
            atomicAdd(&counters[1], 1u);
            stack[top] = Pending(sc.refract_ray.o, p.depth + 1u, sc.refract_ray.d, p.w * sc.refract_weight);
            top += 1u;
        }
        if sc.has_reflect && top < STACK {
            atomicAdd(&counters[1], 1u);
            stack[top] = Pending(sc.reflect_ray.o, p.depth + 1u, sc.reflect_ray.d, p.w * sc.reflect_weight);
            top += 1u;
        }
    }
    if top > 0u {
        loop_cut = true;
    }
    add_radiance(i, total);
    report_loop_cut();
}
