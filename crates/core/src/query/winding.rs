//! Generalized winding number (Jacobson, Kavan and Sorkine-Hornung 2013,
//! "Robust inside-outside segmentation using generalized winding numbers")
//! with the hierarchical far-field approximation of Barill, Dickson,
//! Schmidt, Levin and Jacobson 2018 ("Fast winding numbers for soups and
//! clouds").
//!
//! The winding number of a point `q` is the signed solid angle the surface
//! subtends at `q`, over `4π`: each triangle contributes its solid angle
//! (Van Oosterom and Strackee 1983: `tan(Ω/2) = a·(b×c) / (|a||b||c| +
//! (a·b)|c| + (b·c)|a| + (c·a)|b|)` with `a, b, c` its corners relative to
//! `q`), positive when `q` sees the triangle's back (inside a mesh whose
//! triangles are counter-clockwise seen from outside). It is 1 inside and 0
//! outside a closed surface, and degrades gracefully where the surface is
//! open, duplicated or self-intersecting: it is a harmonic function that
//! jumps by one across each sheet, so a hole shifts it smoothly, a
//! duplicated triangle adds a local ±1 only right at that triangle, and
//! thresholding at ½ still separates inside from outside.
//!
//! Far from a cluster of triangles, the cluster's solid angle is expanded
//! about its area-weighted centroid `p̃` (Barill et al.'s Taylor series of
//! the kernel `f(y) = (y - q) / |y - q|³`, whose flux through a surface is
//! its solid angle): with `x = p̃ - q`, `r = |x|` and each triangle's area
//! vector `A_t = ½(b-a)×(c-a)`,
//! `Ω ≈ Σ_i N_i f_i(p̃) + Σ_ij T_ij ∂_j f_i(p̃) + ½ Σ_ijk C_ijk ∂_j ∂_k f_i(p̃)`
//! with the moments `N = Σ A_t`, `T_ij = Σ A_t,i ∫(y - p̃)_j dA / a_t` and
//! `C_ijk = Σ A_t,i ∫(y - p̃)_j (y - p̃)_k dA / a_t`, integrated exactly over
//! each flat triangle (the terms up to Barill et al.'s "order 2"). A child
//! of a point tree's node (`super::point_tree`) whose triangles all lie
//! within `ρ` of `p̃` is taken in this form when `r > β·ρ` (β = 2 by
//! default, as in the paper); otherwise it is opened, and leaves are
//! summed exactly. The error falls as `(ρ / r)⁴`; at β = 2 the tests find
//! it below 1% of a unit winding number, far from the ½ threshold.
//!
//! Occupancy first counts instead of summing: a surface `M` closed by a
//! cap `C` ([`super::closing`]) has an integer winding number, the signed
//! count of one ray's crossings, so `w_M = crossings_{M ∪ C} - w_C`, one
//! ray through the ray-casting tree plus the cap's solid angle (summed as
//! above, over the cap's own tree). Each crossing is classified with its
//! rounding-error bounds ([`crate::tri::moller::Moller::crossing`]); when
//! one is too close to an edge, a corner or the point to be sure of, two
//! other rays are tried, and if they are unsure too the surface's solid
//! angles are summed: over every triangle when a batch has only a few such
//! points ([`SUM_DIRECTLY`]) and the batches before have not summed many
//! ([`SUM_DIRECTLY_IN_ALL`]), so that they need no point tree, and through
//! the tree otherwise. Occupancy needs only the side of ½, so it sums at a
//! coarser accuracy first ([`COARSE_BETA`]) and again at the default only
//! close to ½.
//!
//! The far field is written lane by lane over a node's eight children and
//! compiled for AVX2 where the CPU has it, so that the eight children are
//! one vector; leaves use an inline arctangent good to 3·10⁻⁷ radians.

use super::batch::answer_coherent;
use super::moments::SlotMoments;
use super::point_tree::PointTree;
use super::surface_bvh::{stack_of, SurfaceBvh, EMPTY, SMALL_STACK, WIDTH};
use crate::mesh::TriangleMesh;
use glam::{DVec3, Vec3};

/// The accuracy occupancy decides at first: a child is approximated when
/// the point is farther than 1.25 times its radius from its centre. On
/// the 2CylinderEngine's cap, at 4,000 points uniform in its box, the
/// counted winding number's largest error against the `f64` sum was
/// 2.7·10⁻³ at this accuracy (BENCHMARKS.md), against 2.7·10⁻⁴ at
/// [`DEFAULT_BETA`]; occupancy only asks on which side of ½ it lies.
pub const COARSE_BETA: f32 = 1.25;

/// How far from ½ a winding number found at [`COARSE_BETA`] must be for
/// occupancy to take it: twenty times the largest error measured there.
pub const COARSE_MARGIN: f32 = 0.05;

/// At most this many points whose crossings are too close to an edge to
/// count are summed over every triangle rather than through the point
/// tree, when the tree and its moments are not made yet. Making them costs
/// about as much as summing 65-90 points together in one pass over the
/// triangles (the full dragon and the 2CylinderEngine, BENCHMARKS.md; a
/// pass for only one or two points costs more per point, its loads of the
/// triangles unshared); a batch that sums at most this many pays at most
/// about a fifth of that, and a later batch may still make the tree.
pub const SUM_DIRECTLY: usize = 16;

/// At most this many points in all, over every batch, are summed over
/// every triangle before the point tree is made. Batches that leave one or
/// two points open pay a whole pass over the triangles for each (on the
/// 2CylinderEngine about a tenth of making the tree, BENCHMARKS.md), so a
/// stream of them makes the tree once their sums have cost two to three
/// times what the tree does, and no call after that pays for a pass
/// (renting until the rent reaches the price).
pub const SUM_DIRECTLY_IN_ALL: usize = 32;

/// Barill et al.'s default accuracy: a child is approximated when the
/// query point is farther than twice its radius from its centre.
pub const DEFAULT_BETA: f32 = 2.0;

/// Solid angle of triangle `(a, b, c)` seen from the origin (Van Oosterom
/// and Strackee 1983), in `f32`.
#[inline(always)]
fn solid_angle32(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * atan2(num, den)
}

/// `y.atan2(x)` to within 3·10⁻⁷ radians, inline: the arctangent of the
/// smaller over the larger magnitude (in [0, 1]) by Hastings' polynomial
/// (Abramowitz and Stegun 1964, 4.4.49, error 2·10⁻⁸), then moved to its
/// octant. Zero for `(0, 0)`, like `atan2`; for finite arguments.
#[inline(always)]
fn atan2(y: f32, x: f32) -> f32 {
    const C: [f32; 8] = [
        -0.333_331_45,
        0.199_935_5,
        -0.142_089,
        0.106_562_64,
        -0.075_289_64,
        0.042_909_614,
        -0.016_165_737,
        0.002_866_225_7,
    ];
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let t = if hi > 0.0 { lo / hi } else { lo };
    let t2 = t * t;
    let mut p = C[7];
    for &c in C[..7].iter().rev() {
        p = p * t2 + c;
    }
    let mut r = t + t * t2 * p;
    if ay > ax {
        r = std::f32::consts::FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = std::f32::consts::PI - r;
    }
    if y < 0.0 {
        -r
    } else {
        r
    }
}

/// Solid angle of triangle `(a, b, c)` seen from `q`, in `f64`.
pub fn solid_angle64(q: DVec3, tri: &[DVec3; 3]) -> f64 {
    let (a, b, c) = (tri[0] - q, tri[1] - q, tri[2] - q);
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * num.atan2(den)
}

/// The far-field solid angles of a node's eight children seen from `q`
/// (the expansion of the module documentation with `x = p̃ - q`,
/// `d2 = |x|²`), summed over the children farther than `beta2` times
/// their squared radius, which are marked in `far`. Written lane by lane
/// over the structure of arrays so that the eight children compile to
/// SIMD.
#[inline(always)]
fn far_fields(m: &SlotMoments, q: Vec3, beta2: f32, far: &mut [bool; WIDTH]) -> f32 {
    let (t, h) = (&m.tensor, &m.hessian);
    let mut terms = [0.0f32; WIDTH];
    for k in 0..WIDTH {
        let x = [
            m.center[0][k] - q.x,
            m.center[1][k] - q.y,
            m.center[2][k] - q.z,
        ];
        let d2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
        let is_far = d2 > m.radius[k] * m.radius[k] * beta2;
        far[k] = is_far;
        // In the unit direction `n = x / r` and the ratio `ρ = R / r` of
        // the child's radius to the distance, with the moments stored over
        // powers of `R`: products of powers of `x` would overflow f32 for
        // points far from large meshes, and `1/r⁷` underflow.
        let inv1 = (1.0 / d2).sqrt();
        let n = [x[0] * inv1, x[1] * inv1, x[2] * inv1];
        let rho = m.radius[k] * inv1;
        let (rho2, rho3) = (rho * rho, rho * rho * rho);
        let rho4 = rho2 * rho2;
        // Zeroth and first order: N·n / r² + (tr T - 3 nᵀTn) / r³, the
        // moments here over R² and R³.
        let dot = n[0] * m.normal[0][k] + n[1] * m.normal[1][k] + n[2] * m.normal[2][k];
        let trace = t[0][0][k] + t[1][1][k] + t[2][2][k];
        let tn = |i: usize| t[i][0][k] * n[0] + t[i][1][k] * n[1] + t[i][2][k] * n[2];
        let ntn = n[0] * tn(0) + n[1] * tn(1) + n[2] * tn(2);
        // Second order: ½ Σ C_ijk ∂j∂k f_i, with
        // ∂j∂k f_i = (-3(δij n_k + δik n_j + δjk n_i) + 15 n_i n_j n_k) / r⁴;
        // `C_i` is stored over R⁴ as `xx, yy, zz, xy, xz, yz`.
        let c = |i: usize, jk: usize| h[i][jk][k];
        // Σ_ij C_iij n_j: row i of C_i against n.
        let diag = c(0, 0) * n[0]
            + c(0, 3) * n[1]
            + c(0, 4) * n[2]
            + c(1, 3) * n[0]
            + c(1, 1) * n[1]
            + c(1, 5) * n[2]
            + c(2, 4) * n[0]
            + c(2, 5) * n[1]
            + c(2, 2) * n[2];
        let tr = |i: usize| c(i, 0) + c(i, 1) + c(i, 2);
        let tr_n = n[0] * tr(0) + n[1] * tr(1) + n[2] * tr(2);
        let quad = |i: usize| {
            c(i, 0) * n[0] * n[0]
                + c(i, 1) * n[1] * n[1]
                + c(i, 2) * n[2] * n[2]
                + 2.0 * (c(i, 3) * n[0] * n[1] + c(i, 4) * n[0] * n[2] + c(i, 5) * n[1] * n[2])
        };
        let cubic = n[0] * quad(0) + n[1] * quad(1) + n[2] * quad(2);
        let second = 0.5 * (-3.0 * (2.0 * diag + tr_n) + 15.0 * cubic) * rho4;
        let term = dot * rho2 + (trace - 3.0 * ntn) * rho3 + second;
        // Near and unused lanes (whose terms may be infinite) give zero.
        terms[k] = if is_far { term } else { 0.0 };
    }
    terms.iter().sum()
}

impl SurfaceBvh {
    /// The generalized winding number of `q` with Barill et al.'s far-field
    /// approximation at accuracy `beta` (a child is approximated when `q` is
    /// farther than `beta` times its radius from its centre; `beta = inf`
    /// gives the exact sum). NaN for a point that is not finite; 0 for an
    /// empty mesh.
    pub fn winding_number_with(&self, q: Vec3, beta: f32) -> f32 {
        self.winding_at_scale(self.scale.point(q), beta)
    }

    /// [`SurfaceBvh::winding_number_with`] of `q` at
    /// [`SurfaceBvh::scale`].
    fn winding_at_scale(&self, q: Vec3, beta: f32) -> f32 {
        if !q.is_finite() {
            return f32::NAN;
        }
        let tree = self.winding_tree();
        if tree.nodes.is_empty() {
            return 0.0;
        }
        let moments = &tree.moments().0;
        #[cfg(target_arch = "x86_64")]
        if crate::accel::bvh::avx2() {
            // SAFETY: the CPU has AVX2 and FMA.
            return unsafe { tree.winding_avx2(moments, q, beta) };
        }
        tree.winding(moments, q, beta)
    }

    /// [`SurfaceBvh::winding_number_with`] at [`DEFAULT_BETA`].
    pub fn winding_number(&self, q: Vec3) -> f32 {
        self.winding_number_with(q, DEFAULT_BETA)
    }

    /// The winding number of `q` counted rather than summed: the signed
    /// crossings of one ray through the surface and the cap that closes it,
    /// less the cap's winding number ([`super::closing`]); exact for a
    /// closed surface, and as accurate as the cap's solid angle otherwise.
    /// None when a crossing lies within rounding error of an edge, a
    /// corner or `q` itself, or `q` is not finite; always None for a soup
    /// whose cap would hold more than a quarter as many triangles as it
    /// (counting would cost more than summing).
    pub fn winding_number_counted(&self, q: Vec3) -> Option<f32> {
        if self.mesh.indices.is_empty() {
            return q.is_finite().then_some(0.0);
        }
        let q = self.scale.point(q);
        let (tree, cap_tree, cap) = self.closed_trees();
        let count = cap_tree.signed_crossings(tree, q)?;
        Some(count as f32 - cap.map_or(0.0, |c| c.winding_number(q)))
    }

    /// Occupancy: true when `q` is inside the surface, i.e. its generalized
    /// winding number is at least ½. Unlike the parity of one ray's
    /// crossings, this is right on open meshes (a ray leaving through a hole
    /// crosses the surface an even number of times from inside), duplicated
    /// and overlapping triangles (one crossing counted twice flips the
    /// parity) and self-intersecting meshes; the tests show such cases.
    /// False for a point that is not finite.
    ///
    /// The winding number is counted exactly where it can be: the signed
    /// crossings of one ray through the surface and the cap that closes
    /// it, less the cap's own winding number ([`super::closing`]). When a
    /// crossing lies within rounding error of an edge, a corner or `q`
    /// itself, the solid angles are summed instead
    /// ([`SurfaceBvh::winding_number`]).
    ///
    /// The solid angles (of the cap, or of the surface when summing) are
    /// first approximated coarsely ([`COARSE_BETA`]), and again at
    /// [`DEFAULT_BETA`] only where the coarse winding number is within
    /// [`COARSE_MARGIN`] of ½.
    pub fn is_inside(&self, q: Vec3) -> bool {
        self.inside_if_counted(q)
            .unwrap_or_else(|| self.inside_summed(q))
    }

    /// [`SurfaceBvh::is_inside`] where the winding number can be counted
    /// (and for points that are not finite); `None` where it must be
    /// summed.
    fn inside_if_counted(&self, q: Vec3) -> Option<bool> {
        let q = self.scale.point(q);
        if !q.is_finite() {
            return Some(false);
        }
        let (tree, cap_tree, cap) = self.closed_trees();
        let n = cap_tree.signed_crossings(tree, q)?;
        // The cap's tree takes points at this tree's scale, at which it was
        // made.
        Some(half_or_more(|beta| {
            n as f32 - cap.map_or(0.0, |c| c.winding_number_with(q, beta))
        }))
    }

    /// [`SurfaceBvh::is_inside`] by the summed winding number.
    fn inside_summed(&self, q: Vec3) -> bool {
        let q = self.scale.point(q);
        q.is_finite() && half_or_more(|beta| self.winding_at_scale(q, beta))
    }

    /// The insides that `counted` leaves open (`None`) summed, the others
    /// as counted. The moments that summing needs are made here, outside
    /// any parallel loop, and only when some point needs them: a closed
    /// surface's crossings are sure at all but points within rounding error
    /// of an edge.
    fn summed_where_open(&self, points: &[Vec3], counted: &[Option<bool>]) -> Vec<bool> {
        let mut inside: Vec<bool> = counted.iter().map(|c| c.unwrap_or(false)).collect();
        let open: Vec<usize> = (0..points.len())
            .filter(|&i| counted[i].is_none())
            .collect();
        if open.is_empty() {
            return inside;
        }
        // A few points are summed over every triangle, when the point tree
        // and its moments are not made yet and would cost more; only the
        // points whose exact sum lies near ½ are left to the tree, so that
        // each answer is the one `is_inside` gives.
        let mut open = open;
        if open.len() <= SUM_DIRECTLY
            && !self.winding_tree_made()
            && self.may_sum_directly(open.len())
        {
            let at: Vec<Vec3> = open.iter().map(|&i| self.scale.point(points[i])).collect();
            let sums = self.winding_numbers_exact(&at);
            let mut near_half = Vec::new();
            for (&i, w) in open.iter().zip(sums) {
                if (w - 0.5).abs() > COARSE_MARGIN {
                    inside[i] = w >= 0.5;
                } else {
                    near_half.push(i);
                }
            }
            if near_half.is_empty() {
                return inside;
            }
            open = near_half;
        }
        self.winding_tree();
        let at: Vec<Vec3> = open.iter().map(|&i| points[i]).collect();
        let mut summed = vec![false; at.len()];
        answer_coherent(&at, &mut summed, |p, _: &mut ()| self.inside_summed(p));
        for (&i, s) in open.iter().zip(summed) {
            inside[i] = s;
        }
        inside
    }

    /// Whether `n` more points may be summed over every triangle within
    /// [`SUM_DIRECTLY_IN_ALL`]; if so they are counted as summed.
    fn may_sum_directly(&self, n: usize) -> bool {
        use std::sync::atomic::Ordering;
        self.summed_directly
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |done| {
                (done + n <= SUM_DIRECTLY_IN_ALL).then_some(done + n)
            })
            .is_ok()
    }

    /// Whether the point tree and its winding-number moments are made.
    pub(crate) fn winding_tree_made(&self) -> bool {
        self.points.get().is_some_and(|p| p.moments.get().is_some())
    }

    /// The exact winding numbers of `at` (points at [`SurfaceBvh::scale`],
    /// finite), each triangle's solid angle summed, without the point tree:
    /// one parallel pass over the triangles for all the points.
    fn winding_numbers_exact(&self, at: &[Vec3]) -> Vec<f32> {
        use rayon::prelude::*;
        let mesh = &self.mesh;
        let sums = (0..mesh.num_triangles())
            .into_par_iter()
            .with_min_len(4096)
            .fold(
                || vec![0.0f64; at.len()],
                |mut acc, t| {
                    let [a, b, c] = mesh.triangle(t);
                    for (s, &q) in acc.iter_mut().zip(at) {
                        *s += solid_angle32(a - q, b - q, c - q) as f64;
                    }
                    acc
                },
            )
            .reduce(
                || vec![0.0f64; at.len()],
                |mut x, y| {
                    x.iter_mut().zip(y).for_each(|(x, y)| *x += y);
                    x
                },
            );
        sums.iter()
            .map(|s| (s / (4.0 * std::f64::consts::PI)) as f32)
            .collect()
    }

    /// Signed distance: the unsigned distance, negative inside (by
    /// [`SurfaceBvh::is_inside`], the winding number), as Open3D's
    /// `compute_signed_distance`. NaN for a point that is not finite.
    pub fn signed_distance(&self, q: Vec3) -> f32 {
        self.signed_distance_hinted(q, &mut None)
    }

    /// [`SurfaceBvh::signed_distance`] with the distance search bounded
    /// from the start by triangle `hint`, as in [`SurfaceBvh::distances`].
    fn signed_distance_hinted(&self, q: Vec3, hint: &mut Option<usize>) -> f32 {
        let d = self.distance_hinted(q, hint);
        signed(d, !d.is_nan() && self.is_inside(q))
    }

    /// Make what occupancy needs: the ray-casting trees of the surface and
    /// its closing cap, and the point tree with its winding-number moments
    /// when the crossings are not counted (otherwise those are made only
    /// if some point's crossings are too close to an edge to count).
    pub(crate) fn inside_trees(&self) {
        if !self.closed_trees().1.countable() {
            self.winding_tree();
        }
    }

    /// Make what signed distances need: the point tree and
    /// [`SurfaceBvh::inside_trees`], side by side, since neither build
    /// keeps both cores busy throughout.
    pub(crate) fn signed_trees(&self) {
        if self.has_point_tree() {
            // Nothing to overlap: a join from outside the pool would hand
            // even a one-point query to a pool's thread and back.
            self.inside_trees();
        } else {
            rayon::join(|| self.points(), || self.inside_trees());
        }
    }

    /// [`SurfaceBvh::winding_number`] for many points, in parallel, in
    /// Morton order so that neighbouring points share cached nodes.
    pub fn winding_numbers(&self, points: &[Vec3], out: &mut [f32]) {
        self.winding_numbers_with(points, DEFAULT_BETA, out)
    }

    /// [`SurfaceBvh::winding_number_with`] at accuracy `beta` for many
    /// points, as [`SurfaceBvh::winding_numbers`]; the point tree and its
    /// moments are made before the parallel loop.
    pub fn winding_numbers_with(&self, points: &[Vec3], beta: f32, out: &mut [f32]) {
        assert_eq!(points.len(), out.len(), "one result per point");
        self.winding_tree();
        answer_coherent(points, out, |p, _: &mut ()| {
            self.winding_number_with(p, beta)
        });
    }

    /// [`SurfaceBvh::is_inside`] for many points, in parallel, in Morton
    /// order.
    pub fn inside_batch(&self, points: &[Vec3], out: &mut [bool]) {
        assert_eq!(points.len(), out.len(), "one result per point");
        self.closed_trees();
        let mut counted = vec![None; points.len()];
        answer_coherent(points, &mut counted, |p, _: &mut ()| {
            self.inside_if_counted(p)
        });
        out.copy_from_slice(&self.summed_where_open(points, &counted));
    }

    /// [`SurfaceBvh::signed_distance`] for many points, in parallel, the
    /// distances searched as in [`SurfaceBvh::distances`].
    pub fn signed_distances(&self, points: &[Vec3], out: &mut [f32]) {
        assert_eq!(points.len(), out.len(), "one result per point");
        self.signed_trees();
        let mut first = vec![(0.0f32, None); points.len()];
        answer_coherent(points, &mut first, |p, hint| {
            let d = self.distance_hinted(p, hint);
            (
                d,
                if d.is_nan() {
                    Some(false)
                } else {
                    self.inside_if_counted(p)
                },
            )
        });
        let counted: Vec<Option<bool>> = first.iter().map(|f| f.1).collect();
        let inside = self.summed_where_open(points, &counted);
        for ((o, (d, _)), inside) in out.iter_mut().zip(first).zip(inside) {
            *o = signed(d, inside);
        }
    }
}

impl PointTree {
    /// [`SurfaceBvh::winding_number_with`]'s walk compiled for AVX2 and
    /// FMA, so that a node's eight far fields are one vector each.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn winding_avx2(&self, moments: &[SlotMoments], q: Vec3, beta: f32) -> f32 {
        self.winding(moments, q, beta)
    }

    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lanes of structure-of-arrays
    fn winding(&self, moments: &[SlotMoments], q: Vec3, beta: f32) -> f32 {
        let beta2 = beta * beta;
        let mut w = 0.0f32;
        let (mut small, mut big) = ([0u32; SMALL_STACK], Vec::new());
        let stack = stack_of(&mut small, &mut big, self.stack_need);
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let ni = stack[sp] as usize;
            let (node, m) = (&self.nodes[ni], &moments[ni]);
            let mut far = [false; WIDTH];
            w += far_fields(m, q, beta2, &mut far);
            for k in 0..WIDTH {
                if far[k] || node.child[k] == EMPTY {
                    continue;
                }
                if node.count[k] > 0 {
                    let first = node.first[k] as usize;
                    for t in &self.tris[first..first + node.count[k] as usize] {
                        w += solid_angle32(t[0] - q, t[1] - q, t[2] - q);
                    }
                } else if sp < stack.len() {
                    stack[sp] = node.child[k];
                    sp += 1;
                }
            }
        }
        w / (4.0 * std::f32::consts::PI)
    }
}

/// Whether the winding number that `winding(beta)` gives at accuracy `beta`
/// is at least ½: at [`COARSE_BETA`] first, again at [`DEFAULT_BETA`] only
/// within [`COARSE_MARGIN`] of ½.
fn half_or_more(winding: impl Fn(f32) -> f32) -> bool {
    let w = winding(COARSE_BETA);
    if (w - 0.5).abs() > COARSE_MARGIN {
        return w >= 0.5;
    }
    winding(DEFAULT_BETA) >= 0.5
}

/// The distance `d`, negative when `inside`.
fn signed(d: f32, inside: bool) -> f32 {
    if inside {
        -d
    } else {
        d
    }
}

/// Reference: the exact winding number of `q` in `f64`, summing every
/// triangle's solid angle.
pub fn winding_number_brute(mesh: &TriangleMesh, q: DVec3) -> f64 {
    (0..mesh.num_triangles())
        .map(|t| solid_angle64(q, &mesh.triangle(t).map(|c| c.as_dvec3())))
        .sum::<f64>()
        / (4.0 * std::f64::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::{atan2, winding_number_brute, SurfaceBvh, SUM_DIRECTLY, SUM_DIRECTLY_IN_ALL};
    use crate::icosphere::Icosphere;
    use crate::mesh::TriangleMesh;
    use crate::rng::Pcg32;
    use glam::Vec3;

    /// Two nested unit and half-unit icospheres, and a source of points on
    /// the inner one (its triangles' centroids): within rounding error of a
    /// crossing on every ray, so their crossings cannot be counted; their
    /// winding number is 1½.
    fn nested_spheres() -> (TriangleMesh, impl FnMut(&mut Pcg32) -> Vec3) {
        let sphere = Icosphere::new(3);
        let mut positions = sphere.positions.clone();
        let mut indices = sphere.indices.clone();
        let n = positions.len() as u32;
        positions.extend(sphere.positions.iter().map(|&p| p * 0.5));
        indices.extend(sphere.indices.iter().map(|t| t.map(|i| i + n)));
        let mesh = TriangleMesh::new(positions, indices);
        let inner = mesh.clone();
        let first = sphere.indices.len();
        let on_inner = move |rng: &mut Pcg32| {
            let t = inner.triangle(first + rng.below(first as u32) as usize);
            (t[0] + t[1] + t[2]) / 3.0
        };
        (mesh, on_inner)
    }

    /// Points on the inner of two nested spheres cannot be counted, so
    /// occupancy sums them. A few are summed over every triangle without
    /// making the point tree, more through the tree; either way each answer
    /// is `is_inside`'s and the `f64` sum's, and the points counted keep
    /// theirs.
    #[test]
    fn points_that_cannot_be_counted_are_summed_directly_or_through_the_tree() {
        let (mesh, mut on_inner) = nested_spheres();
        let mut rng = Pcg32::new(9);
        for on_surface in [SUM_DIRECTLY, SUM_DIRECTLY + 1, 3 * SUM_DIRECTLY] {
            let mut points: Vec<Vec3> = (0..on_surface).map(|_| on_inner(&mut rng)).collect();
            points.extend((0..200).map(|_| rng.in_box(Vec3::splat(-1.2), Vec3::splat(1.2))));
            let bvh = SurfaceBvh::build(&mesh);
            let mut batch = vec![false; points.len()];
            bvh.inside_batch(&points, &mut batch);
            let counted = points
                .iter()
                .filter(|&&p| bvh.winding_number_counted(p).is_some())
                .count();
            assert_eq!(counted, 200, "{on_surface} points on the inner sphere");
            assert_eq!(
                bvh.winding_tree_made(),
                on_surface > SUM_DIRECTLY,
                "{on_surface} points on the inner sphere"
            );
            for (p, &inside) in points.iter().zip(&batch) {
                let w = winding_number_brute(&mesh, p.as_dvec3());
                assert_eq!(inside, w >= 0.5, "at {p}: f64 winding number {w}");
                assert_eq!(inside, bvh.is_inside(*p), "at {p}");
            }
        }
    }

    /// Batches that each leave a few points uncountable sum them over
    /// every triangle until [`SUM_DIRECTLY_IN_ALL`] have been, then make
    /// the point tree; every answer is the `f64` winding number's side.
    #[test]
    fn many_small_batches_make_the_tree_once_their_direct_sums_add_up() {
        let (mesh, mut on_inner) = nested_spheres();
        let bvh = SurfaceBvh::build(&mesh);
        let mut rng = Pcg32::new(10);
        let per_batch = 5;
        let mut summed = 0;
        for batch in 0..2 * SUM_DIRECTLY_IN_ALL / per_batch {
            let mut points: Vec<Vec3> = (0..per_batch).map(|_| on_inner(&mut rng)).collect();
            points.extend((0..20).map(|_| rng.in_box(Vec3::splat(-1.2), Vec3::splat(1.2))));
            let mut inside = vec![false; points.len()];
            bvh.inside_batch(&points, &mut inside);
            let open = points
                .iter()
                .filter(|&&p| bvh.winding_number_counted(p).is_none())
                .count();
            assert_eq!(open, per_batch, "batch {batch}");
            summed += open;
            assert_eq!(
                bvh.winding_tree_made(),
                summed > SUM_DIRECTLY_IN_ALL,
                "batch {batch}: {summed} points left open so far"
            );
            for (p, &inside) in points.iter().zip(&inside) {
                let w = winding_number_brute(&mesh, p.as_dvec3());
                assert_eq!(inside, w >= 0.5, "at {p}: f64 winding number {w}");
            }
        }
        assert!(bvh.winding_tree_made());
    }

    /// The inline arctangent against `f64`'s over every octant, the axes,
    /// the origin and a wide range of magnitudes.
    #[test]
    fn inline_atan2_is_within_its_bound() {
        let mut rng = Pcg32::new(11);
        let mut worst = 0.0f64;
        let mut check = |y: f32, x: f32| {
            let err = (atan2(y, x) as f64 - (y as f64).atan2(x as f64)).abs();
            assert!(err <= 3e-7, "atan2({y}, {x}) off by {err}");
            worst = worst.max(err);
        };
        for _ in 0..1_000_000 {
            let scale = 10f32.powi(rng.below(13) as i32 - 6);
            let y = (rng.next_f32() * 2.0 - 1.0) * scale;
            let x = (rng.next_f32() * 2.0 - 1.0) * scale;
            check(y, x);
        }
        for (y, x) in [
            (0.0, 0.0),
            (1.0, 0.0),
            (-1.0, 0.0),
            (0.0, -1.0),
            (0.0, 1.0),
            (1.0, 1.0),
        ] {
            check(y, x);
        }
        assert!(
            worst > 0.0,
            "a bound that is never approached tests nothing"
        );
    }
}
