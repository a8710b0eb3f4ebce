// The one Whitted shading kernel (crates/render/src/whitted/tracer.rs,
// Tracer::scatter), shared by one kernel per ray path and the Purcell-style stream tracer's
// shading stage: a hit's local radiance (emission + (1-t)(1-r) direct) and
// up to two secondary rays with their weights (reflection: (1-t) r
// Schlick(ks) + t F; refraction: t (1-F) kd).
// Material record (16 words): diffuse, shininess, specular, reflectivity,
// emission, transmission, ior (t and r clamped to [0, 1] on the host),
// the base-colour texture's first texel, width and height (width 0: none).

struct Scatter {
    local: vec3f,
    has_reflect: bool,
    reflect_ray: RayIn,
    reflect_weight: vec3f,
    has_refract: bool,
    refract_ray: RayIn,
    refract_weight: vec3f,
}

fn scatter(r: RayIn, h: Hit, depth: u32) -> Scatter {
    let s = surface_at(r, h);
    let mb = 16u * s.material;
    let kd = tv3(mb) * base_colour(mb, s.uv);
    let shininess = tf(mb + 3u);
    let ks = tv3(mb + 4u);
    let refl = tf(mb + 7u);
    let t = tf(mb + 11u);
    let ior = tf(mb + 12u);
    let d = normalize_or(r.d, vec3f(0.0));
    var sc: Scatter;
    sc.local = tv3(mb + 8u);
    sc.has_reflect = false;
    sc.has_refract = false;
    let opaque_diffuse = (1.0 - t) * (1.0 - refl);
    if opaque_diffuse > 0.0 {
        sc.local += opaque_diffuse * direct(s, -d, kd, ks, shininess);
    }
    if depth >= sp.max_depth || (t == 0.0 && refl == 0.0) {
        return sc;
    }
    var eta = ior;
    if s.front {
        eta = 1.0 / ior;
    }
    let ng = s.ng;
    var n = s.ns;
    let bent = refract3(d, n, eta);
    if dot3(reflect3(d, n), ng) <= 0.0 || (t > 0.0 && bent.ok && dot3(bent.dir, ng) >= 0.0) {
        n = ng;
    }
    let cos_i = clamp(-dot3(d, n), 0.0, 1.0);
    var fresnel = 0.0;
    if t > 0.0 {
        fresnel = fresnel_dielectric(cos_i, eta);
    }
    let rw = (1.0 - t) * refl * fresnel_schlick(cos_i, ks) + vec3f(t * fresnel);
    if fmax(rw.x, fmax(rw.y, rw.z)) > 0.0 {
        sc.has_reflect = true;
        sc.reflect_ray = make_ray(s.point + ng * sp.bias, reflect3(d, n), 0.0, inf());
        sc.reflect_weight = rw;
    }
    if t > 0.0 && fresnel < 1.0 {
        let tr = refract3(d, n, eta);
        if tr.ok {
            sc.has_refract = true;
            sc.refract_ray = make_ray(s.point - ng * sp.bias, tr.dir, 0.0, inf());
            sc.refract_weight = t * (1.0 - fresnel) * kd;
        }
    }
    return sc;
}
