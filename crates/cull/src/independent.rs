//! The ground truth computed independently of the rays mode: through an
//! 8-wide BVH over the Plücker test (Jones 2000), another triangle test
//! than the Möller–Trumbore (1997) test the rays mode casts with.

use crate::evaluate::{evaluate_with_progress, EvalOptions, EvalProgress, GroundTruth};
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_core::TriangleMesh;
use raykit_core::UnitScale;

/// The ground truth of `mesh` with `options` ([`evaluate_with_progress`])
/// through its own 8-wide BVH over the Plücker test, judged at unit scale
/// ([`UnitScale`]); `progress` as there.
pub fn independent_truth(
    mesh: &TriangleMesh,
    options: &EvalOptions,
    progress: &(dyn Fn(EvalProgress) + Sync),
) -> GroundTruth {
    let (unit, scaled) = UnitScale::of(mesh);
    let mesh = &*scaled;
    let accel = build_accel(
        AccelKind::Bvh8,
        TestKind::Plucker,
        mesh,
        &BuildOptions::default(),
    );
    let mut truth = evaluate_with_progress(mesh, accel.as_ref(), options, progress);
    truth.beam = unit.to_model(truth.beam);
    truth
}
