// The Whitted renderer's shading data (group 1), shared by the stack kd-tree GPU tracer's
// single kernel and the Purcell-style stream tracer's stream kernels: per-triangle corners,
// vertex normals and material, the material and light tables, the frame's
// parameters, the ray counters and the radiance accumulator.
// See crates/gpu/src/render/upload.rs for the layouts.

struct ShadeParams {
    eye: vec3f,
    width: u32,
    forward: vec3f,
    height: u32,
    right: vec3f,
    num_lights: u32,
    up: vec3f,
    max_depth: u32,
    ambient: vec3f,
    bias: f32,
    env_color: vec3f,
    env_kind: u32,
    has_normals: u32,
    shadows: u32,
    lights_offset: u32,
    // 1 - 1e-4 rounded to f32 on the host, as the CPU shortens shadow rays.
    shadow_scale: f32,
    // The equirectangular map (env_kind 2 and 3): size, turn (rotation as a
    // fraction of a full turn), intensity; the environment box (env_kind 3).
    map_width: u32,
    map_height: u32,
    map_turn: f32,
    map_intensity: f32,
    box_min: vec3f,
    _pad0: u32,
    box_max: vec3f,
    _pad1: u32,
    box_center: vec3f,
    _pad2: u32,
}

// 26 words per triangle: corners a, b, c; vertex normals na, nb, nc;
// material index; one unused word; texture coordinates ta, tb, tc.
@group(1) @binding(0) var<storage, read> shade_tris: array<u32>;
// Materials (16 words each) from word 0, lights (16 words each) from
// sp.lights_offset.
@group(1) @binding(1) var<storage, read> tables: array<u32>;
@group(1) @binding(2) var<uniform> sp: ShadeParams;
// [shadow rays, secondary rays, environment hits, next-queue length,
// status]: the status slot is set to 1 by a thread whose loops the driver
// cut short (report_loop_cut).
@group(1) @binding(3) var<storage, read_write> counters: array<atomic<u32>>;
// Linear radiance summed over samples, three f32 bit patterns per pixel.
@group(1) @binding(4) var<storage, read_write> radiance: array<atomic<u32>>;
// The environment map's linear RGB texels, row-major (one word without a map).
@group(1) @binding(5) var<storage, read> env_texels: array<f32>;
// Every material's base-colour texture, linear RGB, one after the other.
@group(1) @binding(6) var<storage, read> tex_texels: array<f32>;

const F32_MIN_POSITIVE: f32 = 1.17549435e-38;

fn sw3(i: u32) -> vec3f {
    return vec3f(bitcast<f32>(shade_tris[i]), bitcast<f32>(shade_tris[i + 1u]), bitcast<f32>(shade_tris[i + 2u]));
}

fn sw2(i: u32) -> vec2f {
    return vec2f(bitcast<f32>(shade_tris[i]), bitcast<f32>(shade_tris[i + 1u]));
}

fn tf(i: u32) -> f32 {
    return bitcast<f32>(tables[i]);
}

fn tv3(i: u32) -> vec3f {
    return vec3f(tf(i), tf(i + 1u), tf(i + 2u));
}

fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// glam's normalize_or: v times the reciprocal of its length, or fallback.
fn normalize_or(v: vec3f, fallback: vec3f) -> vec3f {
    let rcp = 1.0 / sqrt(dot3(v, v));
    if is_finite(rcp) && rcp > 0.0 {
        return v * rcp;
    }
    return fallback;
}

// glam's normalize (no fallback).
fn normalize3(v: vec3f) -> vec3f {
    return v * (1.0 / sqrt(dot3(v, v)));
}

// The surface at a hit, as crates/render/src/surface.rs computes it.
struct Surface {
    point: vec3f,
    ng: vec3f,
    ns: vec3f,
    front: bool,
    material: u32,
    uv: vec2f,
}

fn surface_at(r: RayIn, h: Hit) -> Surface {
    let b = 26u * h.prim;
    let a = sw3(b);
    let bb = sw3(b + 3u);
    let c = sw3(b + 6u);
    let u = h.u;
    let v = h.v;
    let w = 1.0 - u - v;
    let point = a * w + bb * u + c * v;
    var ng = normalize_or(cross3(bb - a, c - a), vec3f(0.0));
    let front = dot3(ng, r.d) <= 0.0;
    if !front {
        ng = -ng;
    }
    var ns = ng;
    if sp.has_normals != 0u {
        ns = normalize_or(sw3(b + 9u) * w + sw3(b + 12u) * u + sw3(b + 15u) * v, ng);
    }
    if dot3(ns, ng) < 0.0 {
        ns = -ns;
    }
    let uv = sw2(b + 20u) * w + sw2(b + 22u) * u + sw2(b + 24u) * v;
    return Surface(point, ng, ns, front, shade_tris[b + 18u], uv);
}

// Add c to pixel p's sum (a compare-and-swap loop per channel: WGSL has no
// float atomics, and the stream's rays of one pixel may meet in one stage).
// The swap loop ends only by break, once the sum is stored.
fn add_radiance(p: u32, c: vec3f) {
    var k = 0u;
    for (; k < 3u; k++) {
        let i = 3u * p + k;
        var old = atomicLoad(&radiance[i]);
        var stored = false;
        loop {
            let r = atomicCompareExchangeWeak(&radiance[i], old, bitcast<u32>(bitcast<f32>(old) + c[k]));
            if r.exchanged {
                stored = true;
                break;
            }
            old = r.old_value;
        }
        if !stored {
            loop_cut = true;
        }
    }
    if k < 3u {
        loop_cut = true;
    }
}

// Set the status slot when this thread's loops were cut short (loop_cut,
// see scene.wgsl); called last by every kernel that traces or shades.
fn report_loop_cut() {
    if loop_cut {
        atomicStore(&counters[4], 1u);
    }
}

// The camera ray through image position (fx, fy), as Camera::rays computes it.
fn camera_ray(fx: f32, fy: f32) -> RayIn {
    let sx = 2.0 * fx / f32(sp.width) - 1.0;
    let sy = 1.0 - 2.0 * fy / f32(sp.height);
    let d = normalize3(sp.forward + sp.right * sx + sp.up * sy);
    return make_ray(sp.eye, d, 0.0, inf());
}

fn tex_texel(first: u32, w: i32, h: i32, i: i32, j: i32) -> vec3f {
    var ii = i % w;
    if ii < 0 {
        ii += w;
    }
    var jj = j % h;
    if jj < 0 {
        jj += h;
    }
    let k = 3u * (first + u32(jj * w + ii));
    return vec3f(tex_texels[k], tex_texels[k + 1u], tex_texels[k + 2u]);
}

// Texture::sample: bilinear, repeating, texel centres at (i + 1/2) / width;
// the texture of material record mb, or 1 without one.
fn base_colour(mb: u32, uv: vec2f) -> vec3f {
    let first = tables[mb + 13u];
    let w = i32(tables[mb + 14u]);
    let h = i32(tables[mb + 15u]);
    if w == 0 || h == 0 {
        return vec3f(1.0);
    }
    let x = uv.x * f32(w) - 0.5;
    let y = uv.y * f32(h) - 0.5;
    if !(is_finite(x) && is_finite(y)) {
        return tex_texel(first, w, h, 0, 0);
    }
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let i = i32(x0);
    let j = i32(y0);
    let top = tex_texel(first, w, h, i, j) * (1.0 - fx) + tex_texel(first, w, h, i + 1, j) * fx;
    let bottom = tex_texel(first, w, h, i, j + 1) * (1.0 - fx) + tex_texel(first, w, h, i + 1, j + 1) * fx;
    return top * (1.0 - fy) + bottom * fy;
}
