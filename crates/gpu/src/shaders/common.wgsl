// Shared by every kernel: the ray and hit records and float helpers whose
// NaN behaviour matches Rust's f32::min / f32::max, so that the slab tests
// drop a NaN from 0 * inf exactly as the CPU code does.

struct RayIn {
    o: vec3f,
    tnear: f32,
    d: vec3f,
    tfar: f32,
    inv: vec3f,
}

struct Hit {
    t: f32,
    u: f32,
    v: f32,
    prim: u32,
}

const MISS: u32 = 0xffffffffu;
const F32_EPS: f32 = 1.1920929e-7;
// Half an ulp of 1.
const U: f32 = 5.9604645e-8;
// 1 + 2 gamma(3): widens a slab exit past its rounding (see NodeBox::ROBUST_EXIT).
const ROBUST_EXIT: f32 = 1.0000003576279;
const MAX_EDGE_TOLERANCE: f32 = 0.00390625;

fn inf() -> f32 {
    return bitcast<f32>(0x7f800000u);
}

fn is_nan(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) > 0x7f800000u;
}

// Rust's f32::min: a NaN operand yields the other one.
fn fmin(a: f32, b: f32) -> f32 {
    if is_nan(a) {
        return b;
    }
    if is_nan(b) {
        return a;
    }
    return min(a, b);
}

// Rust's f32::max: a NaN operand yields the other one.
fn fmax(a: f32, b: f32) -> f32 {
    if is_nan(a) {
        return b;
    }
    if is_nan(b) {
        return a;
    }
    return max(a, b);
}

fn max_abs3(v: vec3f) -> f32 {
    let a = abs(v);
    return fmax(fmax(a.x, a.y), a.z);
}

fn make_ray(o: vec3f, d: vec3f, tnear: f32, tfar: f32) -> RayIn {
    return RayIn(o, tnear, d, tfar, vec3f(1.0) / d);
}

fn miss_hit() -> Hit {
    return Hit(inf(), 0.0, 0.0, MISS);
}
