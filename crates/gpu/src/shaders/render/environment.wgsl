// What rays leaving the scene see (crates/render/src/env, crates/render/src/sky.rs):
// env_kind 0 the sky gradient, 1 a constant radiance.

const SKY_ZENITH: vec3f = vec3f(0.22, 0.40, 0.80);
const SKY_HORIZON: vec3f = vec3f(0.72, 0.80, 0.90);
const SKY_NADIR: vec3f = vec3f(0.30, 0.30, 0.32);

fn lerp3(a: vec3f, b: vec3f, s: f32) -> vec3f {
    return a * (1.0 - s) + b * s;
}

fn environment(d: vec3f) -> vec3f {
    if sp.env_kind == 1u {
        return sp.env_color;
    }
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
