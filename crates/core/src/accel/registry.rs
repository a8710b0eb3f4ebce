//! Run-time choice of structure and triangle test, for the command line and
//! for tests and benches that iterate over every combination.

use super::kdtree::{KdBuildNode, KdTree};
use super::kind::AccelKind;
use super::{
    Accel, BruteForce, BuildOptions, Bvh2, Bvh4, Bvh8, FarRays, KdBacktrack, KdRestart, KdRopes,
    KdStack, PersistError, ThreadedBvh, UnitScaled,
};
use crate::aabb::Aabb;
use crate::mesh::TriangleMesh;
use crate::tri::TestKind;
use crate::unit_scale::{used_bounds, UnitScale};
use crate::with_test;

/// The scale a structure with triangle test `test` is built at: Möller's
/// test works on differences from the ray's origin and needs only tiny
/// models scaled ([`UnitScale::of`]); the Plücker and projection tests
/// also need a model far from the origin moved to it
/// ([`UnitScale::of_near_origin`]).
fn unit_scale(
    test: TestKind,
    mesh: &TriangleMesh,
) -> (UnitScale, std::borrow::Cow<'_, TriangleMesh>) {
    match test {
        TestKind::Moller => UnitScale::of(mesh),
        TestKind::Plucker | TestKind::Projection => UnitScale::of_near_origin(mesh),
    }
}

/// Whether a structure that [`build_accel`] built over `built` with test
/// `test`, refit to `moved` ([`Accel::refit`]), keeps the precision a build
/// over `moved` has: the scaling and placement it was built with still
/// suit the moved model (a build over the moved model, taken in the
/// built one's frame, would scale or move nothing). A model moved far from
/// where it was built (with the Plücker or projection test) or shrunk to
/// a tiny size is not: rebuild it instead.
pub fn refit_keeps_precision(test: TestKind, built: &TriangleMesh, moved: &TriangleMesh) -> bool {
    let frame = match test {
        TestKind::Moller => UnitScale::for_mesh(built),
        TestKind::Plucker | TestKind::Projection => UnitScale::for_mesh_near_origin(built),
    };
    let b = used_bounds(moved);
    let b = Aabb::new(frame.point(b.min), frame.point(b.max));
    let again = match test {
        TestKind::Moller => UnitScale::for_bounds(&b),
        TestKind::Plucker | TestKind::Projection => UnitScale::for_bounds_near_origin(&b),
    };
    again.is_one()
}

/// Build the structure `kind` over `mesh` with triangle test `test`; over
/// the mesh at unit scale when it is tiny, and moved to the origin when it
/// is far from it and the test needs it ([`UnitScaled`]); with Möller's
/// test, rays from far away are moved up to the mesh before they are traced
/// ([`FarRays`]).
///
/// # Panics
///
/// When a triangle names a vertex `mesh` does not have, naming it. The
/// loaders and [`TriangleMesh::from_arrays`] never make such a mesh;
/// [`TriangleMesh::validate`] finds one made by hand. It also finds what is
/// not checked here: a vertex that is not finite (its triangles are never
/// hit) or lies beyond [`crate::mesh::MAX_COORDINATE`] (the tests' `f32`
/// products overflow and its triangles may be missed).
pub fn build_accel(
    kind: AccelKind,
    test: TestKind,
    mesh: &TriangleMesh,
    options: &BuildOptions,
) -> Box<dyn Accel> {
    let vertices = mesh.positions.len();
    if let Some((t, i)) = mesh.indices.iter().enumerate().find_map(|(t, tri)| {
        tri.iter()
            .find(|&&i| i as usize >= vertices)
            .map(|&i| (t, i))
    }) {
        panic!("build_accel: triangle {t} names vertex {i}, but the mesh has {vertices} vertices");
    }
    let model = mesh;
    let (scale, scaled) = unit_scale(test, mesh);
    let mesh = &*scaled;
    let wrap = Wrap { test, scale, model };
    with_test!(test, T => match kind {
        AccelKind::Brute => wrap.around(BruteForce::<T>::new(mesh)),
        AccelKind::Bvh2 => wrap.around(Bvh2::<T>::build(mesh, options)),
        AccelKind::Bvh4 => wrap.around(Bvh4::<T>::build(mesh, options)),
        AccelKind::Bvh8 => wrap.around(Bvh8::<T>::build(mesh, options)),
        AccelKind::ThreadedBvh => wrap.around(ThreadedBvh::<T>::build(mesh, options)),
        AccelKind::KdStack => wrap.around(KdStack::<T>::build(mesh, &options.kd)),
        AccelKind::KdRopes => wrap.around(KdRopes::<T>::build(mesh, &options.kd)),
        AccelKind::KdRestart => wrap.around(KdRestart::<T>::build(mesh, &options.kd)),
        AccelKind::KdBacktrack => wrap.around(KdBacktrack::<T>::build(mesh, &options.kd)),
    })
}

/// What a structure built or loaded over `model` is wrapped in: the scale
/// it was built at ([`UnitScaled`]) and, for Möller's test, rays from far
/// away moved up to the model ([`FarRays`]).
///
/// Only Möller's test moves far rays: it is the default, and the one whose
/// far rays were measured to pass through closed meshes. Moved rays (an
/// origin near the model, grazing a triangle's tolerance band) found the
/// wide BVHs' Plücker boxes narrower than that test's band, a disagreement
/// with brute force that moving must not bring in.
struct Wrap<'a> {
    test: TestKind,
    scale: UnitScale,
    model: &'a TriangleMesh,
}

impl Wrap<'_> {
    /// `accel` wrapped. At unit scale the structure sits directly in
    /// [`FarRays`], so that a one-ray call reaches it without a second
    /// dynamic call.
    fn around<A: Accel + 'static>(&self, accel: A) -> Box<dyn Accel> {
        match (self.test, self.scale.is_one()) {
            (TestKind::Moller, true) => Box::new(FarRays::around(Box::new(accel), self.model)),
            (TestKind::Moller, false) => {
                FarRays::wrap(UnitScaled::wrap(Box::new(accel), self.scale), self.model)
            }
            (TestKind::Plucker | TestKind::Projection, _) => {
                UnitScaled::wrap(Box::new(accel), self.scale)
            }
        }
    }
}

/// Load a structure saved with [`Accel::save`] over `mesh`, of the
/// structure and triangle test its header names (see
/// [`super::bvh::saved_kind`]), checked as the structure's own `load` does.
pub fn load_accel(
    path: &std::path::Path,
    mesh: &TriangleMesh,
) -> Result<(AccelKind, TestKind, Box<dyn Accel>), PersistError> {
    let (kind, test) = super::bvh::saved_kind(path)?;
    let model = mesh;
    // The scale the file records (files that predate the record: the one
    // build_accel would choose for this mesh).
    let (scale, scaled) = match super::bvh::saved_scale(path)? {
        Some(s) => (s, s.mesh(mesh)),
        None => unit_scale(test, mesh),
    };
    let mesh = &*scaled;
    let wrap = Wrap { test, scale, model };
    with_test!(test, T => {
        let accel = match kind {
            AccelKind::Bvh4 => wrap.around(Bvh4::<T>::load_scaled(path, mesh)?),
            _ => wrap.around(Bvh8::<T>::load_scaled(path, mesh)?),
        };
        Ok((kind, test, accel))
    })
}

/// Wrap an already built kd-tree (see [`super::kdtree::build_tree`]) in the
/// traversal `kind` with triangle test `test`, so that every traversal and
/// test can share one build; `None` when `kind` is not a kd-tree traversal.
pub fn kd_accel_from_tree(
    kind: AccelKind,
    test: TestKind,
    mesh: &TriangleMesh,
    root: &KdBuildNode,
    cell: &Aabb,
    options: &BuildOptions,
    build_seconds: f64,
) -> Option<Box<dyn Accel>> {
    with_test!(test, T => {
        let tree = || KdTree::<T>::from_build(mesh, root, cell, &options.kd, build_seconds);
        Some(match kind {
            AccelKind::KdStack => Box::new(KdStack::from_tree(tree())) as Box<dyn Accel>,
            AccelKind::KdRopes => Box::new(KdRopes::from_tree(tree())),
            AccelKind::KdRestart => Box::new(KdRestart::from_tree(tree())),
            AccelKind::KdBacktrack => Box::new(KdBacktrack::from_tree(tree())),
            _ => return None,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec3;

    /// A mesh made by hand with an index past its vertices is refused by
    /// name, by every structure, rather than with a bare index panic.
    #[test]
    fn a_triangle_naming_a_missing_vertex_is_named() {
        let mesh = TriangleMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            vec![[0, 1, 2], [0, 1, 7]],
        );
        assert!(mesh.validate().is_err());
        for kind in AccelKind::ALL {
            let built = std::panic::catch_unwind(|| {
                build_accel(kind, TestKind::Moller, &mesh, &BuildOptions::default())
            });
            let message = built.err().expect("refused");
            let message = message
                .downcast_ref::<String>()
                .cloned()
                .unwrap_or_default();
            assert!(
                message.contains("triangle 1 names vertex 7, but the mesh has 3 vertices"),
                "{kind:?}: {message}"
            );
        }
    }
}
