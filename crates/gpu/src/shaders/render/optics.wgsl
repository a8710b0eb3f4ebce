// Perfect specular optics (crates/render/src/whitted/optics.rs): mirror
// reflection, Snell refraction with total internal reflection, the exact
// dielectric Fresnel reflectance and Schlick's conductor approximation.

fn reflect3(d: vec3f, n: vec3f) -> vec3f {
    return d - 2.0 * dot3(d, n) * n;
}

struct Refracted {
    ok: bool,
    dir: vec3f,
}

fn refract3(d: vec3f, n: vec3f, eta: f32) -> Refracted {
    let cos_i = clamp(-dot3(d, n), 0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t > 1.0 {
        return Refracted(false, vec3f(0.0));
    }
    let cos_t = sqrt(1.0 - sin2_t);
    return Refracted(true, normalize3(eta * d + (eta * cos_i - cos_t) * n));
}

fn fresnel_dielectric(cos_in: f32, eta: f32) -> f32 {
    let cos_i = clamp(cos_in, 0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

fn fresnel_schlick(cos_i: f32, f0: vec3f) -> vec3f {
    let x = 1.0 - clamp(cos_i, 0.0, 1.0);
    let x2 = x * x;
    let k = x * (x2 * x2);
    return f0 + (vec3f(1.0) - f0) * k;
}
