//! Structures built straight from a mesh (not through `build_accel`, which
//! validates it) stop with `TriangleMesh::validate`'s message, naming the
//! triangle, when a vertex index lies beyond the vertices.

use raykit_core::accel::bvh::{BuildOptions, Bvh2, Bvh8};
use raykit_core::query::SurfaceBvh;
use raykit_core::tri::Moller;
use raykit_core::{MeshError, TriangleMesh, Vec3};

fn quad() -> TriangleMesh {
    TriangleMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

/// One structure's build over the mesh, for `catch_unwind`.
type Build<'a> = dyn Fn() + 'a;

fn message(r: std::thread::Result<()>) -> String {
    let e = r.expect_err("the build must stop");
    e.downcast_ref::<String>().cloned().unwrap_or_default()
}

#[test]
fn direct_builds_name_the_triangle_with_a_vertex_index_out_of_range() {
    let mut m = quad();
    m.indices[1][2] = 9;
    let want = m.validate().unwrap_err();
    assert_eq!(
        want,
        MeshError::IndexOutOfRange {
            tri: 1,
            index: 9,
            count: 4
        }
    );
    let want = want.to_string();
    let options = BuildOptions::default();
    let builds: [(&str, Box<Build>); 3] = [
        (
            "bvh8",
            Box::new(|| drop(Bvh8::<Moller>::build(&m, &options))),
        ),
        (
            "bvh2",
            Box::new(|| drop(Bvh2::<Moller>::build(&m, &options))),
        ),
        ("surface", Box::new(|| drop(SurfaceBvh::build(&m)))),
    ];
    for (name, build) in builds {
        let got = message(std::panic::catch_unwind(std::panic::AssertUnwindSafe(
            build,
        )));
        assert!(got.contains(&want), "{name}: {got}");
    }
    // A whole mesh builds.
    drop(Bvh8::<Moller>::build(&quad(), &options));
}
