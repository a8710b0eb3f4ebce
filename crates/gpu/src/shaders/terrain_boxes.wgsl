// per-frame quadtree boxes on the GPU: the boxes come from the CPU's one
// quadtree traversal per frame (raykit-terrain's boxes.rs select_boxes:
// view-distance LOD and frustum culling), listed per image row; each thread
// takes one pixel, finds the nearest entry of its ray into the boxes
// covering the pixel (the stand-in for the paper's rasterization with a
// depth test), and marches the cells from there (a 2D DDA whose stretches
// partition the ray, each cell tested by terrain_cell.wgsl's hit_cell, with
// the same candidate rule as terrain_maxmip.wgsl). Output as
// terrain_maxmip.wgsl's, with the status word after it.
//
// Group 1: boxes (8 floats each: lo x, y, z, first column of its pixel
// rectangle, hi x, y, z, end column; grid units), the rows' lists (offsets of image rows 0..=h into the index list, then the list),
// and the chunk's first pixel and the image width.

struct BoxParams {
    first: u32,
    width: u32,
    // Cells along x and y.
    cw: u32,
    ch: u32,
}

@group(1) @binding(0) var<storage, read> boxes: array<f32>;
@group(1) @binding(1) var<storage, read> rows: array<u32>;
@group(1) @binding(2) var<uniform> bp: BoxParams;

// The entry of the ray into box k within [0, tmax], or +inf; the box is
// widened by a rounding bound so that a pixel never starts past the surface.
fn box_entry(k: u32, o: vec3f, inv: vec3f, tmax: f32) -> f32 {
    let b = 8u * k;
    let lo = vec3f(boxes[b], boxes[b + 1u], boxes[b + 2u]);
    let hi = vec3f(boxes[b + 4u], boxes[b + 5u], boxes[b + 6u]);
    let pad = ROUND * (abs(lo) + abs(hi) + abs(o)) + vec3f(1e-6);
    let ta = (lo - pad - o) * inv;
    let tb = (hi + pad - o) * inv;
    let t0 = fmax(fmax(fmax(fmin(ta.x, tb.x), fmin(ta.y, tb.y)), fmin(ta.z, tb.z)), 0.0);
    let t1 = fmin(fmin(fmin(fmax(ta.x, tb.x), fmax(ta.y, tb.y)), fmax(ta.z, tb.z)), tmax);
    if t0 <= t1 * ROBUST_EXIT {
        return t0;
    }
    return inf();
}

@compute @workgroup_size(64)
fn terrain_boxes(@builtin(global_invocation_id) gid: vec3u) {
    let ray = gid.x + gid.y * tp.row;
    if ray >= tp.count {
        return;
    }
    let tr = load_terrain_ray(ray);
    let o = tr.o;
    let span = tr.span;
    let d = tr.d;
    let pixel = bp.first + ray;
    let px = pixel % bp.width;
    let py = pixel / bp.width;
    var visits = 0u;
    var start = inf();
    if span >= 0.0 {
        let inv = vec3f(1.0) / d;
        var k = rows[py];
        for (; k < rows[py + 1u]; k++) {
            let b = rows[k];
            let fx = f32(px);
            if fx < boxes[8u * b + 3u] || fx >= boxes[8u * b + 7u] {
                continue;
            }
            visits += 1u;
            start = min(start, box_entry(b, o, inv, min(start, span)));
        }
        if k < rows[py + 1u] {
            loop_cut = true;
        }
    }
    var hit_t = inf();
    var hit_id = MISS;
    var cand_t = inf();
    var cand_id = MISS;
    var cells = 0u;
    if start < inf() {
        // Start a hair before the box entry, so a hit on the box's face is
        // not lost to rounding.
        var ta = max(start - ROUND * (start + span), 0.0);
        let p = o + ta * d;
        var c = u32(clamp(floor(p.x), 0.0, f32(bp.cw - 1u)));
        var r = u32(clamp(floor(p.y), 0.0, f32(bp.ch - 1u)));
        var cand_reach = inf();
        // The march ends only by break; `ended` tells a break from a cut.
        var ended = false;
        loop {
            if ta > cand_reach {
                ended = true;
                break;
            }
            cells += 1u;
            let tx = node_exit(o.x, d.x, c, 1u);
            let ty = node_exit(o.y, d.y, r, 1u);
            let tb = max(min(min(tx, ty), span), ta);
            let h = hit_cell(c, r, o, d, ta, tb);
            if h.y > 0.5 && h.x <= cand_reach {
                hit_t = h.x;
                hit_id = c | (r << 16u);
                ended = true;
                break;
            }
            if h.x < cand_t {
                cand_t = h.x;
                cand_reach = h.x + h.z;
                cand_id = c | (r << 16u);
            }
            if min(tx, ty) >= span {
                ended = true;
                break;
            }
            if tx <= ty {
                if d.x > 0.0 {
                    c += 1u;
                    if c >= bp.cw {
                        ended = true;
                        break;
                    }
                } else {
                    if c == 0u {
                        ended = true;
                        break;
                    }
                    c -= 1u;
                }
            } else if d.y > 0.0 {
                r += 1u;
                if r >= bp.ch {
                    ended = true;
                    break;
                }
            } else {
                if r == 0u {
                    ended = true;
                    break;
                }
                r -= 1u;
            }
            ta = tb;
        }
        if !ended {
            loop_cut = true;
        }
    }
    write_cast(ray, hit_t, hit_id, cand_t, cand_id, visits, cells);
}
