//! Far-field moments of a [`super::point_tree::PointTree`]'s nodes for the
//! fast winding number (Barill et al. 2018): per child, the area-weighted
//! centroid, the radius about it, and the first three terms of the dipole
//! expansion.

use super::surface_node::{SurfaceNode, EMPTY, WIDTH};
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// The pairs `(j, k)` of the symmetric second moments, in storage order.
const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// The far-field data of each node's eight children (structure of arrays,
/// parallel to the nodes): area-weighted centroid, radius `R` about it, and
/// the expansion's moments over powers of `R` (the area vector over `R²`,
/// `T` over `R³`, `C` over `R⁴`), which keeps them near 1 at any scale.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct SlotMoments {
    pub(super) center: [[f32; WIDTH]; 3],
    pub(super) radius: [f32; WIDTH],
    pub(super) normal: [[f32; WIDTH]; 3],
    /// `T[i][j]`.
    pub(super) tensor: [[[f32; WIDTH]; 3]; 3],
    /// `C[i][jk]` for `jk` in `xx, yy, zz, xy, xz, yz`.
    pub(super) hessian: [[[f32; WIDTH]; 6]; 3],
}

/// The moments of every node of a [`super::point_tree::PointTree`].
pub(crate) struct Moments(pub(super) Vec<SlotMoments>);

impl Moments {
    /// Bytes held.
    pub(super) fn bytes(&self) -> usize {
        self.0.len() * std::mem::size_of::<SlotMoments>()
    }

    /// The moments of every child of every node, in `f64` from the
    /// triangles below it (each triangle is summed once per level above
    /// it), stored in `f32` over the powers of the child's radius.
    #[allow(clippy::needless_range_loop)] // lanes of structure-of-arrays
    pub(super) fn build(nodes: &[SurfaceNode], leaf_tris: &[[Vec3; 3]]) -> Moments {
        let nodes = nodes
            .par_iter()
            .map(|node| {
                let mut m = SlotMoments {
                    center: [[0.0; WIDTH]; 3],
                    radius: [f32::INFINITY; WIDTH],
                    normal: [[0.0; WIDTH]; 3],
                    tensor: [[[0.0; WIDTH]; 3]; 3],
                    hessian: [[[0.0; WIDTH]; 6]; 3],
                };
                for k in 0..WIDTH {
                    if node.child[k] == EMPTY {
                        continue;
                    }
                    let (lo, hi) = (
                        node.first[k] as usize,
                        (node.first[k] + node.total[k]) as usize,
                    );
                    let tris = &leaf_tris[lo..hi];
                    let (mut nsum, mut csum, mut asum) = (DVec3::ZERO, DVec3::ZERO, 0.0f64);
                    for t in tris {
                        let [a, b, c] = t.map(|v| v.as_dvec3());
                        let av = 0.5 * (b - a).cross(c - a);
                        nsum += av;
                        csum += av.length() * (a + b + c) / 3.0;
                        asum += av.length();
                    }
                    let center = if asum > 0.0 {
                        csum / asum
                    } else {
                        tris.iter().flatten().map(|v| v.as_dvec3()).sum::<DVec3>()
                            / (3 * tris.len()) as f64
                    };
                    let mut r2 = 0.0f64;
                    let mut tensor = [[0.0f64; 3]; 3];
                    let mut hessian = [[0.0f64; 6]; 3];
                    for t in tris {
                        let [a, b, c] = t.map(|v| v.as_dvec3() - center);
                        r2 = r2
                            .max(a.length_squared())
                            .max(b.length_squared())
                            .max(c.length_squared());
                        let av = 0.5 * (b - a).cross(c - a);
                        let g = (a + b + c) / 3.0;
                        // ∫ y dA / area = g; ∫ y yᵀ dA / area = (Σ v vᵀ + 9 g gᵀ) / 12.
                        for i in 0..3 {
                            for j in 0..3 {
                                tensor[i][j] += av[i] * g[j];
                            }
                            for (jk, &(j, kk)) in PAIRS.iter().enumerate() {
                                let second = (a[j] * a[kk]
                                    + b[j] * b[kk]
                                    + c[j] * c[kk]
                                    + 9.0 * g[j] * g[kk])
                                    / 12.0;
                                hessian[i][jk] += av[i] * second;
                            }
                        }
                    }
                    // Rounded up so the f32 centre stays within the radius.
                    m.radius[k] = (r2.sqrt() * (1.0 + 1e-6)) as f32;
                    // Each order stored over its power of the radius, so
                    // that large meshes stay within f32 (a zero radius has
                    // zero moments).
                    let r = match m.radius[k] as f64 {
                        r if r > 0.0 && r.is_finite() => r,
                        _ => 1.0,
                    };
                    let (r2, r3, r4) = (r * r, r * r * r, r * r * r * r);
                    for i in 0..3 {
                        m.center[i][k] = center[i] as f32;
                        m.normal[i][k] = (nsum[i] / r2) as f32;
                        for j in 0..3 {
                            m.tensor[i][j][k] = (tensor[i][j] / r3) as f32;
                        }
                        for jk in 0..6 {
                            m.hessian[i][jk][k] = (hessian[i][jk] / r4) as f32;
                        }
                    }
                }
                m
            })
            .collect();
        Moments(nodes)
    }
}
