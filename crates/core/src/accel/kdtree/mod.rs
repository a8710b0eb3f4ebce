//! kd-trees: three builds (the SAH, Kim's (2013) split-plane heuristic and the
//! spatial median), one compact node layout, four traversals.
//!
//! Builds ([`KdSplit`]), all producing the same [`KdBuildNode`] tree:
//! - [`KdSplit::Sah`]: the surface area heuristic in O(N log N) with
//!   perfect splits and automatic termination (Wald & Havran 2006), [`sah`].
//! - [`KdSplit::Game`]: Kim's (2013) weighted split count / balance score
//!   `|front − back| · (20 − H) + splits · H`, cutting straddling triangles
//!   into pieces, [`game`].
//! - [`KdSplit::Median`]: the spatial median of the longest axis, the simple
//!   baseline.
//!
//! Layout: the compact 8-byte [`KdNode`], subtrees laid out breadth first,
//! leaves pointing into one triangle-index list; the triangles are
//! precomputed once each.
//!
//! Traversals, each an [`Accel`](crate::accel::Accel) generic over the
//! triangle test: [`KdStack`] (a fixed-size per-ray stack), [`KdRopes`]
//! (stackless with ropes and leaf boxes, Popov et al. 2007), [`KdRestart`]
//! and [`KdBacktrack`] (Foley & Sugerman 2005).
//!
//! Triangle references cover each triangle's tolerance band (see
//! [`crate::tri::MAX_EDGE_TOLERANCE`]): a leaf lists every triangle whose
//! band reaches into its cell, so a kd-tree reports exactly the hits brute
//! force reports, like the BVHs with their padded boxes.

/// The `Accel` impl every kd traversal shares: `traverse::<ANY>` answers
/// both queries, `extra_bytes` adds the traversal's own data to the stats.
macro_rules! kd_accel {
    ($name:ident, $self:ident => $extra:expr) => {
        impl<T: TriangleTest> Accel for $name<T> {
            fn intersect(&self, ray: &Ray) -> Option<Hit> {
                self.traverse::<false>(ray).0
            }

            fn occluded(&self, ray: &Ray) -> bool {
                self.traverse::<true>(ray).1
            }

            fn stats(&$self) -> AccelStats {
                $self.tree.stats_with($extra)
            }

            fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
                self.visit(enter, leaf)
            }
        }
    };
}

mod backtrack;
mod base;
mod clip;
pub mod game;
mod layout;
mod median;
mod refs;
mod restart;
mod ropes;
pub mod sah;
mod stack;
mod tree;

pub use backtrack::KdBacktrack;
pub use base::{build_tree, KdBuildInfo, KdTree};
pub use game::{build_game, cut_mesh, CutMesh, GameBuild, GameLeaf};
pub use layout::KdNode;
pub use restart::KdRestart;
pub use ropes::KdRopes;
pub use stack::KdStack;
pub use tree::{KdBuildNode, TreeShape};

use crate::aabb::Aabb;
use crate::mesh::TriangleMesh;
use glam::DVec3;
use rayon::prelude::*;

/// Deepest kd-tree the builds produce: traversal stacks hold this many
/// entries.
pub const MAX_KD_DEPTH: usize = 64;

/// How the split planes are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KdSplit {
    /// Surface area heuristic, O(N log N), perfect splits (Wald & Havran 2006).
    Sah,
    /// Kim's (2013) score with weight `H` in `0..=20`: 0 balances only, 20
    /// counts split triangles only.
    Game(u8),
    /// Middle of the cell's longest axis.
    Median,
}

impl KdSplit {
    /// The rule's name (`sah`, `median`, `game:H`), as `Display` writes it
    /// and `FromStr` reads it.
    pub fn name(self) -> String {
        match self {
            KdSplit::Sah => "sah".into(),
            KdSplit::Median => "median".into(),
            KdSplit::Game(h) => format!("game:{h}"),
        }
    }
}

impl std::fmt::Display for KdSplit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

/// Reads `sah`, `median` or `game:H` with an integer `H` in `0..=20`.
impl std::str::FromStr for KdSplit {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let game = s.strip_prefix("game:").and_then(|h| h.parse::<u8>().ok());
        match (s, game) {
            ("sah", _) => Ok(KdSplit::Sah),
            ("median", _) => Ok(KdSplit::Median),
            (_, Some(h)) if h <= 20 => Ok(KdSplit::Game(h)),
            _ => Err(crate::names::UnknownName {
                what: "kd split",
                given: s.to_string(),
                choices: vec!["sah", "median", "game:H (H an integer in 0..=20)"],
            }),
        }
    }
}

/// Options of the kd-tree builds.
#[derive(Clone, Debug, PartialEq)]
pub struct KdOptions {
    /// Split rule.
    pub split: KdSplit,
    /// SAH cost of traversing a node (`K_T`).
    pub traversal_cost: f32,
    /// SAH cost of one triangle test (`K_I`).
    pub intersection_cost: f32,
    /// SAH discount for planes that cut off empty space (Wald & Havran's
    /// `1 − λ`).
    pub empty_bonus: f32,
    /// Depth limit; 0 picks `8 + 1.3 log2 N` (pbrt's rule), capped at
    /// `MAX_KD_DEPTH - 1`.
    pub max_depth: u32,
    /// Median and game builds: nodes with at most this many triangles
    /// become leaves.
    pub max_leaf_size: usize,
    /// Subtrees with more references than this are built in parallel.
    pub parallel_threshold: usize,
    /// Levels of the subtrees that are laid out breadth-first, one after the
    /// other depth first (default 6: a sibling pair and its descendants for
    /// 6 levels, 126 nodes, 1 KB); 0 lays the whole tree out breadth-first
    /// as one array level by level.
    pub subtree_levels: u32,
}

impl Default for KdOptions {
    fn default() -> Self {
        KdOptions {
            split: KdSplit::Sah,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            empty_bonus: 0.2,
            max_depth: 0,
            max_leaf_size: 4,
            parallel_threshold: 4096,
            subtree_levels: 6,
        }
    }
}

impl KdOptions {
    /// The depth limit for `n` triangles.
    pub fn depth_limit(&self, n: usize) -> u32 {
        let auto = 8.0 + 1.3 * (n.max(1) as f64).log2();
        let d = if self.max_depth > 0 {
            self.max_depth
        } else {
            auto.round() as u32
        };
        d.min(MAX_KD_DEPTH as u32 - 1)
    }
}

/// The mesh's triangles as the builds see them: corners in `f64`, the width
/// of each one's tolerance band, and the ids of the non-degenerate ones
/// (zero-area and non-finite triangles are never hit, so never stored).
pub(crate) struct TriangleSet {
    pub corners: Vec<[DVec3; 3]>,
    pub band: Vec<f64>,
    pub ids: Vec<u32>,
}

impl TriangleSet {
    pub fn new(mesh: &TriangleMesh) -> TriangleSet {
        let corners: Vec<[DVec3; 3]> = (0..mesh.num_triangles())
            .into_par_iter()
            .map(|i| mesh.triangle(i).map(|p| p.as_dvec3()))
            .collect();
        let band = corners.par_iter().map(clip::band_width).collect();
        let ids = (0..corners.len() as u32)
            .into_par_iter()
            .filter(|&i| {
                let [a, b, c] = corners[i as usize];
                let n = (b - a).cross(c - a);
                a.is_finite() && b.is_finite() && c.is_finite() && n.length_squared() > 0.0
            })
            .collect();
        TriangleSet { corners, band, ids }
    }

    /// The root cell: all triangles with their bands, rounded outwards.
    pub fn root_cell(&self) -> Aabb {
        let (lo, hi) = self
            .ids
            .par_iter()
            .map(|&i| {
                let t = &self.corners[i as usize];
                let w = DVec3::splat(self.band[i as usize]);
                (t[0].min(t[1]).min(t[2]) - w, t[0].max(t[1]).max(t[2]) + w)
            })
            .reduce(
                || (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        if self.ids.is_empty() {
            return Aabb::EMPTY;
        }
        Aabb::new(clip::round_down(lo), clip::round_up(hi))
    }
}
