// Point, spot and directional lights (raykit_core::Light::toward) and
// Blinn-Phong direct lighting with shadow rays (crates/render/src/lighting.rs),
// as the stack kd-tree GPU tracer shades its hits and the Purcell-style stream tracer's lighting kernel does.
// Light record (16 words): kind (0 point, 1 spot, 2 directional),
// position, direction, intensity or irradiance, cos_inner, cos_outer,
// max(cos_inner - cos_outer, 1e-6).

struct LightSample {
    to_light: vec3f,
    distance: f32,
    irradiance: vec3f,
}

fn light_toward(i: u32, p: vec3f) -> LightSample {
    let b = sp.lights_offset + 16u * i;
    let kind = tables[b];
    let dir = tv3(b + 4u);
    let e = tv3(b + 7u);
    if kind == 2u {
        return LightSample(-dir, inf(), e);
    }
    let d = tv3(b + 1u) - p;
    let dist = sqrt(dot3(d, d));
    let to_light = d / fmax(dist, F32_MIN_POSITIVE);
    var intensity = e;
    if kind == 1u {
        let cos = dot3(-to_light, dir);
        var cone = 1.0;
        if !(cos >= tf(b + 10u)) {
            let t = clamp((cos - tf(b + 11u)) / tf(b + 12u), 0.0, 1.0);
            cone = t * t;
        }
        intensity = e * cone;
    }
    return LightSample(to_light, dist, intensity / fmax(dist * dist, F32_MIN_POSITIVE));
}

// Rust's powf for a base in [0, 1].
fn powf(x: f32, y: f32) -> f32 {
    if y == 0.0 {
        return 1.0;
    }
    if x == 0.0 {
        return 0.0;
    }
    return pow(x, y);
}

// Blinn-Phong radiance towards the unit direction view; one shadow ray per
// light in front of the surface.
fn direct(s: Surface, view: vec3f, kd: vec3f, ks: vec3f, shininess: f32) -> vec3f {
    var out = kd * sp.ambient;
    var i = 0u;
    for (; i < sp.num_lights; i++) {
        let ls = light_toward(i, s.point);
        let l = ls.to_light;
        let ndl = dot3(s.ns, l);
        if ndl <= 0.0 || dot3(s.ng, l) <= 0.0 || all(ls.irradiance == vec3f(0.0)) {
            continue;
        }
        if sp.shadows != 0u {
            atomicAdd(&counters[0], 1u);
            // Starting `bias` along the ray too: at a concave edge the
            // offset origin still lies in the other face's plane.
            let origin = s.point + s.ng * sp.bias;
            if scene_occluded(make_ray(origin, l, sp.bias, ls.distance * sp.shadow_scale)) {
                continue;
            }
        }
        let h = normalize_or(l + view, vec3f(0.0));
        let spec = powf(fmax(dot3(s.ns, h), 0.0), shininess);
        out += ls.irradiance * (kd * ndl + ks * spec);
    }
    if i < sp.num_lights {
        loop_cut = true;
    }
    return out;
}
