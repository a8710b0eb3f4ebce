// The stack kd-tree GPU tracer's Plücker test (section 5.1) with the conservative side
// tolerance of crates/core/src/tri/plucker.rs, on its 28-word record:
// (e_i, M_i) for the three edges, n, a, scale_v, scale_u, tol_m, cap.
// The sign test is branch-free; shadow rays skip the barycentrics.

// Bytes of one record, for the traversal counts.
const TRI_BYTES: u32 = 112u;

const PLUCKER_K_SIDE: f32 = 16.0;

struct TriRay {
    d: vec3f,
    m: vec3f,
    dsum: f32,
    mtol: f32,
}

// a * b as an unevaluated sum hi + lo (Dekker's product with Veltkamp's
// split), so the ray's moment is rounded once, as the CPU's f64 moment is.
fn two_prod(a: f32, b: f32) -> vec2f {
    let p = a * b;
    let ca = 4097.0 * a;
    let ah = ca - (ca - a);
    let al = a - ah;
    let cb = 4097.0 * b;
    let bh = cb - (cb - b);
    let bl = b - bh;
    let e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    return vec2f(p, e);
}

fn diff_prod(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let p = two_prod(a, b);
    let q = two_prod(c, d);
    return (p.x - q.x) + (p.y - q.y);
}

fn tri_prepare(r: RayIn) -> TriRay {
    let o = r.o;
    let d = r.d;
    let m = vec3f(diff_prod(o.y, d.z, o.z, d.y), diff_prod(o.z, d.x, o.x, d.z), diff_prod(o.x, d.y, o.y, d.x));
    let prod = vec3f(
        abs(o.y * d.z) + abs(o.z * d.y),
        abs(o.z * d.x) + abs(o.x * d.z),
        abs(o.x * d.y) + abs(o.y * d.x),
    );
    // The CPU adds prod * 2^-29 for its f64 moment; 2^-20 here covers the
    // f32 product pair's rounding.
    let mb = abs(m) + prod * 9.5367432e-7;
    let ad = abs(d);
    return TriRay(d, m, (ad.x + ad.y) + ad.z, 2.0 * PLUCKER_K_SIDE * U * ((mb.x + mb.y) + mb.z));
}

fn plucker_side(rd: TriRay, e: vec3f, m: vec3f) -> f32 {
    return ((rd.d.x * m.x + rd.d.y * m.y) + rd.d.z * m.z) + ((e.x * rd.m.x + e.y * rd.m.y) + e.z * rd.m.z);
}

fn plucker_test(i: u32, r: RayIn, rd: TriRay, tfar: f32, full: bool) -> TriHit {
    let b = i * 28u;
    let none = TriHit(false, 0.0, 0.0, 0.0);
    let s0 = plucker_side(rd, tw3(b), tw3(b + 3u));
    let s1 = plucker_side(rd, tw3(b + 6u), tw3(b + 9u));
    let s2 = plucker_side(rd, tw3(b + 12u), tw3(b + 15u));
    let n = tw3(b + 18u);
    let den = (n.x * rd.d.x + n.y * rd.d.y) + n.z * rd.d.z;
    let tol_m = tw(b + 26u);
    let cap = tw(b + 27u);
    let eps = fmin(rd.dsum * tol_m + rd.mtol, cap * abs(den));
    let all_ge = (s0 >= -eps) & (s1 >= -eps) & (s2 >= -eps);
    let all_le = (s0 <= eps) & (s1 <= eps) & (s2 <= eps);
    if !(all_ge | all_le) {
        return none;
    }
    let nmax = fmax(fmax(abs(n.x), abs(n.y)), abs(n.z));
    if !(abs(den) > 8.0 * U * nmax * rd.dsum) {
        return none;
    }
    let inv = 1.0 / den;
    let w = tw3(b + 21u) - r.o;
    let t = ((n.x * w.x + n.y * w.y) + n.z * w.z) * inv;
    if !((t >= r.tnear) & (t <= tfar) & (t < inf())) {
        return none;
    }
    if !full {
        return TriHit(true, t, 0.0, 0.0);
    }
    let scale_v = tw(b + 24u);
    let scale_u = tw(b + 25u);
    return TriHit(true, t, s2 * scale_u * inv, s0 * scale_v * inv);
}

fn tri_intersect(i: u32, r: RayIn, rd: TriRay, tfar: f32) -> TriHit {
    return plucker_test(i, r, rd, tfar, true);
}

fn tri_occluded(i: u32, r: RayIn, rd: TriRay, tfar: f32) -> bool {
    return plucker_test(i, r, rd, tfar, false).hit;
}
