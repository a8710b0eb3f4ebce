//! SAH kd-tree build in O(N log N) after Wald & Havran 2006, "On building
//! fast kd-trees for ray tracing, and on doing that in O(N log N)".
//!
//! - Each triangle reference contributes *events* per axis: a start and an
//!   end at its box bounds, or one planar event when the box is flat. The
//!   event lists are sorted once, at the root.
//! - At a node, one sweep per axis over the sorted events gives, for every
//!   candidate plane, the counts left, right and on the plane, and so the
//!   SAH cost `K_T + K_I (P_L N_L + P_R N_R)` (planar triangles on the
//!   cheaper side, a bonus for cutting off empty space); the node becomes a
//!   leaf when no plane is cheaper than `K_I N` ("automatic termination").
//! - Splitting keeps the order: references entirely on one side carry their
//!   events over unchanged; only straddling triangles are clipped to each
//!   child ("perfect splits"), and their few new events are sorted and merged
//!   in.
//!
//! Reference boxes include each triangle's tolerance band (see
//! `clip::reference_box`).

use super::clip::reference_box;
use super::refs::{leaf_of as leaf, root_refs, Ref};
use super::tree::{split_cell, KdBuildNode};
use super::{KdOptions, TriangleSet};
use crate::aabb::Aabb;

/// Event kinds, in the order events at one position are swept.
const END: u8 = 0;
const PLANAR: u8 = 1;
const START: u8 = 2;

#[derive(Clone, Copy, Debug)]
struct Event {
    pos: f32,
    kind: u8,
    /// Index of the reference in the node's reference list.
    r: u32,
}

/// Which children a reference goes to.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Side {
    Left,
    Right,
    Both,
}

/// A chosen split.
#[derive(Clone, Copy, Debug)]
struct Plane {
    axis: usize,
    pos: f32,
    planar_left: bool,
    cost: f32,
}

/// Build the SAH kd-tree over `tris` with root cell `cell`.
pub(crate) fn build(tris: &TriangleSet, cell: &Aabb, opts: &KdOptions) -> KdBuildNode {
    let refs = root_refs(tris, cell);
    let events = std::array::from_fn(|axis| {
        let mut ev = events_of(&refs, 0, axis);
        sort_events(&mut ev);
        ev
    });
    let max_depth = opts.depth_limit(refs.len());
    node(tris, refs, events, *cell, 0, max_depth, opts)
}

fn events_of(refs: &[Ref], base: u32, axis: usize) -> Vec<Event> {
    let mut ev = Vec::with_capacity(refs.len() * 2);
    for (i, r) in refs.iter().enumerate() {
        let (lo, hi) = (r.bounds.min[axis], r.bounds.max[axis]);
        let r = base + i as u32;
        if lo == hi {
            ev.push(Event {
                pos: lo,
                kind: PLANAR,
                r,
            });
        } else {
            ev.push(Event {
                pos: lo,
                kind: START,
                r,
            });
            ev.push(Event {
                pos: hi,
                kind: END,
                r,
            });
        }
    }
    ev
}

fn sort_events(ev: &mut [Event]) {
    let key = |e: &Event| (e.pos, e.kind);
    if ev.len() > 1 << 16 {
        use rayon::slice::ParallelSliceMut;
        ev.par_sort_unstable_by(|a, b| key(a).partial_cmp(&key(b)).unwrap());
    } else {
        ev.sort_unstable_by(|a, b| key(a).partial_cmp(&key(b)).unwrap());
    }
}

/// Merge two lists sorted by `(pos, kind)`.
fn merge(a: Vec<Event>, b: Vec<Event>) -> Vec<Event> {
    if b.is_empty() {
        return a;
    }
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if (a[i].pos, a[i].kind) <= (b[j].pos, b[j].kind) {
            out.push(a[i]);
            i += 1;
        } else {
            out.push(b[j]);
            j += 1;
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

fn node(
    tris: &TriangleSet,
    refs: Vec<Ref>,
    events: [Vec<Event>; 3],
    cell: Aabb,
    depth: u32,
    max_depth: u32,
    opts: &KdOptions,
) -> KdBuildNode {
    let n = refs.len();
    if n <= 1 || depth >= max_depth {
        return leaf(&refs);
    }
    let Some(plane) = find_plane(&events, n, &cell, opts) else {
        return leaf(&refs);
    };
    if plane.cost >= opts.intersection_cost * n as f32 {
        return leaf(&refs);
    }
    let [lcell, rcell] = split_cell(&cell, plane.axis, plane.pos);

    // Classify with the events of the split axis.
    let mut side = vec![Side::Both; n];
    for e in &events[plane.axis] {
        let s = &mut side[e.r as usize];
        match e.kind {
            END if e.pos <= plane.pos => *s = Side::Left,
            START if e.pos >= plane.pos => *s = Side::Right,
            PLANAR => {
                *s = if e.pos < plane.pos || (e.pos == plane.pos && plane.planar_left) {
                    Side::Left
                } else {
                    Side::Right
                }
            }
            _ => {}
        }
    }

    // Child reference lists: one-sided references keep their boxes, the
    // straddling ones are clipped to each child.
    let mut lrefs = Vec::with_capacity(n / 2);
    let mut rrefs = Vec::with_capacity(n / 2);
    let mut lmap = vec![u32::MAX; n];
    let mut rmap = vec![u32::MAX; n];
    for (i, r) in refs.iter().enumerate() {
        if side[i] == Side::Left {
            lmap[i] = lrefs.len() as u32;
            lrefs.push(*r);
        } else if side[i] == Side::Right {
            rmap[i] = rrefs.len() as u32;
            rrefs.push(*r);
        }
    }
    let (l_kept, r_kept) = (lrefs.len(), rrefs.len());
    for (i, r) in refs.iter().enumerate() {
        if side[i] == Side::Both {
            let t = r.tri as usize;
            for (cell, out) in [(&lcell, &mut lrefs), (&rcell, &mut rrefs)] {
                if let Some(b) = reference_box(&tris.corners[t], tris.band[t], cell) {
                    out.push(Ref {
                        tri: r.tri,
                        bounds: b.intersection(r.bounds),
                    });
                }
            }
        }
    }
    drop(refs);
    let [e0, e1, e2] = events;
    let mut levents: [Vec<Event>; 3] = Default::default();
    let mut revents: [Vec<Event>; 3] = Default::default();
    for (axis, ev) in [e0, e1, e2].into_iter().enumerate() {
        let mut l = Vec::with_capacity(2 * l_kept);
        let mut r = Vec::with_capacity(2 * r_kept);
        for e in &ev {
            match side[e.r as usize] {
                Side::Left => l.push(Event {
                    r: lmap[e.r as usize],
                    ..*e
                }),
                Side::Right => r.push(Event {
                    r: rmap[e.r as usize],
                    ..*e
                }),
                Side::Both => {}
            }
        }
        drop(ev);
        let mut lnew = events_of(&lrefs[l_kept..], l_kept as u32, axis);
        sort_events(&mut lnew);
        let mut rnew = events_of(&rrefs[r_kept..], r_kept as u32, axis);
        sort_events(&mut rnew);
        levents[axis] = merge(l, lnew);
        revents[axis] = merge(r, rnew);
    }
    drop(side);
    let (left, right) = if n > opts.parallel_threshold {
        rayon::join(
            || node(tris, lrefs, levents, lcell, depth + 1, max_depth, opts),
            || node(tris, rrefs, revents, rcell, depth + 1, max_depth, opts),
        )
    } else {
        (
            node(tris, lrefs, levents, lcell, depth + 1, max_depth, opts),
            node(tris, rrefs, revents, rcell, depth + 1, max_depth, opts),
        )
    };
    KdBuildNode::Inner {
        axis: plane.axis as u8,
        split: plane.pos,
        children: Box::new([left, right]),
    }
}

/// The cheapest plane strictly inside the cell, by one sweep per axis.
fn find_plane(events: &[Vec<Event>; 3], n: usize, cell: &Aabb, opts: &KdOptions) -> Option<Plane> {
    let area = cell.surface_area();
    if area <= 0.0 {
        return None;
    }
    let mut best: Option<Plane> = None;
    let ext = cell.extent();
    for (axis, ev) in events.iter().enumerate() {
        // Child areas are linear in the plane position: SA = 2 (e_b e_c +
        // len · (e_b + e_c)) with `len` the child's extent along `axis`.
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        let (perp, side) = (ext[b] * ext[c], ext[b] + ext[c]);
        let (lo, hi) = (cell.min[axis], cell.max[axis]);
        let (mut nl, mut nr) = (0usize, n);
        let mut i = 0;
        while i < ev.len() {
            let pos = ev[i].pos;
            let (mut ends, mut planars, mut starts) = (0, 0, 0);
            while i < ev.len() && ev[i].pos == pos && ev[i].kind == END {
                ends += 1;
                i += 1;
            }
            while i < ev.len() && ev[i].pos == pos && ev[i].kind == PLANAR {
                planars += 1;
                i += 1;
            }
            while i < ev.len() && ev[i].pos == pos && ev[i].kind == START {
                starts += 1;
                i += 1;
            }
            nr -= planars + ends;
            if pos > lo && pos < hi {
                let pl = 2.0 * (perp + (pos - lo) * side) / area;
                let pr = 2.0 * (perp + (hi - pos) * side) / area;
                for planar_left in [true, false] {
                    let (a, b) = if planar_left {
                        (nl + planars, nr)
                    } else {
                        (nl, nr + planars)
                    };
                    let mut cost = opts.traversal_cost
                        + opts.intersection_cost * (pl * a as f32 + pr * b as f32);
                    if a == 0 || b == 0 {
                        cost *= 1.0 - opts.empty_bonus;
                    }
                    if best.is_none_or(|p| cost < p.cost) {
                        best = Some(Plane {
                            axis,
                            pos,
                            planar_left,
                            cost,
                        });
                    }
                }
            }
            nl += starts + planars;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use glam::Vec3;

    /// The sweep over sorted events finds the same cheapest cost as counting
    /// left, right and planar references from scratch for every candidate.
    #[test]
    fn sweep_matches_naive_cost_evaluation() {
        let opts = KdOptions::default();
        let mut rng = Pcg32::new(3);
        for case in 0..200 {
            let cell = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 0.5));
            let n = 1 + case % 40;
            let refs: Vec<Ref> = (0..n)
                .map(|i| {
                    let a = rng.in_box(cell.min, cell.max);
                    let mut b = rng.in_box(cell.min, cell.max);
                    if i % 4 == 0 {
                        b[i % 3] = a[i % 3]; // planar
                    }
                    // Snap to a coarse grid so positions coincide often.
                    let snap = |v: Vec3| (v * 8.0).round() / 8.0;
                    Ref {
                        tri: i as u32,
                        bounds: Aabb::new(snap(a.min(b)), snap(a.max(b))),
                    }
                })
                .collect();
            let events: [Vec<Event>; 3] = std::array::from_fn(|axis| {
                let mut ev = events_of(&refs, 0, axis);
                sort_events(&mut ev);
                ev
            });
            let got = find_plane(&events, n, &cell, &opts).map(|p| p.cost);
            let mut want: Option<f32> = None;
            let area = cell.surface_area();
            for axis in 0..3 {
                for r in &refs {
                    for pos in [r.bounds.min[axis], r.bounds.max[axis]] {
                        if !(pos > cell.min[axis] && pos < cell.max[axis]) {
                            continue;
                        }
                        let flat =
                            |r: &&Ref| r.bounds.min[axis] == pos && r.bounds.max[axis] == pos;
                        let planar = refs.iter().filter(flat).count();
                        let left = refs.iter().filter(|r| r.bounds.min[axis] < pos).count();
                        let right = refs
                            .iter()
                            .filter(|r| {
                                r.bounds.max[axis] > pos || (r.bounds.min[axis] >= pos && !flat(r))
                            })
                            .count();
                        let [l, rr] = split_cell(&cell, axis, pos);
                        let (pl, pr) = (l.surface_area() / area, rr.surface_area() / area);
                        for (a, b) in [(left + planar, right), (left, right + planar)] {
                            let mut c = opts.traversal_cost
                                + opts.intersection_cost * (pl * a as f32 + pr * b as f32);
                            if a == 0 || b == 0 {
                                c *= 1.0 - opts.empty_bonus;
                            }
                            want = Some(want.map_or(c, |w: f32| w.min(c)));
                        }
                    }
                }
            }
            match (got, want) {
                (Some(g), Some(w)) => assert!(
                    (g - w).abs() <= 1e-4 * w,
                    "case {case}: sweep {g}, naive {w}"
                ),
                (g, w) => assert_eq!(g.is_some(), w.is_some(), "case {case}"),
            }
        }
    }
}
