// Per-ray maximum-mipmap traversal of a height field (Tevs, Ihrke and
// Seidel 2008; per-ray top-down), one thread per
// pixel, the same walk as raykit-terrain's maxmip.rs: from the root, skip a
// node when the ray stays above its maximum over the node's stretch of the
// ray, visit the children in the order the ray crosses them, and test the
// cells' two triangles at level 0. The recursion needs no stack here: the
// node after a finished one is the child, under their lowest common
// ancestor, of the neighbour the ray enters, and every stretch ends where
// the ray leaves its node (measured on the same grid lines as the parents'
// cuts, so the values agree); (level, i, j, start) is the whole state.
// (A first version kept maxmip.rs's stretches on a per-thread stack: the
// same answers, 3x slower on lavapipe, whose private arrays are costly.)
//
// The surface is the declared one (heightfield.rs): two triangles per cell
// split along the (col, row)-(col+1, row+1) diagonal. Arithmetic is f32, so
// the tests are made conservative where the CPU's f64 ones are exact:
// - a node is skipped only when the ray clears its maximum by more than a
//   bound on the rounding of the ray's heights;
// - the stretches [a, b] of the ray given to the cells partition the ray's
//   span exactly (each starts where the previous one ended); a cell's triangle is hit when the
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
// (col | row << 16, or MISS), nodes visited, cells tested; then one status
// word for all rays (see terrain_cell.wgsl).

@compute @workgroup_size(64)
fn terrain_maxmip(@builtin(global_invocation_id) gid: vec3u) {
    let ray = gid.x + gid.y * tp.row;
    if ray >= tp.count {
        return;
    }
    let tr = load_terrain_ray(ray);
    let o = tr.o;
    let span = tr.span;
    let d = tr.d;
    var hit_t = inf();
    var hit_cell_id = MISS;
    var nodes = 0u;
    var cells = 0u;
    // A hit that only the rounding bound admits waits until the cells
    // within its reach (the bound as a distance along the ray) have had
    // their chance: a strict hit there wins.
    var cand_t = inf();
    var cand_reach = inf();
    var cand_cell = MISS;
    // The walk without a stack: the node visited next is always the
    // sibling, under the lowest common ancestor, of the node the ray
    // enters, and a node's stretch of the ray ends where it leaves the node,
    // so (level, i, j, ta) is the whole state.
    var level = tp.top;
    var i = 0u;
    var j = 0u;
    var ta = 0.0;
    var live = span >= 0.0;
    // The walk ends only by break; `ended` tells a break from a cut.
    var ended = false;
    loop {
        if !live || ta > cand_reach {
            ended = true;
            break;
        }
        let size = 1u << level;
        let tx = node_exit(o.x, d.x, i, size);
        let ty = node_exit(o.y, d.y, j, size);
        let tb = max(min(min(tx, ty), span), ta);
        nodes += 1u;
        let zmax = node_max(level, i, j);
        let za = o.z + ta * d.z;
        let zb = o.z + tb * d.z;
        let slack_z = ROUND * (abs(o.z) + abs(tb * d.z) + abs(zmax));
        var descend = min(za, zb) <= zmax + slack_z;
        if descend && level == 0u {
            descend = false;
            cells += 1u;
            let h = hit_cell(i, j, o, d, ta, tb);
            if h.y > 0.5 && h.x <= cand_reach {
                hit_t = h.x;
                hit_cell_id = i | (j << 16u);
                ended = true;
                break;
            }
            if h.x < cand_t {
                cand_t = h.x;
                cand_reach = h.x + h.z;
                cand_cell = i | (j << 16u);
            }
        }
        if descend {
            // The child holding the first stretch (up to the nearest split
            // line inside [ta, tb]), found by its midpoint as maxmip.rs does.
            let half = size >> 1u;
            let xm = f32((2u * i + 1u) * half);
            let ym = f32((2u * j + 1u) * half);
            var c1 = tb;
            if d.x != 0.0 {
                let t = (xm - o.x) / d.x;
                if t > ta && t < c1 {
                    c1 = t;
                }
            }
            if d.y != 0.0 {
                let t = (ym - o.y) / d.y;
                if t > ta && t < c1 {
                    c1 = t;
                }
            }
            let p = o + (0.5 * (ta + c1)) * d;
            let ci = 2u * i + select(0u, 1u, p.x >= xm);
            let cj = 2u * j + select(0u, 1u, p.y >= ym);
            let child = tp.levels[level - 1u].size;
            level -= 1u;
            i = ci;
            j = cj;
            if ci < child.x && cj < child.y {
                continue;
            }
            // Outside the grid (the pyramid's edge): the ray is leaving.
            ended = true;
            break;
        }
        // Done with this node: step to the neighbour the ray enters.
        if tb >= span {
            ended = true;
            break;
        }
        var ni = i32(i);
        var nj = i32(j);
        if tx <= ty {
            ni += select(-1, 1, d.x > 0.0);
        }
        if ty <= tx {
            nj += select(-1, 1, d.y > 0.0);
        }
        let lv = tp.levels[level].size;
        if ni < 0 || nj < 0 || ni >= i32(lv.x) || nj >= i32(lv.y) {
            ended = true;
            break;
        }
        var ui = u32(ni);
        var uj = u32(nj);
        // Up to the lowest common ancestor; its child holding the neighbour
        // comes next.
        while (i >> 1u) != (ui >> 1u) || (j >> 1u) != (uj >> 1u) {
            i = i >> 1u;
            j = j >> 1u;
            ui = ui >> 1u;
            uj = uj >> 1u;
            level += 1u;
        }
        if (i >> 1u) != (ui >> 1u) || (j >> 1u) != (uj >> 1u) {
            loop_cut = true;
        }
        i = ui;
        j = uj;
        ta = tb;
    }
    if !ended {
        loop_cut = true;
    }
    write_cast(ray, hit_t, hit_cell_id, cand_t, cand_cell, nodes, cells);
}
