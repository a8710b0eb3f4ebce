//! The structures by name, for run-time choice.

use crate::names::named_choice;

/// The acceleration structures by name.
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

    /// The structure's name (`bvh8`, `kd-ropes`, …), as `Display` writes it.
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

    /// The structure with this name, if any (`str::parse` gives an error
    /// listing the names instead).
    pub fn from_name(name: &str) -> Option<AccelKind> {
        name.parse().ok()
    }
}

named_choice!(AccelKind, "structure");
