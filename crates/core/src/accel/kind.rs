//! The structures by name, for run-time choice.

/// The acceleration structures by name (`--accel NAME`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AccelKind {
    /// [`BruteForce`](super::BruteForce).
    Brute,
    /// [`Bvh2`](super::Bvh2).
    Bvh2,
    /// [`Bvh4`](super::Bvh4).
    Bvh4,
    /// [`Bvh8`](super::Bvh8).
    Bvh8,
    /// [`ThreadedBvh`](super::ThreadedBvh).
    ThreadedBvh,
    /// [`KdStack`](super::KdStack).
    KdStack,
    /// [`KdRopes`](super::KdRopes).
    KdRopes,
    /// [`KdRestart`](super::KdRestart).
    KdRestart,
    /// [`KdBacktrack`](super::KdBacktrack).
    KdBacktrack,
}

impl AccelKind {
    /// Every structure, in a fixed order.
    pub const ALL: [AccelKind; 9] = [
        AccelKind::Brute,
        AccelKind::Bvh2,
        AccelKind::Bvh4,
        AccelKind::Bvh8,
        AccelKind::ThreadedBvh,
        AccelKind::KdStack,
        AccelKind::KdRopes,
        AccelKind::KdRestart,
        AccelKind::KdBacktrack,
    ];

    /// The kd-tree traversals.
    pub const KD: [AccelKind; 4] = [
        AccelKind::KdStack,
        AccelKind::KdRopes,
        AccelKind::KdRestart,
        AccelKind::KdBacktrack,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            AccelKind::Brute => "brute",
            AccelKind::Bvh2 => "bvh2",
            AccelKind::Bvh4 => "bvh4",
            AccelKind::Bvh8 => "bvh8",
            AccelKind::ThreadedBvh => "bvh-threaded",
            AccelKind::KdStack => "kd-stack",
            AccelKind::KdRopes => "kd-ropes",
            AccelKind::KdRestart => "kd-restart",
            AccelKind::KdBacktrack => "kd-backtrack",
        }
    }

    /// One-line description for `raykit info accels`.
    pub fn description(self) -> &'static str {
        match self {
            AccelKind::Brute => {
                "every ray against every triangle; the reference (slow: O(rays x triangles))"
            }
            AccelKind::Bvh2 => {
                "binary BVH, parallel binned-SAH build, stack traversal nearest child first"
            }
            AccelKind::Bvh4 => {
                "4-wide BVH, binned-SAH build making wide nodes directly, SSE box tests, ordered stack traversal"
            }
            AccelKind::Bvh8 => {
                "8-wide BVH, binned-SAH build making wide nodes directly, AVX box tests (SSE/scalar fallback), ordered stack traversal"
            }
            AccelKind::ThreadedBvh => {
                "BVH nodes in pre-order with escape indices, stackless traversal (Smits 1998)"
            }
            AccelKind::KdStack => {
                "kd-tree (--kd-split), 8-byte nodes, per-ray stack traversal"
            }
            AccelKind::KdRopes => {
                "kd-tree with ropes and leaf boxes, stackless (Popov et al. 2007)"
            }
            AccelKind::KdRestart => "kd-tree, kd-restart: stackless, descends from the root per leaf (Foley & Sugerman 2005)",
            AccelKind::KdBacktrack => "kd-tree, kd-backtrack: stackless, climbs parent links (Foley & Sugerman 2005)",
        }
    }

    /// Parse a command-line name.
    pub fn from_name(name: &str) -> Option<AccelKind> {
        AccelKind::ALL.into_iter().find(|k| k.name() == name)
    }
}
