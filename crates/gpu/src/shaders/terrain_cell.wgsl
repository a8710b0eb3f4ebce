// What the GPU terrain kernels share (terrain_maxmip.wgsl, terrain_boxes.wgsl):
// the bindings of group 0 (heights, pyramid maxima, rays, results,
// parameters) and the test of one cell's two triangles over one stretch of
// the ray, on the declared surface of raykit-terrain's heightfield.rs (two
// triangles per cell split along the (col, row)-(col+1, row+1) diagonal),
// in f32 made conservative: see terrain_maxmip.wgsl's header.
// Every loop is followed by a check that it ended because its condition
// failed (or by break or return); one that ended with its condition still
// true was cut short by the driver (Mesa's lavapipe ends every loop of an
// invocation once it has made 65,535 loop passes in all), and sets
// loop_cut. write_cast then sets the status word after the results (word
// 4 * count), and the host refuses them; on a GPU without such a limit the
// checks never fire.

struct Level {
    // Texels along x, along y, offset of the level's first texel, unused.
    size: vec4u,
}

struct TerrainParams {
    // Grid points per row of `heights`.
    width: u32,
    // Index of the top (1 x 1) level.
    top: u32,
    count: u32,
    row: u32,
    levels: array<Level, 24>,
}

@group(0) @binding(0) var<storage, read> heights: array<f32>;
@group(0) @binding(1) var<storage, read> maxes: array<f32>;
@group(0) @binding(2) var<storage, read> rays: array<f32>;
@group(0) @binding(3) var<storage, read_write> out: array<u32>;
@group(0) @binding(4) var<uniform> tp: TerrainParams;

// Band of the diagonal test, cell units.
const DIAG_EPS: f32 = 1e-5;
// Multiple of the unit roundoff in the rounding bounds.
const ROUND: f32 = 8.0 * F32_EPS;

var<private> loop_cut: bool;

fn grid_height(c: u32, r: u32) -> f32 {
    return heights[r * tp.width + c];
}

fn node_max(level: u32, i: u32, j: u32) -> f32 {
    let l = tp.levels[level].size;
    return maxes[l.z + j * l.x + i];
}

// The nearest hit of cell (c, r)'s two triangles for t in [a, b]: (t, 1,
// reach) for a hit strictly inside [a, b], (t, 0, reach) for one that only
// the rounding bound admits (the ray passes within that bound of a
// triangle's plane at an end of [a, b]; t is then clamped into [a, b]),
// (+inf, 0, 0) for none. `reach` is the bound on the rounding as a
// distance along the ray.
fn hit_cell(c: u32, r: u32, o: vec3f, d: vec3f, a: f32, b: f32) -> vec3f {
    let h00 = grid_height(c, r);
    let h10 = grid_height(c + 1u, r);
    let h01 = grid_height(c, r + 1u);
    let h11 = grid_height(c + 1u, r + 1u);
    // The ray's point where it enters the cell, in cell coordinates: the
    // plane equations are solved from there, so their terms stay small.
    let pa = o + a * d;
    let u0 = pa.x - f32(c);
    let v0 = pa.y - f32(r);
    let len = b - a;
    var best = vec3f(inf(), 0.0, 0.0);
    var k = 0u;
    for (; k < 2u; k++) {
        let upper = k == 0u;
        // z = h00 + bu u + bv v (heightfield.rs cell_plane).
        var bu = h11 - h01;
        var bv = h01 - h00;
        if upper {
            bu = h10 - h00;
            bv = h11 - h10;
        }
        // The ray's height above the plane is fa + denom (t - a).
        let denom = d.z - bu * d.x - bv * d.y;
        if denom == 0.0 || is_nan(denom) || abs(denom) == inf() {
            continue;
        }
        let fa = pa.z - h00 - bu * u0 - bv * v0;
        let fb = fa + denom * len;
        // Bound on the rounding of fa and fb (the ray's point, the plane's
        // terms, and the stretch's ends).
        let e = ROUND * (abs(pa.z) + abs(h00) + abs(bu * u0) + abs(bv * v0) + abs(denom) * (abs(a) + abs(b)));
        if min(fa, fb) > e || max(fa, fb) < -e {
            continue;
        }
        let dt = -fa / denom;
        let strict = dt >= 0.0 && dt <= len;
        let dtc = clamp(dt, 0.0, len);
        let u = u0 + dtc * d.x;
        let v = v0 + dtc * d.y;
        var inside = u <= v + DIAG_EPS;
        if upper {
            inside = v <= u + DIAG_EPS;
        }
        let t = a + dtc;
        if inside && (t < best.x || (t == best.x && strict)) {
            best = vec3f(t, select(0.0, 1.0, strict), e / abs(denom));
        }
    }
    if k < 2u {
        loop_cut = true;
    }
    return best;
}

// Parameter where the ray leaves the node of `size` cells at index `k`
// along one axis (the same line, hence the same value, as the parent's
// cut there), +inf when the ray runs parallel. A single cell is a node of
// size 1.
fn node_exit(o: f32, d: f32, k: u32, size: u32) -> f32 {
    if d > 0.0 {
        return (f32((k + 1u) * size) - o) / d;
    }
    if d < 0.0 {
        return (f32(k * size) - o) / d;
    }
    return inf();
}

// Ray `ray` of the rays buffer: origin, span (the last t inside the grid's
// box, negative when the ray misses it) and direction.
struct TerrainRay {
    o: vec3f,
    span: f32,
    d: vec3f,
}

fn load_terrain_ray(ray: u32) -> TerrainRay {
    let base = 8u * ray;
    return TerrainRay(
        vec3f(rays[base], rays[base + 1u], rays[base + 2u]),
        rays[base + 3u],
        vec3f(rays[base + 4u], rays[base + 5u], rays[base + 6u]),
    );
}

// Write a ray's result: the accepted hit or, when none followed it, the
// held-back candidate within the rounding bound; then the two step counts;
// and the status word when the ray's loops were cut short.
fn write_cast(ray: u32, hit_t: f32, hit_id: u32, cand_t: f32, cand_id: u32, steps_a: u32, steps_b: u32) {
    var t = hit_t;
    var id = hit_id;
    if id == MISS {
        t = cand_t;
        id = cand_id;
    }
    out[4u * ray] = bitcast<u32>(t);
    out[4u * ray + 1u] = id;
    out[4u * ray + 2u] = steps_a;
    out[4u * ray + 3u] = steps_b;
    if loop_cut {
        out[4u * tp.count] = 1u;
    }
}
