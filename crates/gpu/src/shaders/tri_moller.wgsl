// Möller–Trumbore (1997) with the conservative tolerance of
// crates/core/src/tri/moller.rs, on its 11-word record:
// v0, e1, e2, max|e1_i|, max|e2_i|.

// Bytes of one record, for the traversal counts.
const TRI_BYTES: u32 = 44u;

const MOLLER_K_BARY: f32 = 64.0;

struct TriRay {
    scale: f32,
}

fn tri_prepare(r: RayIn) -> TriRay {
    return TriRay(MOLLER_K_BARY * U * max_abs3(r.d));
}

fn tri_intersect(i: u32, r: RayIn, rd: TriRay, tfar: f32) -> TriHit {
    let b = i * 11u;
    let v0 = tw3(b);
    let e1 = tw3(b + 3u);
    let e2 = tw3(b + 6u);
    let e1_max = tw(b + 9u);
    let e2_max = tw(b + 10u);
    let none = TriHit(false, 0.0, 0.0, 0.0);
    let d = r.d;
    let p = cross3(d, e2);
    let det = dot3(e1, p);
    // Parallel when |det| is within its rounding-error bound.
    if !(abs(det) > 0.75 * rd.scale * e1_max * e2_max) {
        let ad = abs(d);
        let a2 = abs(e2);
        let pc = vec3f(ad.y * a2.z + ad.z * a2.y, ad.z * a2.x + ad.x * a2.z, ad.x * a2.y + ad.y * a2.x);
        if !(abs(det) > 8.0 * U * dot3(abs(e1), pc)) {
            return none;
        }
    }
    let inv_det = 1.0 / det;
    let s = r.o - v0;
    let u = dot3(s, p) * inv_det;
    let q = cross3(s, e1);
    let v = dot3(d, q) * inv_det;
    let c = rd.scale * abs(inv_det);
    let sm = max_abs3(s);
    let eu = fmin(c * e2_max * (sm + e1_max), MAX_EDGE_TOLERANCE);
    let ev = fmin(c * e1_max * (sm + e2_max), MAX_EDGE_TOLERANCE);
    let t = dot3(e2, q) * inv_det;
    let inside = (u >= -eu) & (v >= -ev) & (u + v <= 1.0 + (eu + ev));
    let in_range = (t >= r.tnear) & (t <= tfar) & (t < inf());
    if inside & in_range {
        return TriHit(true, t, u, v);
    }
    return none;
}

fn tri_occluded(i: u32, r: RayIn, rd: TriRay, tfar: f32) -> bool {
    return tri_intersect(i, r, rd, tfar).hit;
}
