// Per-ray maximum-mipmap traversal of a height field (Tevs, Ihrke and
// Seidel 2008; paper 004's "per-ray top-down" method C), one thread per
// pixel, the same walk as raykit-terrain's maxmip.rs: from the root, skip a
// node when the ray stays above its maximum over the node's stretch of the
// ray, visit the children in the order the ray crosses them (a stack stands
// in for the recursion), and test the cells' two triangles at level 0.
//
// The surface is the declared one (heightfield.rs): two triangles per cell
// split along the (col, row)-(col+1, row+1) diagonal. Arithmetic is f32, so
// the tests are made conservative where the CPU's f64 ones are exact:
// - a node is skipped only when the ray clears its maximum by more than a
//   bound on the rounding of the ray's heights;
// - the stretches [a, b] of the ray given to the cells partition the ray's
//   span exactly (a child's cut points lie strictly inside its parent's
//   stretch and neighbours share them); a cell's triangle is hit when the
//   ray's height above its plane changes sign within [a, b]. When it only
//   comes within a bound on the rounding of that height at an end of
//   [a, b], the hit is kept as a candidate and the following cells within
//   that bound's reach along the ray are tried first: a hit on a cell
//   border is found by one side or the other, never lost between them, and
//   a strict hit in the next cell wins;
// - the diagonal test between the two triangles has a small band (either
//   triangle gives the same point on the diagonal).
//
// Rays (8 floats each, grid units, see terrain/rays.rs): origin at the
// ray's entry into the grid's bounding box, span (the last t inside it, or
// negative when the ray misses the box), direction, unused. Output per ray
// (4 words): t from the origin (f32 bits, +inf on a miss), cell
// (col | row << 16, or MISS), nodes visited, cells tested.

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

const STACK: u32 = 48u;
// Band of the diagonal test, cell units.
const DIAG_EPS: f32 = 1e-5;
// Multiple of the unit roundoff in the rounding bounds.
const ROUND: f32 = 8.0 * F32_EPS;

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
    for (var k = 0u; k < 2u; k++) {
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
    return best;
}

@compute @workgroup_size(64)
fn terrain_maxmip(@builtin(global_invocation_id) gid: vec3u) {
    let ray = gid.x + gid.y * tp.row;
    if ray >= tp.count {
        return;
    }
    let base = 8u * ray;
    let o = vec3f(rays[base], rays[base + 1u], rays[base + 2u]);
    let span = rays[base + 3u];
    let d = vec3f(rays[base + 4u], rays[base + 5u], rays[base + 6u]);
    var hit_t = inf();
    var hit_cell_id = MISS;
    var nodes = 0u;
    var cells = 0u;
    var st: array<vec2f, STACK>;
    var sn: array<vec2u, STACK>;
    var sp = 0u;
    // A hit that only the rounding bound admits waits until the cells
    // within its reach (the bound as a distance along the ray) have had
    // their chance: a strict hit there wins.
    var cand_t = inf();
    var cand_reach = inf();
    var cand_cell = MISS;
    if span >= 0.0 {
        st[0] = vec2f(0.0, span);
        sn[0] = vec2u(0u, tp.top);
        sp = 1u;
    }
    loop {
        if sp == 0u {
            break;
        }
        sp -= 1u;
        let ta = st[sp].x;
        let tb = st[sp].y;
        let i = sn[sp].x & 0xffffu;
        let j = sn[sp].x >> 16u;
        let level = sn[sp].y;
        if ta > cand_reach {
            break;
        }
        nodes += 1u;
        let zmax = node_max(level, i, j);
        let za = o.z + ta * d.z;
        let zb = o.z + tb * d.z;
        let slack_z = ROUND * (abs(o.z) + abs(tb * d.z) + abs(zmax));
        if min(za, zb) > zmax + slack_z {
            continue;
        }
        if level == 0u {
            cells += 1u;
            let h = hit_cell(i, j, o, d, ta, tb);
            if h.y > 0.5 && h.x <= cand_reach {
                hit_t = h.x;
                hit_cell_id = i | (j << 16u);
                break;
            }
            if h.x < cand_t {
                cand_t = h.x;
                cand_reach = h.x + h.z;
                cand_cell = i | (j << 16u);
            }
            continue;
        }
        // Split lines between the children, in cell units.
        let half = 1u << (level - 1u);
        let xm = f32((2u * i + 1u) * half);
        let ym = f32((2u * j + 1u) * half);
        var cuts = array<f32, 4>(ta, tb, tb, tb);
        var n = 1u;
        if d.x != 0.0 {
            let t = (xm - o.x) / d.x;
            if t > ta && t < tb {
                cuts[n] = t;
                n += 1u;
            }
        }
        if d.y != 0.0 {
            let t = (ym - o.y) / d.y;
            if t > ta && t < tb {
                cuts[n] = t;
                n += 1u;
            }
        }
        cuts[n] = tb;
        if n == 3u && cuts[2] < cuts[1] {
            let s = cuts[1];
            cuts[1] = cuts[2];
            cuts[2] = s;
        }
        let child = tp.levels[level - 1u].size;
        // Push the stretches last-first so the nearest is popped first.
        for (var q = 0u; q < n; q++) {
            let k = n - 1u - q;
            let a = cuts[k];
            let b = cuts[k + 1u];
            let p = o + (0.5 * (a + b)) * d;
            let ci = 2u * i + select(0u, 1u, p.x >= xm);
            let cj = 2u * j + select(0u, 1u, p.y >= ym);
            if ci >= child.x || cj >= child.y || sp >= STACK {
                continue;
            }
            st[sp] = vec2f(a, b);
            sn[sp] = vec2u(ci | (cj << 16u), level - 1u);
            sp += 1u;
        }
    }
    if hit_cell_id == MISS {
        hit_t = cand_t;
        hit_cell_id = cand_cell;
    }
    out[4u * ray] = bitcast<u32>(hit_t);
    out[4u * ray + 1u] = hit_cell_id;
    out[4u * ray + 2u] = nodes;
    out[4u * ray + 3u] = cells;
}
