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

const STACK: u32 = 48u;

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
