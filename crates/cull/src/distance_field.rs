//! The directed distance field (Min 2008, first stage): per grid point, the
//! distance to the nearest surface along each of ±x, ±y, ±z and the id of the
//! triangle found there.
//!
//! Min (2008) renders the model slab by slab and reads the depth buffer (the
//! distance) and a colour buffer (the triangle id). We cast one axis-aligned
//! ray per grid line through the accel and peel it: after each hit the ray
//! goes on just past it, so a line's sorted hit list holds every surface
//! crossing along it. Every point's six directed distances follow from its
//! lines' lists (the next hit after the point, the last one before it), so
//! the field is stored as those lists — a few hits per line instead of 48
//! bytes per point, which at 256³ would be 800 MB — plus one byte per point
//! with the three "free step" bits that front propagation reads.

use crate::grid::Grid;
use raykit_core::{Accel, Ray, Vec3};
use rayon::prelude::*;

/// Most hits recorded on one grid line; a line that crosses more surfaces
/// (pathological stacks of coincident triangles) is cut off there and treated
/// as free beyond its last recorded hit, which can only let more points be
/// reached from outside (more triangles kept, never fewer).
pub const MAX_HITS_PER_LINE: usize = 1 << 16;

/// One of the six axis directions of Min's (2008) directed distances.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Direction {
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// True for the positive direction.
    pub positive: bool,
}

impl Direction {
    /// The six directions: +x, −x, +y, −y, +z, −z.
    pub const ALL: [Direction; 6] = [
        Direction {
            axis: 0,
            positive: true,
        },
        Direction {
            axis: 0,
            positive: false,
        },
        Direction {
            axis: 1,
            positive: true,
        },
        Direction {
            axis: 1,
            positive: false,
        },
        Direction {
            axis: 2,
            positive: true,
        },
        Direction {
            axis: 2,
            positive: false,
        },
    ];
}

/// The nearest surface along one direction from one grid point (Min (2008):
/// the depth and colour buffer values at that point).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectedHit {
    /// Distance from the grid point to the surface.
    pub distance: f32,
    /// Triangle index in the mesh.
    pub prim: u32,
}

/// Sorted surface crossings of every grid line parallel to one axis, in
/// compressed rows: line `l`'s hits are `t[offsets[l]..offsets[l + 1]]`,
/// measured from the line's first grid point.
#[derive(Clone, Debug, Default)]
struct LineHits {
    offsets: Vec<usize>,
    t: Vec<f32>,
    prim: Vec<u32>,
}

impl LineHits {
    #[inline]
    fn line(&self, l: usize) -> (&[f32], &[u32]) {
        let r = self.offsets[l]..self.offsets[l + 1];
        (&self.t[r.clone()], &self.prim[r])
    }
}

/// Min's (2008) directed distance field on a [`Grid`], stored as the sorted
/// hit lists of the grid lines (see the module documentation).
#[derive(Clone, Debug)]
pub struct DirectedDistanceField {
    /// The grid the field is sampled on.
    pub grid: Grid,
    lines: [LineHits; 3],
}

/// All surface crossings along one line, nearest first: cast, then cast again
/// from just past the hit (depth peeling, as Min's (2008) slab renders).
fn peel_line(accel: &dyn Accel, origin: Vec3, axis: usize, length: f32) -> Vec<(f32, u32)> {
    let dir = Vec3::AXES[axis];
    let mut hits = Vec::new();
    let mut tnear = 0.0f32;
    while hits.len() < MAX_HITS_PER_LINE {
        let ray = Ray::segment(origin, dir, tnear, length);
        match accel.intersect(&ray) {
            Some(h) if h.t.is_finite() && h.t >= tnear => {
                hits.push((h.t, h.prim));
                tnear = h.t.next_up();
            }
            _ => break,
        }
    }
    hits
}

impl DirectedDistanceField {
    /// Cast the grid lines of `grid` against `accel` (built over the model),
    /// in parallel over lines (Min 2008, first stage).
    pub fn compute(accel: &dyn Accel, grid: &Grid) -> DirectedDistanceField {
        let lines = [0, 1, 2].map(|axis| {
            let n = grid.dims[axis];
            let length = grid.spacing * (n - 1) as f32;
            let per_line: Vec<Vec<(f32, u32)>> = (0..grid.lines(axis))
                .into_par_iter()
                .with_min_len(64)
                .map(|l| peel_line(accel, grid.point(grid.line_point(axis, l, 0)), axis, length))
                .collect();
            let mut out = LineHits {
                offsets: Vec::with_capacity(per_line.len() + 1),
                ..Default::default()
            };
            out.offsets.push(0);
            for hits in per_line {
                out.t.extend(hits.iter().map(|h| h.0));
                out.prim.extend(hits.iter().map(|h| h.1));
                out.offsets.push(out.t.len());
            }
            out
        });
        DirectedDistanceField { grid: *grid, lines }
    }

    /// Total number of surface crossings stored (all lines, all axes).
    pub fn hit_count(&self) -> usize {
        self.lines.iter().map(|l| l.t.len()).sum()
    }

    /// Sorted crossings of line `line` parallel to `axis` (numbered as in
    /// [`Grid::line_point`]): distances from the line's point 0 and triangle
    /// ids.
    pub fn line_hits(&self, axis: usize, line: usize) -> (&[f32], &[u32]) {
        self.lines[axis].line(line)
    }

    /// Min's (2008) directed distance of point `p` in direction `dir`: the
    /// nearest surface at distance ≥ 0 (a surface through the point is at 0),
    /// or `None` when the ray leaves the grid without meeting one.
    pub fn directed(&self, p: [usize; 3], dir: Direction) -> Option<DirectedHit> {
        let (t, prim) = self.line_hits(dir.axis, self.grid.line_of(dir.axis, p));
        let s = p[dir.axis] as f32 * self.grid.spacing;
        if dir.positive {
            let k = t.partition_point(|&x| x < s);
            (k < t.len()).then(|| DirectedHit {
                distance: t[k] - s,
                prim: prim[k],
            })
        } else {
            let k = t.partition_point(|&x| x <= s);
            (k > 0).then(|| DirectedHit {
                distance: s - t[k - 1],
                prim: prim[k - 1],
            })
        }
    }

    /// One byte per grid point: bit `a` set when the step from the point to
    /// its neighbour along `+a` is free — no surface on the closed segment
    /// between them, i.e. the point's `+a` directed distance exceeds the
    /// spacing (Min's (2008) propagation rule). A line cut off at
    /// [`MAX_HITS_PER_LINE`] is free beyond its last recorded hit.
    pub fn free_steps(&self) -> Vec<u8> {
        let g = &self.grid;
        let h = g.spacing;
        // A crossing within rounding of a grid point blocks the steps on
        // both sides of it. The crossings are distances from a line's first
        // point and the steps' ends multiples of the spacing, each rounded
        // in `f32`: a surface passing just after a point came out one ulp
        // before it, the step beyond it was free, and the front leaked
        // through a closed sphere at some resolutions.
        let reach =
            h * g.dims.iter().copied().max().unwrap_or(1) as f32 + g.origin.abs().max_element();
        let slack = 8.0 * f32::EPSILON * reach;
        let slab = g.dims[0] * g.dims[1];
        let mut bits = vec![0u8; g.len()];
        bits.par_chunks_mut(slab).enumerate().for_each(|(k, out)| {
            for axis in 0..3 {
                let n = g.dims[axis];
                if axis == 2 {
                    // z lines cross the slabs: find the step k → k + 1.
                    if k + 1 == n {
                        continue;
                    }
                    let (s0, s1) = (k as f32 * h - slack, (k + 1) as f32 * h + slack);
                    for (idx, b) in out.iter_mut().enumerate() {
                        let p = [idx % g.dims[0], idx / g.dims[0], k];
                        let (t, _) = self.line_hits(2, g.line_of(2, p));
                        let m = t.partition_point(|&x| x < s0);
                        if m == t.len() || t[m] > s1 {
                            *b |= 4;
                        }
                    }
                    continue;
                }
                // x and y lines lie inside the slab: sweep each once.
                let other = g.dims[1 - axis];
                for o in 0..other {
                    let mut p = [0, 0, k];
                    p[1 - axis] = o;
                    let (t, _) = self.line_hits(axis, g.line_of(axis, p));
                    let mut m = 0;
                    for i in 0..n - 1 {
                        let (s0, s1) = (i as f32 * h - slack, (i + 1) as f32 * h + slack);
                        while m < t.len() && t[m] < s0 {
                            m += 1;
                        }
                        if m == t.len() || t[m] > s1 {
                            p[axis] = i;
                            out[p[0] + g.dims[0] * p[1]] |= 1 << axis;
                        }
                    }
                }
            }
        });
        bits
    }
}
