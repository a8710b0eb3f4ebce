//! Escape directions shared between neighbouring triangles: the
//! ground-truth evaluator's search through narrow openings (our
//! addition to Min's (2008) setting).
//!
//! A triangle seen only through a slit (the clearance round a bolt, a seam
//! between two parts) escapes along a small cone of directions that random
//! sampling rarely meets. Its neighbours behind the same slit escape along
//! nearly the same directions. So escaping rays found (by random sampling
//! or by a render) are filed under the coarse cell of their triangle's
//! centroid (the first [`DIRECTIONS_PER_CELL`] distinct ones per cell), and the still-unseen triangles of that cell and the
//! 26 around it try those directions; what they find is filed in turn,
//! until nothing new is found. Each label still rests on one ray that met
//! nothing, so this only finds visible triangles faster, never invents one.

use crate::escape::{beam_escapes, off_surface, on_surface, MIN_FACE_COSINE};
use raykit_core::rng::Pcg32;
use raykit_core::{Aabb, Accel, TriangleMesh, Vec3};
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

/// Cells per axis of the grid on which escape directions are shared.
pub const SHARING_CELLS: usize = 64;
/// Most passes of [`SharedEscapes::spread`].
pub const MAX_SHARING_PASSES: usize = 64;
/// Most sample points per triangle when trying shared directions.
pub const SHARING_POINTS: u32 = 4;

/// What [`SharedEscapes::spread`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spread {
    /// Triangles newly labelled by the escapes given to it.
    pub direct: usize,
    /// Triangles newly labelled by shared directions.
    pub by_sharing: usize,
    /// Passes of sharing.
    pub passes: usize,
    /// Rays cast (at most; tries stop at the first escape).
    pub rays: u64,
    /// True when the ray budget stopped it before nothing new was found.
    pub cut_short: bool,
}

/// Most directions kept per cell.
pub const DIRECTIONS_PER_CELL: usize = 8;
/// Most directions one triangle tries per pass (its own cell's first).
pub const DIRECTIONS_PER_TRIANGLE: usize = 32;
/// Directions closer than this cosine to one already filed in the cell are
/// not filed again.
const SAME_DIRECTION: f32 = 0.999;

/// Escaping directions filed by coarse cell (see the module documentation).
#[derive(Clone, Debug)]
pub struct SharedEscapes {
    origin: Vec3,
    cell: f32,
    dims: [usize; 3],
    cells: HashMap<[usize; 3], Vec<Vec3>>,
    changed: HashSet<[usize; 3]>,
}

impl SharedEscapes {
    /// Cells of side `extent / cells_per_axis` over `bounds`.
    pub fn new(bounds: &Aabb, cells_per_axis: usize) -> Self {
        let extent = bounds.extent().max_element();
        let cell = if extent.is_finite() && extent > 0.0 {
            extent / cells_per_axis.max(1) as f32
        } else {
            1.0
        };
        let dims = bounds
            .extent()
            .to_array()
            .map(|e| ((e / cell).floor() as usize + 1).clamp(1, cells_per_axis.max(1)));
        SharedEscapes {
            origin: bounds.min,
            cell,
            dims,
            cells: HashMap::new(),
            changed: HashSet::new(),
        }
    }

    fn cell_of(&self, p: Vec3) -> [usize; 3] {
        let q = (p - self.origin) / self.cell;
        [0, 1, 2].map(|a| (q[a].max(0.0) as usize).min(self.dims[a] - 1))
    }

    /// The cell of triangle `tri`'s centroid.
    pub fn cell_of_triangle(&self, mesh: &TriangleMesh, tri: usize) -> [usize; 3] {
        self.cell_of(centroid(mesh, tri))
    }

    /// File direction `d`, which escaped from a point of triangle `tri`.
    pub fn add(&mut self, mesh: &TriangleMesh, tri: usize, d: Vec3) {
        let c = self.cell_of(centroid(mesh, tri));
        let list = self.cells.entry(c).or_default();
        if list.len() < DIRECTIONS_PER_CELL && list.iter().all(|e| e.dot(d) < SAME_DIRECTION) {
            list.push(d);
            self.changed.insert(c);
        }
    }

    /// Cells that received a direction since the last call, cleared.
    pub fn take_changed(&mut self) -> HashSet<[usize; 3]> {
        std::mem::take(&mut self.changed)
    }

    /// True when triangle `tri`'s cell or one of its 26 neighbours is in
    /// `cells`.
    pub fn near_any(&self, mesh: &TriangleMesh, tri: usize, cells: &HashSet<[usize; 3]>) -> bool {
        let mut found = false;
        self.around(centroid(mesh, tri), |c| found |= cells.contains(&c));
        found
    }

    /// Visit the cell of `p` and its 26 neighbours, own cell first.
    fn around(&self, p: Vec3, mut f: impl FnMut([usize; 3])) {
        let c = self.cell_of(p);
        f(c);
        for dz in -1i64..=1 {
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    if (dx, dy, dz) == (0, 0, 0) {
                        continue;
                    }
                    let q = [dx, dy, dz];
                    let n: Option<Vec<usize>> = (0..3)
                        .map(|a| {
                            let v = c[a] as i64 + q[a];
                            (v >= 0 && (v as usize) < self.dims[a]).then_some(v as usize)
                        })
                        .collect();
                    if let Some(n) = n {
                        f([n[0], n[1], n[2]]);
                    }
                }
            }
        }
    }

    /// The directions filed near triangle `tri` (at most
    /// [`DIRECTIONS_PER_TRIANGLE`], its own cell's first).
    pub fn near(&self, mesh: &TriangleMesh, tri: usize) -> Vec<Vec3> {
        let mut out = Vec::new();
        self.around(centroid(mesh, tri), |c| {
            if let Some(list) = self.cells.get(&c) {
                for &d in list {
                    if out.len() < DIRECTIONS_PER_TRIANGLE {
                        out.push(d);
                    }
                }
            }
        });
        out
    }

    /// A direction filed near triangle `tri` along which a ray from one of
    /// `points` sample points (centroid first) escapes, from the face the
    /// direction leaves.
    pub fn try_near(
        &self,
        mesh: &TriangleMesh,
        accel: &dyn Accel,
        tri: usize,
        points: u32,
        seed: u64,
        beam: f32,
    ) -> Option<Vec3> {
        let dirs = self.near(mesh, tri);
        if dirs.is_empty() {
            return None;
        }
        let mut rng = Pcg32::with_stream(seed, tri as u64);
        on_surface(mesh, tri, points, &mut rng, |p, n, _| {
            for &d in &dirs {
                let cos = d.dot(n);
                if cos.abs() < MIN_FACE_COSINE {
                    continue;
                }
                let face = if cos > 0.0 { n } else { -n };
                let origin = off_surface(mesh, tri, p, face);
                if beam_escapes(accel, origin, d, beam) {
                    return Some(d);
                }
            }
            None
        })
    }
}

impl SharedEscapes {
    /// File the escapes `found` (triangle, direction) and label their
    /// triangles visible in `labels`; then let every unlabelled triangle
    /// (but those `skip` names) near a cell that received a direction try
    /// the directions near it ([`Self::try_near`] with up to `points` sample
    /// points and `beam`), file what escapes, and repeat until a pass finds
    /// nothing (at most [`MAX_SHARING_PASSES`] passes, and no pass that
    /// would take the rays past `max_rays`; then [`Spread::cut_short`]).
    /// Parallel over triangles.
    #[allow(clippy::too_many_arguments)]
    pub fn spread(
        &mut self,
        mesh: &TriangleMesh,
        accel: &dyn Accel,
        labels: &mut [bool],
        skip: &(dyn Fn(usize) -> bool + Sync),
        mut found: Vec<(usize, Vec3)>,
        points: u32,
        seed: u64,
        beam: f32,
        max_rays: Option<u64>,
    ) -> Spread {
        let mut out = Spread::default();
        let points = points.clamp(1, SHARING_POINTS);
        loop {
            let mut change = 0;
            for &(t, d) in &found {
                self.add(mesh, t, d);
                if !labels[t] {
                    labels[t] = true;
                    change += 1;
                }
            }
            if out.passes == 0 {
                out.direct = change;
            } else {
                out.by_sharing += change;
            }
            let cells = self.take_changed();
            if cells.is_empty() || out.passes == MAX_SHARING_PASSES {
                return out;
            }
            let near: Vec<usize> = (0..labels.len())
                .filter(|&t| !labels[t] && !skip(t) && self.near_any(mesh, t, &cells))
                .collect();
            let cost = near.len() as u64 * u64::from(points) * DIRECTIONS_PER_TRIANGLE as u64;
            if max_rays.is_some_and(|m| out.rays + cost > m) {
                out.cut_short = true;
                return out;
            }
            let pass_seed = seed ^ ((out.passes as u64 + 1) << 32);
            let this = &*self;
            found = near
                .par_iter()
                .with_min_len(16)
                .filter_map(|&t| {
                    this.try_near(mesh, accel, t, points, pass_seed, beam)
                        .map(|d| (t, d))
                })
                .collect();
            out.rays += cost;
            out.passes += 1;
        }
    }
}

fn centroid(mesh: &TriangleMesh, tri: usize) -> Vec3 {
    let [a, b, c] = mesh.triangle(tri);
    (a + b + c) / 3.0
}
