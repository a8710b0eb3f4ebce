// What rays leaving the scene see (crates/render/src/env, crates/render/src/sky.rs):
// env_kind 0 the sky gradient, 1 a constant radiance, 2 an equirectangular
// map looked up by direction, 3 The environment box (the map looked
// up from the box centre towards the ray's exit point).

const SKY_ZENITH: vec3f = vec3f(0.22, 0.40, 0.80);
const SKY_HORIZON: vec3f = vec3f(0.72, 0.80, 0.90);
const SKY_NADIR: vec3f = vec3f(0.30, 0.30, 0.32);
const PI_F32: f32 = 3.14159265358979;
const TAU_F32: f32 = 6.28318530717959;

fn lerp3(a: vec3f, b: vec3f, s: f32) -> vec3f {
    return a * (1.0 - s) + b * s;
}

fn finite3(v: vec3f) -> bool {
    return is_finite(v.x) && is_finite(v.y) && is_finite(v.z);
}

fn sky(d: vec3f) -> vec3f {
    let rcp = 1.0 / sqrt(dot3(d, d));
    if !(is_finite(rcp) && rcp > 0.0) {
        return vec3f(0.0);
    }
    let y = clamp((d * rcp).y, -1.0, 1.0);
    if y >= 0.0 {
        return lerp3(SKY_HORIZON, SKY_ZENITH, sqrt(y));
    }
    return lerp3(SKY_HORIZON, SKY_NADIR, sqrt(-y));
}

fn env_texel(i: i32, j: i32) -> vec3f {
    let k = 3u * (u32(j) * sp.map_width + u32(i));
    return vec3f(env_texels[k], env_texels[k + 1u], env_texels[k + 2u]);
}

// EquirectMap::sample_uv: bilinear, wrapping in u, clamping in v.
fn sample_uv(u: f32, v: f32) -> vec3f {
    if !(is_finite(u) && is_finite(v)) {
        return vec3f(0.0);
    }
    let w = i32(sp.map_width);
    let h = i32(sp.map_height);
    var ur = u % 1.0;
    if ur < 0.0 {
        ur += 1.0;
    }
    let x = ur * f32(sp.map_width) - 0.5;
    let y = clamp(v, 0.0, 1.0) * f32(sp.map_height) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    var i0 = i32(x0) % w;
    if i0 < 0 {
        i0 += w;
    }
    let i1 = (i0 + 1) % w;
    let j0 = clamp(i32(y0), 0, h - 1);
    let j1 = clamp(i32(y0) + 1, 0, h - 1);
    let top = env_texel(i0, j0) * (1.0 - fx) + env_texel(i1, j0) * fx;
    let bottom = env_texel(i0, j1) * (1.0 - fx) + env_texel(i1, j1) * fx;
    return top * (1.0 - fy) + bottom * fy;
}

// EquirectMap::lookup: y up, u = 0.5 + atan2(x, -z) / 2pi, v = acos(y) / pi.
fn map_lookup(d: vec3f) -> vec3f {
    if !finite3(d) || all(d == vec3f(0.0)) {
        return vec3f(0.0);
    }
    let u = clamp(0.5 + atan2(d.x, -d.z) / TAU_F32, 0.0, 1.0);
    let v = clamp(atan2(sqrt(d.x * d.x + d.z * d.z), d.y) / PI_F32, 0.0, 1.0);
    return sample_uv(u + sp.map_turn, v) * sp.map_intensity;
}

// exit_direction of crates/render/src/env/env_box.rs: the direction from
// the box centre to where the ray leaves the box, or d when it misses it.
fn box_direction(o: vec3f, d: vec3f) -> vec3f {
    if !(finite3(o) && finite3(d)) {
        return d;
    }
    var near = -inf();
    var far = inf();
    var a = 0;
    for (; a < 3; a++) {
        let lo = sp.box_min[a];
        let hi = sp.box_max[a];
        if d[a] == 0.0 {
            if o[a] < lo || o[a] > hi {
                return d;
            }
            continue;
        }
        let t0 = (lo - o[a]) / d[a];
        let t1 = (hi - o[a]) / d[a];
        near = fmax(near, fmin(t0, t1));
        far = fmin(far, fmax(t0, t1));
    }
    if a < 3 {
        loop_cut = true;
    }
    if !(near <= far && far >= 0.0) {
        return d;
    }
    let q = (o - sp.box_center) + d * far;
    if finite3(q) && any(q != vec3f(0.0)) {
        return q;
    }
    return d;
}

fn environment(o: vec3f, d: vec3f) -> vec3f {
    switch sp.env_kind {
        case 1u: {
            return sp.env_color;
        }
        case 2u: {
            return map_lookup(d);
        }
        case 3u: {
            return map_lookup(box_direction(o, d));
        }
        default: {
            return sky(d);
        }
    }
}
