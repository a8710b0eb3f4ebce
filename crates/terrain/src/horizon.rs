//! Point-light shadow masks by a front-to-back horizon sweep (De Floriani
//! and Magillo 1994): exact for the declared surface, and a few operations
//! per grid point instead of one segment walk each.
//!
//! **Projection.** The grid around the light L is cut into eight octants.
//! In each, `a` is the distance from L along the octant's main grid axis and
//! `b` the distance across it, `0 ≤ b ≤ a`. Seen from L, a point projects
//! to `(u, v) = (b / a, (z − z_L) / a)`: the central projection onto the
//! plane `a = 1`, which keeps straight lines straight. The segment from a
//! grid point P to L projects to the single direction `u_P`, and P is lit
//! exactly when no part of the surface between L and P projects above
//! `v_P` there.
//!
//! **Sweep.** Columns (lines of constant `a`) are swept outward. The
//! horizon, the upper envelope of the projection of everything swept so
//! far, is a piecewise linear function of `u` kept as a list of vertices.
//! Each column's points are compared with it; then the strip of triangles
//! between the previous column and this one is merged in. A strip's
//! projection is bounded above by its projected edges (the two columns, the
//! edges along `a` and the cell diagonals), so the merge is the upper
//! envelope of a few segments per cell and the old horizon, done in one
//! pass over both.
//!
//! **What is decided here.** The ray from a point back to the previous
//! column stays inside one triangle, or crosses one diagonal when the
//! diagonals lean towards the octant's axis, so a point's answer is the
//! horizon of the columns before it, that diagonal, and a bound for the
//! part nearer than the second column. Points on an octant's axis or
//! diagonal, whose segments run along grid edges, are read off the horizon
//! at `u = 0` or `u = 1`. A point is decided only when its `v` clears all
//! of these by a margin that covers rounding and the triangle test's
//! tolerance; the rest (points in the first two columns, within the
//! margin, or off an octant's border by less than 10⁻⁹ of `a` but more than
//! rounding) are left to the caller's exact segment test. The part nearer
//! than the second column is bounded by its highest corner where that is
//! below the light, and always by its steepest rise from the light's
//! ground point, which serves a light on the ground. Lights off the grid,
//! or below the ground, are not swept at all.
//!
//! **Blocks.** Far from the light, most of a strip lies wholly below the
//! old horizon (the horizon is copied and the points are in shadow), or
//! its far column wholly above it (the strip alone is the new horizon).
//! Blocks of rows are tested for both before rows are merged one by one.
//!
//! **Memory order.** Half the octants run their columns across the
//! row-major grid, one cache line and one page per point. Each octant reads
//! its columns sixteen at a time, in the grid's storage order, into a small
//! buffer, and keeps their answers there until the sixteen are swept
//! (`ColumnBlock`).

use crate::ground::place_light;
use crate::heightfield::HeightField;

/// A mask cell the sweep left to the exact segment test.
pub const UNDECIDED: u8 = 2;

/// A horizon vertex: direction `u = b / a`, height `v = (z − z_L) / a`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Vertex {
    u: f64,
    v: f64,
}

/// One octant in grid-index terms: grid point (m, n) is column `m` (at
/// `a = a0 + m`) and row `n` (at `b = n − beta`) of the octant, stored at
/// `base + m·sm + n·sn` in the height array.
#[derive(Clone, Copy, Debug)]
struct Octant {
    base: isize,
    sm: isize,
    sn: isize,
    columns: usize,
    rows: usize,
    a0: f64,
    beta: f64,
    /// Whether each cell's diagonal runs from (m−1, n) to (m, n+1), away
    /// from the axis; otherwise from (m−1, n+1) to (m, n).
    outward: bool,
}

/// The eight octants around a light at grid position (`lx`, `ly`) of a
/// `width` × `height` grid.
fn octants(lx: f64, ly: f64, width: usize, height: usize) -> Vec<Octant> {
    let (w, h) = (width as isize, height as isize);
    let mut out = Vec::with_capacity(8);
    // Major axis along columns (x) or rows (y); s: direction along it,
    // t: direction across it.
    for major_x in [true, false] {
        let (lm, ln, len_m, len_n) = if major_x {
            (lx, ly, w, h)
        } else {
            (ly, lx, h, w)
        };
        let (stride_m, stride_n) = if major_x { (1, w) } else { (w, 1) };
        for s in [1isize, -1] {
            let c0 = if s > 0 {
                lm.floor() as isize + 1
            } else {
                lm.ceil() as isize - 1
            };
            let columns = if s > 0 { len_m - c0 } else { c0 + 1 };
            let a0 = s as f64 * (c0 as f64 - lm);
            for t in [1isize, -1] {
                let j0 = if t > 0 {
                    ln.floor() as isize
                } else {
                    ln.ceil() as isize
                };
                let rows = if t > 0 { len_n - j0 } else { j0 + 1 };
                if columns < 3 || rows < 2 {
                    continue;
                }
                out.push(Octant {
                    base: c0 * stride_m + j0 * stride_n,
                    sm: s * stride_m,
                    sn: t * stride_n,
                    columns: columns as usize,
                    rows: rows as usize,
                    a0,
                    beta: t as f64 * (ln - j0 as f64),
                    outward: s * t > 0,
                });
            }
        }
    }
    out
}

/// The light and the tolerances every octant uses.
struct Setup<'a> {
    heights: &'a [f32],
    zl: f64,
    /// The surface's height under the light.
    ground: f64,
    lift: f64,
    /// Margins within which an answer is left to the exact test.
    tol: Margins,
    /// The largest height step between grid neighbours ([`max_step`]).
    step: f64,
}

/// How far, in `v`, the surface must stay below a point's segment for the
/// sweep to call the point lit, or rise above it to call it shadowed.
///
/// Shadowed needs only room for rounding: a surface point above the segment
/// makes the segment cross the surface between there and the light. Lit
/// needs room for the triangle test's tolerance too: it accepts crossings up
/// to 10⁻⁹ cells outside a triangle along each axis, where the triangle's
/// plane may stand above the neighbouring triangle by 10⁻⁹ times the sum of
/// their slopes and the segment's (every `a` here is over 1).
#[derive(Clone, Copy, Debug)]
struct Margins {
    /// Rounding: near 10⁻¹⁵ of the largest |v|, kept at 10⁻¹².
    round: f64,
    /// Lit, before the segment's own slope: rounding plus the steepest
    /// triangles' part, 10⁻⁸ times (1 + the largest step between grid
    /// neighbours).
    lit: f64,
}

impl Margins {
    /// Both margins grown by `extra`.
    fn widened(&self, extra: f64) -> Margins {
        Margins {
            round: self.round + extra,
            lit: self.lit + extra,
        }
    }

    /// The margin for calling a point whose segment has slope `vp` lit.
    #[inline]
    fn lit(&self, vp: f64) -> f64 {
        self.lit + 1e-8 * vp.abs()
    }
}

/// One line on a stretch of `u`: an identity (so that vertices are only
/// kept where the envelope changes line), and its values at both ends.
#[derive(Clone, Copy, Debug)]
struct Line {
    id: i64,
    l: f64,
    r: f64,
}

/// Appends the upper envelope of `lines` over `[x0, x1]` to `out`: a
/// vertex at `x0` when the top line differs from `last` (the top line at
/// the end of the previous stretch), and one at every crossing inside.
/// Returns the envelope's value at `x1`.
fn envelope(lines: &[Line], x0: f64, x1: f64, last: &mut i64, out: &mut Vec<Vertex>) -> f64 {
    let mut top = 0;
    for (i, c) in lines.iter().enumerate().skip(1) {
        let t = &lines[top];
        if c.l > t.l || (c.l == t.l && c.r > t.r) {
            top = i;
        }
    }
    if lines[top].id != *last {
        out.push(Vertex {
            u: x0,
            v: lines[top].l,
        });
    }
    let mut s = 0.0;
    loop {
        let t = lines[top];
        let (mut best, mut next) = (1.0, usize::MAX);
        for (i, c) in lines.iter().enumerate() {
            if c.r > t.r {
                let (dl, dr) = (t.l - c.l, c.r - t.r);
                let si = dl / (dl + dr);
                if si >= s && si < best {
                    best = si;
                    next = i;
                }
            }
        }
        if next == usize::MAX {
            break;
        }
        s = best;
        out.push(Vertex {
            u: x0 + s * (x1 - x0),
            v: t.l + s * (t.r - t.l),
        });
        top = next;
    }
    *last = lines[top].id;
    lines[top].r
}

/// The value at `x` of the segment from `p` to `q` (`p.u != q.u`); exactly
/// an end's value at that end.
#[inline]
fn at(p: Vertex, q: Vertex, x: f64) -> f64 {
    if x == q.u {
        q.v
    } else if x == p.u {
        p.v
    } else {
        p.v + (q.v - p.v) * ((x - p.u) / (q.u - p.u))
    }
}

/// The larger of two values that are never NaN: one comparison, where
/// `f64::max` also checks both for NaN.
#[inline]
fn hi(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// The smaller of two values that are never NaN.
#[inline]
fn lo(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else {
        b
    }
}

/// Columns of one octant a block at a time: their heights, read in the
/// grid's storage order, and the answers for their points, written back in
/// that order when the block is done. Columns along the grid's rows (an
/// octant whose main axis is y) lie along memory; across them, one column
/// touches a cache line and a page per point, so a block of [`BLOCK_COLUMNS`]
/// reads and writes each line once.
#[derive(Default)]
struct ColumnBlock {
    /// The block's first column and its number of columns.
    m0: usize,
    len: usize,
    /// Rows held per column, and the distance between columns in the
    /// buffers (padded, so that the columns do not share cache sets).
    rows: usize,
    stride: usize,
    heights: Vec<f32>,
    /// Per point: 0, 1, [`UNDECIDED`], or [`UNSET`] when not written.
    answers: Vec<u8>,
}

/// The `len` heights from grid index `first` on, one `step` (±1) apart, as
/// a slice in storage order (the lowest index first).
fn run(heights: &[f32], first: usize, len: usize, step: isize) -> &[f32] {
    if step > 0 {
        &heights[first..first + len]
    } else {
        &heights[first + 1 - len..=first]
    }
}

/// Columns per [`ColumnBlock`].
const BLOCK_COLUMNS: usize = 16;

/// An answer not written by the sweep.
const UNSET: u8 = u8::MAX;

impl ColumnBlock {
    /// The grid index of row `n` of octant column `m`.
    fn index(oct: &Octant, m: usize, n: usize) -> usize {
        (oct.base + m as isize * oct.sm + n as isize * oct.sn) as usize
    }

    /// Reads the block of columns from `m0`: a run of the grid's storage
    /// at a time, a row of the block where columns lie across memory, or a
    /// column where they lie along it.
    fn load(&mut self, oct: &Octant, setup: &Setup, m0: usize) {
        self.m0 = m0;
        self.len = BLOCK_COLUMNS.min(oct.columns - m0);
        self.rows = rows_for(oct, m0 + self.len - 1).min(oct.rows);
        self.stride = self.rows.next_multiple_of(16) + 16;
        let (len, rows, stride) = (self.len, self.rows, self.stride);
        self.heights.resize(len * stride, 0.0);
        let heights = &setup.heights;
        if oct.sm.abs() == 1 {
            for n in 0..rows {
                let first = Self::index(oct, m0, n);
                for (i, &z) in run(heights, first, len, oct.sm).iter().enumerate() {
                    let j = if oct.sm > 0 { i } else { len - 1 - i };
                    self.heights[j * stride + n] = z;
                }
            }
        } else {
            for j in 0..len {
                let first = Self::index(oct, m0 + j, 0);
                let col = &mut self.heights[j * stride..j * stride + rows];
                col.copy_from_slice(run(heights, first, rows, oct.sn));
                if oct.sn < 0 {
                    col.reverse();
                }
            }
        }
        self.answers.clear();
        self.answers.resize(len * stride, UNSET);
    }

    /// Hands the answers written since the last load to `put(index, value)`,
    /// in the grid's storage order.
    fn flush(&mut self, oct: &Octant, put: &mut impl FnMut(usize, u8)) {
        let across = oct.sm.abs() == 1;
        let (major, minor, outer, inner) = if across {
            (oct.sn, oct.sm, self.rows, self.len)
        } else {
            (oct.sm, oct.sn, self.len, self.rows)
        };
        let first = Self::index(oct, self.m0, 0) as isize;
        for o in 0..outer {
            let start = first + o as isize * major;
            for i in 0..inner {
                let (j, n) = if across { (i, o) } else { (o, i) };
                let value = self.answers[j * self.stride + n];
                if value != UNSET {
                    put((start + i as isize * minor) as usize, value);
                }
            }
        }
    }

    /// The projected vertices of octant column `m`, rows `0..rows` (fewer
    /// at the grid's edge), into `out`; the column must lie in the block.
    fn column(&self, oct: &Octant, setup: &Setup, m: usize, rows: usize, out: &mut Vec<Vertex>) {
        out.clear();
        let inv = 1.0 / (oct.a0 + m as f64);
        let start = (m - self.m0) * self.stride;
        let heights = &self.heights[start..start + rows.min(oct.rows)];
        for (n, &z) in heights.iter().enumerate() {
            out.push(Vertex {
                u: (n as f64 - oct.beta) * inv,
                v: (z as f64 - setup.zl) * inv,
            });
        }
    }

    /// Records the answer for row `n` of column `m`, which lies in the block.
    fn answer(&mut self, m: usize, n: usize, value: u8) {
        self.answers[(m - self.m0) * self.stride + n] = value;
    }
}

/// Rows the octant's column `m` needs: all with `b` up to past `a + 1`, so
/// that the column also serves as the near side of the next strip.
fn rows_for(oct: &Octant, m: usize) -> usize {
    (oct.a0 + m as f64 + oct.beta).ceil() as usize + 4
}

/// An upper bound on `v` over the part of the octant nearer than column 1
/// (`a ≤ a0 + 1`, `b ≤ a`), the smaller of two (`+∞` when neither holds):
/// - from the highest corner of the cells there (columns −1 to 1, the first
///   on or behind the light; rows 0 to 3), when it is below the light;
/// - from the surface's slope: along the straight way from the light's
///   ground point to any point there, the surface rises at most as fast as
///   the steepest of those cells' triangles rises along the octant's
///   directions, `g_a + max(0, g_b)` per unit `a`, so that
///   `v ≤ G + (z_ground − z_L) / (a0 + 1)`. This one also bounds a light on
///   or just above the ground, where the first is `+∞`.
fn near_bound(oct: &Octant, setup: &Setup) -> f64 {
    let z = |m: isize, n: isize| -> Option<f64> {
        let i = oct.base + m * oct.sm + n * oct.sn;
        (n < oct.rows as isize && i >= 0 && (i as usize) < setup.heights.len())
            .then(|| setup.heights[i as usize] as f64)
    };
    let mut zmax = f64::NEG_INFINITY;
    for m in -1isize..=1 {
        for n in 0..4 {
            zmax = zmax.max(z(m, n).unwrap_or(f64::NEG_INFINITY));
        }
    }
    let corner = if zmax < setup.zl {
        (zmax - setup.zl) / (oct.a0 + 1.0)
    } else {
        f64::INFINITY
    };
    // The cells between columns m − 1 and m for m = 0, 1 (column −1 and
    // column 0's cells on the grid: `octants` keeps the light's own cell in
    // it) and rows n to n + 1 for n = 0..3 where the grid has them.
    let mut steepest = f64::NEG_INFINITY;
    for m in 0isize..=1 {
        for n in 0isize..3 {
            let (Some(z00), Some(z10), Some(z01), Some(z11)) =
                (z(m - 1, n), z(m, n), z(m - 1, n + 1), z(m, n + 1))
            else {
                continue;
            };
            // Rises along a (rows n and n + 1) and along b (columns m − 1
            // and m); each triangle has one of each, paired by the diagonal.
            let (a0, a1, b0, b1) = (z10 - z00, z11 - z01, z01 - z00, z11 - z10);
            let up = |g: f64| hi(g, 0.0);
            let cell = if oct.outward {
                hi(a0 + up(b1), a1 + up(b0))
            } else {
                hi(a0 + up(b0), a1 + up(b1))
            };
            steepest = hi(steepest, cell);
        }
    }
    let sloped = steepest + (setup.ground - setup.zl) / (oct.a0 + 1.0);
    lo(corner, sloped)
}

/// Sweeps one octant, writing 1 (lit), 0 (shadowed) or [`UNDECIDED`] for its
/// interior points through `put(index, value)`.
fn sweep(oct: &Octant, setup: &Setup, put: &mut impl FnMut(usize, u8)) {
    let near = near_bound(oct, setup);
    let mut block = ColumnBlock::default();
    let mut near_col = Vec::new();
    let mut far_col = Vec::new();
    // The horizon of columns 1..m−1, starting from column 1's polyline
    // clipped to [0, 1].
    block.load(oct, setup, 1);
    block.column(oct, setup, 1, rows_for(oct, 1), &mut near_col);
    let mut horizon = clip_polyline(&near_col);
    let mut next = Vec::new();
    for m in 2..oct.columns {
        if m == block.m0 + block.len {
            block.flush(oct, put);
            block.load(oct, setup, m);
        }
        block.column(oct, setup, m, rows_for(oct, m), &mut far_col);
        merge_strip(
            oct,
            setup,
            m,
            near,
            &horizon,
            &near_col,
            &far_col,
            &mut next,
            &mut |n, value| block.answer(m, n, value),
        );
        std::mem::swap(&mut horizon, &mut next);
        std::mem::swap(&mut near_col, &mut far_col);
    }
    block.flush(oct, put);
}

/// A column's polyline clipped to `u ∈ [0, 1]`.
fn clip_polyline(col: &[Vertex]) -> Vec<Vertex> {
    let mut out = Vec::with_capacity(col.len());
    for k in 1..col.len() {
        let (p, q) = (col[k - 1], col[k]);
        if q.u <= 0.0 {
            continue;
        }
        if out.is_empty() {
            out.push(Vertex {
                u: 0.0,
                v: if p.u == 0.0 { p.v } else { at(p, q, 0.0) },
            });
        }
        if q.u >= 1.0 {
            out.push(Vertex {
                u: 1.0,
                v: at(p, q, 1.0),
            });
            return out;
        }
        out.push(q);
    }
    out
}

/// Rows per block in [`merge_strip`]'s fast paths.
const BLOCK: usize = 16;

/// Rows taken one by one where a block fails the fast paths.
const DETAIL: usize = 8;

/// The identity of horizon piece `k` (from vertex `k` to `k + 1`) among the
/// lines of [`envelope`]; strip edges have non-negative identities.
fn piece_id(k: usize) -> i64 {
    -(k as i64) - 1
}

/// The state of one pass over the old horizon while the new one is
/// written: position `x`, the old horizon's piece `k` there, and the line
/// on top of the new one.
struct Walk<'a> {
    horizon: &'a [Vertex],
    k: usize,
    x: f64,
    last_id: i64,
    top_r: f64,
    out: &'a mut Vec<Vertex>,
}

impl Walk<'_> {
    /// Moves `k` to the piece that holds `x` (and continues to its right).
    fn seek(&mut self) {
        while self.horizon[self.k + 1].u <= self.x {
            self.k += 1;
        }
    }

    /// The old horizon at `x`, on the current piece.
    fn old_at(&self, x: f64) -> f64 {
        at(self.horizon[self.k], self.horizon[self.k + 1], x)
    }

    /// The new horizon over `[x, x1]`: the upper envelope of the old one
    /// and the strip edges `segs`, piece by piece of the old one.
    fn merge(&mut self, segs: &[(Vertex, Vertex, i64)], x1: f64) {
        let vmax = segs
            .iter()
            .fold(f64::NEG_INFINITY, |acc, s| hi(hi(acc, s.0.v), s.1.v));
        while self.x < x1 {
            self.seek();
            let (hp, hq) = (self.horizon[self.k], self.horizon[self.k + 1]);
            let xe = lo(x1, hq.u);
            let (hl, hr) = (at(hp, hq, self.x), at(hp, hq, xe));
            let mut lines = [Line {
                id: piece_id(self.k),
                l: hl,
                r: hr,
            }; 5];
            let mut count = 1;
            if vmax >= lo(hl, hr) {
                for &(p, q, id) in segs {
                    lines[count] = Line {
                        id,
                        l: at(p, q, self.x),
                        r: at(p, q, xe),
                    };
                    count += 1;
                }
            }
            self.top_r = envelope(&lines[..count], self.x, xe, &mut self.last_id, self.out);
            self.x = xe;
        }
    }

    /// Appends `p` to the new horizon unless a vertex is already there.
    fn push(&mut self, p: Vertex) {
        if self.out.last().is_none_or(|q| q.u < p.u) {
            self.out.push(p);
        }
    }

    /// The old horizon's highest value over `[x, x1]`.
    fn max_over(&mut self, x1: f64) -> f64 {
        self.seek();
        let k0 = self.k;
        let mut hmax = self.old_at(self.x);
        while self.horizon[self.k + 1].u < x1 {
            self.k += 1;
            hmax = hi(hmax, self.horizon[self.k].v);
        }
        hmax = hi(hmax, self.old_at(x1));
        self.k = k0;
        hmax
    }

    /// Copies the old horizon over `[x, x1]` as the new one and returns
    /// true if it stays above `below` there (so no strip edge under
    /// `below` can show); otherwise changes nothing and returns false.
    fn copy_above(&mut self, x1: f64, below: f64) -> bool {
        self.seek();
        let (k0, len0) = (self.k, self.out.len());
        let h0 = self.old_at(self.x);
        let mut ok = h0 > below;
        if ok && self.last_id != piece_id(self.k) {
            self.out.push(Vertex { u: self.x, v: h0 });
        }
        while ok && self.horizon[self.k + 1].u < x1 {
            let q = self.horizon[self.k + 1];
            ok = q.v > below;
            self.out.push(q);
            self.k += 1;
        }
        let h1 = self.old_at(x1);
        if !(ok && h1 > below) {
            self.k = k0;
            self.out.truncate(len0);
            return false;
        }
        self.last_id = piece_id(self.k);
        self.top_r = h1;
        self.x = x1;
        true
    }
}

/// The strip edges that can be highest on one stretch between consecutive
/// projected vertices, and the stretch's right end.
///
/// In the strip between the near column A and the far column B (vertices
/// `A_n`, `B_n`), the projected vertices come in the order A_0 ≤ B_0 ≤ 0 <
/// B_1 < A_1 < B_2 < A_2 < … up to `u = 1`. On the stretch `[B_n, A_n]`
/// (`odd` false) these are the far column `B_n B_{n+1}`, the edge along `a`
/// `A_n B_n`, and, when the diagonals lean inward, the diagonals of cells
/// n − 1 and n; on `[A_n, B_{n+1}]` (`odd`; from 0 for n = 0) the far
/// column and cell n's diagonal. The near column is already under the old
/// horizon. Edge identities: 4n (far column), 4n + 1 (along a), 4n + 2
/// (diagonal).
fn stretch(
    outward: bool,
    na: &[Vertex],
    fb: &[Vertex],
    n: usize,
    odd: bool,
    segs: &mut [(Vertex, Vertex, i64); 4],
) -> (usize, f64) {
    let last = na.len().min(fb.len()) - 1;
    let diag = |n: usize| -> (Vertex, Vertex, i64) {
        let id = 4 * n as i64 + 2;
        if outward {
            (na[n], fb[n + 1], id)
        } else {
            (fb[n], na[n + 1], id)
        }
    };
    if odd {
        if n + 1 > last {
            return (0, f64::INFINITY);
        }
        segs[0] = (fb[n], fb[n + 1], 4 * n as i64);
        segs[1] = diag(n);
        return (2, fb[n + 1].u);
    }
    let mut count = 0;
    let mut push = |s| {
        segs[count] = s;
        count += 1;
    };
    push((fb[n], na[n], 4 * n as i64 + 1));
    if n < last {
        push((fb[n], fb[n + 1], 4 * n as i64));
    }
    if !outward {
        if n < last {
            push(diag(n));
        }
        push(diag(n - 1));
    }
    (count, na[n].u)
}

/// The new horizon over rows `n..ne` of a strip whose far column lies
/// above the old horizon there, from `B_n` to `B_ne`, and each point's
/// local term (`point(r, v)`: the highest the surface between the point and
/// the near column comes, `−∞` when nothing there can rise above the
/// point).
///
/// The near column is under the old horizon, so below the far column: no
/// edge along `a` and no outward diagonal can top the far column, and the
/// new horizon is the far column itself. Inward diagonals can: on
/// `[B_r, A_r]` the diagonal of cell r − 1 (ending at `A_r`) against the
/// higher of the far column and cell r's diagonal (both from `B_r`), which
/// then runs on to `B_{r+1}`.
fn rise(
    walk: &mut Walk,
    outward: bool,
    na: &[Vertex],
    fb: &[Vertex],
    n: usize,
    ne: usize,
    mut point: impl FnMut(usize, f64),
) {
    if outward {
        for (r, &b) in fb.iter().enumerate().take(ne).skip(n) {
            point(r, f64::NEG_INFINITY);
            walk.push(b);
        }
        walk.last_id = 4 * (ne as i64 - 1);
        walk.top_r = fb[ne].v;
    } else {
        // Cell r − 1's diagonal at B_r.
        let mut db = at(fb[n - 1], na[n], fb[n].u);
        for r in n..ne {
            let (b, a, b1, a1) = (fb[r], na[r], fb[r + 1], na[r + 1]);
            point(r, db);
            walk.push(Vertex {
                u: b.u,
                v: hi(b.v, db),
            });
            let (fa, da) = (at(b, b1, a.u), at(b, a1, a.u));
            let pa = hi(fa, da);
            if db > b.v {
                let (dl, dr) = (db - b.v, pa - a.v);
                let s = dl / (dl + dr);
                walk.push(Vertex {
                    u: b.u + s * (a.u - b.u),
                    v: db + s * (a.v - db),
                });
            }
            walk.last_id = 4 * r as i64 + if fa >= da { 0 } else { 2 };
            db = at(b, a1, b1.u);
        }
        walk.top_r = hi(fb[ne].v, db);
    }
    walk.x = fb[ne].u;
}

/// Decides column `m`'s points against `horizon` (columns 1..m−1), through
/// `put(row, value)`, and writes the horizon of columns 1..m into `out`, in
/// one pass over both.
///
/// Blocks of [`BLOCK`] rows whose strip lies wholly below the old horizon
/// (the common case far from the light) copy the old horizon and shadow
/// their points without looking at single edges.
#[allow(clippy::too_many_arguments)]
fn merge_strip(
    oct: &Octant,
    setup: &Setup,
    m: usize,
    near: f64,
    horizon: &[Vertex],
    na: &[Vertex],
    fb: &[Vertex],
    out: &mut Vec<Vertex>,
    put: &mut impl FnMut(usize, u8),
) {
    out.clear();
    let a = oct.a0 + m as f64;
    let lift = setup.lift / a;
    let tol = setup.tol;
    let end = horizon[horizon.len() - 1].u;
    let last = na.len().min(fb.len()) - 1;
    // Whether B_n is a point of this octant's interior (0 < b < a).
    let interior = |n: usize| {
        let b = n as f64 - oct.beta;
        let margin = 1e-9 * a;
        b > margin && b < a - margin
    };
    let mut walk = Walk {
        horizon,
        k: 0,
        x: 0.0,
        last_id: i64::MIN,
        top_r: f64::NEG_INFINITY,
        out,
    };
    let zero = Vertex { u: 0.0, v: 0.0 };
    let mut segs = [(zero, zero, 0i64); 4];
    // Points on the octant's axis (b = 0) and diagonal (b = a), or off
    // them by rounding (10⁻¹² a, which moves the surface under the segment
    // by under 10⁻¹¹ a times the largest step: both margins grow by that).
    let on_line = 1e-12 * a;
    let line_tol = tol.widened(1e-11 * a * (1.0 + setup.step));
    // On the axis, the segment runs along the edges of row 0, whose grid
    // points the old horizon holds at u = 0.
    if oct.beta <= on_line {
        let old = horizon[0].v;
        put(
            0,
            verdict(old, near, f64::NEG_INFINITY, fb[0].v + lift, line_tol),
        );
    }
    let (count, x1) = stretch(oct.outward, na, fb, 0, true, &mut segs);
    walk.merge(&segs[..count], lo(x1, end));
    let mut n = 1;
    while n <= last && walk.x < end {
        // A block of rows n..ne wholly below the old horizon?
        let ne = (n + BLOCK).min(last);
        let mut strip_above = false;
        if ne > n && fb[ne].u < end {
            let (mut vmax, mut bmin) = (fb[n - 1].v, f64::INFINITY);
            for r in n..=ne {
                vmax = hi(hi(vmax, fb[r].v), na[r].v);
                bmin = lo(bmin, fb[r].v);
            }
            // The whole strip below the old horizon: copy it, and every
            // point is in shadow.
            if walk.copy_above(fb[ne].u, vmax + lift + tol.round) {
                for r in n..ne {
                    if interior(r) {
                        put(r, 0);
                    }
                }
                n = ne;
                continue;
            }
            // The far column above the old horizon (and the part nearer
            // than column 1): the strip alone makes the new horizon, and
            // only the diagonal next to each point can shadow it.
            let lit = tol.lit((bmin + lift).abs().max((vmax + lift).abs()));
            strip_above = near + lit < bmin && walk.max_over(fb[ne].u) + lit < bmin;
        }
        if strip_above {
            rise(&mut walk, oct.outward, na, fb, n, ne, |r, local| {
                if interior(r) {
                    let none = f64::NEG_INFINITY;
                    put(r, verdict(none, none, local, fb[r].v + lift, tol));
                }
            });
            n = ne;
            continue;
        }
        // Row by row: decide B_n, then the stretches [B_n, A_n] and
        // [A_n, B_{n+1}].
        for n in n..(n + DETAIL).min(last + 1) {
            if walk.x >= end {
                break;
            }
            if interior(n) {
                walk.seek();
                let old = walk.old_at(walk.x);
                let local = if oct.outward {
                    f64::NEG_INFINITY
                } else {
                    at(fb[n - 1], na[n], walk.x)
                };
                put(n, verdict(old, near, local, fb[n].v + lift, tol));
            }
            for odd in [false, true] {
                let (count, x1) = stretch(oct.outward, na, fb, n, odd, &mut segs);
                walk.merge(&segs[..count], lo(x1, end));
            }
        }
        n += DETAIL;
    }
    // Past the strip's last row: the old horizon alone, as far as a later
    // column can look. A later column's rows end no further out than this
    // one's (the grid's last row) at a larger `a`, so directions beyond
    // this column's last row are never read again; kept, they would be
    // copied column after column, quadratic time on a long, thin grid.
    let last_u = fb[fb.len() - 1].u;
    let keep = if last_u > 0.0 { lo(end, last_u) } else { end };
    if walk.x <= keep {
        walk.merge(&[], keep);
        if walk.out.last().is_none_or(|p| p.u < keep) {
            let v = walk.top_r;
            walk.out.push(Vertex { u: keep, v });
        }
    } else {
        // The strip reached past `keep`: cut the new horizon there, on the
        // piece that spans it (the last one runs to `x` at `top_r`).
        let mut after = Vertex {
            u: walk.x,
            v: walk.top_r,
        };
        while let Some(&p) = walk.out.last().filter(|p| p.u > keep) {
            after = p;
            walk.out.pop();
        }
        match walk.out.last().copied() {
            Some(before) if before.u < keep => walk.out.push(Vertex {
                u: keep,
                v: at(before, after, keep),
            }),
            Some(_) => {}
            None => walk.out.push(Vertex {
                u: keep,
                v: after.v,
            }),
        }
    }
    // A point on the octant's diagonal (b = a, u = 1): its segment runs
    // along outward diagonals, whose grid points the old horizon holds at
    // u = 1, or across inward ones, whose crossings it holds too, and
    // crosses one more on the way to the near column.
    let nd = (a + oct.beta).round();
    if end == 1.0 && (nd - oct.beta - a).abs() <= on_line && nd >= 1.0 && nd as usize <= last {
        let nd = nd as usize;
        let local = if oct.outward {
            f64::NEG_INFINITY
        } else {
            at(fb[nd - 1], na[nd], 1.0)
        };
        let old = horizon[horizon.len() - 1].v;
        put(nd, verdict(old, near, local, fb[nd].v + lift, line_tol));
    }
}

/// A point's answer from the highest the surface comes between it and the
/// light, in three parts: the old horizon at its direction, the bound for
/// the part nearer than column 1, and the strip up to its own column
/// (`−∞` where nothing there can rise above it). 1 lit, 0 shadowed, or
/// [`UNDECIDED`] within the margins `tol` (the near part is only a bound,
/// so it can light a point but never shadow one).
fn verdict(old: f64, near: f64, local: f64, vp: f64, tol: Margins) -> u8 {
    let seen = hi(old, local);
    if hi(seen, near) < vp - tol.lit(vp) {
        1
    } else if seen > vp + tol.round {
        0
    } else {
        UNDECIDED
    }
}

/// The largest height difference between neighbouring grid points along a
/// row or a column: no triangle's slope along either axis is steeper.
fn max_step(field: &HeightField) -> f64 {
    use rayon::prelude::*;
    let (w, h) = (field.width, field.height);
    let z = &field.heights;
    (0..h)
        .into_par_iter()
        .map(|r| {
            let row = &z[r * w..(r + 1) * w];
            let mut s = largest_difference(&row[..w - 1], &row[1..]);
            if r + 1 < h {
                s = s.max(largest_difference(row, &z[(r + 1) * w..(r + 2) * w]));
            }
            s as f64
        })
        .reduce(|| 0.0, f64::max)
}

/// The largest `|b[i] − a[i]|` (the slices are equally long and hold no
/// NaN), eight lanes at a time so that the loop compiles to vector
/// operations.
fn largest_difference(a: &[f32], b: &[f32]) -> f32 {
    const LANES: usize = 8;
    let mut m = [0f32; LANES];
    let (pa, pb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (ra, rb) = (pa.remainder(), pb.remainder());
    for (x, y) in pa.zip(pb) {
        for k in 0..LANES {
            let d = (y[k] - x[k]).abs();
            m[k] = if d > m[k] { d } else { m[k] };
        }
    }
    let mut out = ra
        .iter()
        .zip(rb)
        .fold(0f32, |acc, (x, y)| acc.max((y - x).abs()));
    for v in m {
        out = out.max(v);
    }
    out
}

/// The mask's cells, for the octants' sweeps to write in parallel.
#[derive(Clone, Copy)]
struct SharedCells(*mut u8);

// SAFETY: the cells are written only through atomic stores while shared.
unsafe impl Sync for SharedCells {}
unsafe impl Send for SharedCells {}

impl SharedCells {
    /// The address of cell `i`.
    fn at(self, i: usize) -> *mut u8 {
        self.0.wrapping_add(i)
    }
}

/// The sweep's mask for a point light at `light` (world metres) and
/// targets `lift` metres above the ground: per grid point (row-major from
/// the north row) 1 lit, 0 shadowed, or [`UNDECIDED`]. A light on the
/// ground is placed as the masks place it ([`place_light`]). `None` when
/// the light is not over the grid or is below the ground there, where the
/// sweep's bounds do not hold.
pub fn point_light_mask(field: &HeightField, light: [f64; 3], lift: f64) -> Option<Vec<u8>> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicU8, Ordering};
    let light = place_light(field, light);
    let (lx, ly, zl) = (light[0] / field.sx, -light[1] / field.sy, light[2]);
    let (w, h) = (field.width, field.height);
    let inside = (0.0..=(w - 1) as f64).contains(&lx) && (0.0..=(h - 1) as f64).contains(&ly);
    if !inside || !lift.is_finite() || lift < 0.0 {
        return None;
    }
    let ground = field.height_at(lx, ly);
    if zl.partial_cmp(&ground) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let (zmin, zmax) = (field.zmin as f64, field.zmax as f64);
    let step = max_step(field);
    let round = 1e-12 * (1.0 + zl.abs() + zmax.abs() + zmin.abs() + lift);
    let setup = Setup {
        heights: &field.heights,
        zl,
        ground,
        lift,
        tol: Margins {
            round,
            lit: round + 1e-8 * (1.0 + step),
        },
        step,
    };
    let mut mask = vec![UNDECIDED; w * h];
    // Octants that share an axis or a diagonal may both write its points,
    // so while they run every write is atomic.
    let cells = SharedCells(mask.as_mut_ptr());
    octants(lx, ly, w, h).par_iter().for_each(|oct| {
        sweep(oct, &setup, &mut |i, value| {
            assert!(i < w * h);
            // SAFETY: `i` is within the mask, which outlives the sweep and
            // is only written through these atomic stores until it ends.
            unsafe { AtomicU8::from_ptr(cells.at(i)) }.store(value, Ordering::Relaxed)
        });
    });
    Some(mask)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The steepest step between grid neighbours against a plain loop over
    /// every pair, on grids whose rows are no multiple of the lanes.
    #[test]
    fn max_step_is_the_steepest_neighbour_difference() {
        let mut rng = raykit_core::rng::Pcg32::new(21);
        for (w, h) in [(2, 2), (9, 3), (37, 29), (130, 17)] {
            let heights: Vec<f32> = (0..w * h).map(|_| rng.range_f32(-50.0, 900.0)).collect();
            let dem = crate::Dem::from_heights(w, h, heights.clone());
            let field = HeightField::new(&dem).unwrap();
            let mut want = 0f32;
            for r in 0..h {
                for c in 0..w {
                    let z = heights[r * w + c];
                    if c + 1 < w {
                        want = want.max((heights[r * w + c + 1] - z).abs());
                    }
                    if r + 1 < h {
                        want = want.max((heights[(r + 1) * w + c] - z).abs());
                    }
                }
            }
            assert_eq!(max_step(&field), want as f64, "{w}x{h}");
        }
    }
}
