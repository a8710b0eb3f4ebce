//! Run-time choice of structure and triangle test, for the command line and
//! for tests and benches that iterate over every combination.

use super::{Accel, BruteForce, BuildOptions, Bvh2, ThreadedBvh};
use crate::mesh::TriangleMesh;
use crate::tri::TestKind;
use crate::with_test;

/// The acceleration structures by name (`--accel NAME`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AccelKind {
    /// [`BruteForce`].
    Brute,
    /// [`Bvh2`].
    Bvh2,
    /// [`ThreadedBvh`].
    ThreadedBvh,
}

impl AccelKind {
    /// Every structure, in a fixed order.
    pub const ALL: [AccelKind; 3] = [AccelKind::Brute, AccelKind::Bvh2, AccelKind::ThreadedBvh];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            AccelKind::Brute => "brute",
            AccelKind::Bvh2 => "bvh2",
            AccelKind::ThreadedBvh => "bvh-threaded",
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
            AccelKind::ThreadedBvh => {
                "paper 001: BVH nodes in pre-order with escape indices, stackless traversal"
            }
        }
    }

    /// Parse a command-line name.
    pub fn from_name(name: &str) -> Option<AccelKind> {
        AccelKind::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// Build the structure `kind` over `mesh` with triangle test `test`.
pub fn build_accel(
    kind: AccelKind,
    test: TestKind,
    mesh: &TriangleMesh,
    options: &BuildOptions,
) -> Box<dyn Accel> {
    with_test!(test, T => match kind {
        AccelKind::Brute => Box::new(BruteForce::<T>::new(mesh)) as Box<dyn Accel>,
        AccelKind::Bvh2 => Box::new(Bvh2::<T>::build(mesh, options)),
        AccelKind::ThreadedBvh => Box::new(ThreadedBvh::<T>::build(mesh, options)),
    })
}
