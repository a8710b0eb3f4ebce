//! Unit tests of the public T-junction API on hand-made meshes with known
//! answers (Kim's (2013) definition).

use super::*;
use glam::Vec3;

/// Two unit quads side by side; the right one is split at y = 0.5 into two
/// quads with their own vertices, so (1, 0.5) lies on the left quad's edge
/// (1,0)–(1,1), which is edge 1 of triangle 0.
fn two_quads() -> TriangleMesh {
    let v = |x: f32, y: f32| Vec3::new(x, y, 0.0);
    let mut m = TriangleMesh::new(
        vec![
            v(0.0, 0.0),
            v(1.0, 0.0),
            v(1.0, 1.0),
            v(0.0, 1.0),
            v(1.0, 0.0),
            v(2.0, 0.0),
            v(2.0, 0.5),
            v(1.0, 0.5),
            v(1.0, 0.5),
            v(2.0, 0.5),
            v(2.0, 1.0),
            v(1.0, 1.0),
        ],
        vec![
            [0, 1, 2],
            [0, 2, 3],
            [4, 5, 6],
            [4, 6, 7],
            [8, 9, 10],
            [8, 10, 11],
        ],
    );
    m.tri_part = vec![0, 0, 1, 1, 2, 2];
    m.tri_material = vec![5, 5, 6, 6, 7, 7];
    m
}

#[test]
fn two_quads_have_one_t_junction_and_it_is_fixed() {
    let m = two_quads();
    let o = TJunctionOptions::default();
    let want = vec![EdgeVertex {
        tri: 0,
        edge: 1,
        vertex: 7,
        t: 0.5,
    }];
    assert_eq!(find_naive(&m, &o).unwrap(), want);
    assert_eq!(find_fast(&m, &o).unwrap(), want);
    for method in [Method::Naive, Method::Fast] {
        let (out, report) = eliminate(&m, method, &o).unwrap();
        assert_eq!(
            out.indices,
            vec![
                [0, 1, 7],
                [0, 7, 2],
                [0, 2, 3],
                [4, 5, 6],
                [4, 6, 7],
                [8, 9, 10],
                [8, 10, 11]
            ]
        );
        assert_eq!(out.tri_part, vec![0, 0, 0, 1, 1, 2, 2]);
        assert_eq!(out.tri_material, vec![5, 5, 5, 6, 6, 7, 7]);
        assert_eq!(out.positions, m.positions);
        assert!((out.area() - m.area()).abs() < 1e-12);
        assert_eq!(
            (report.t_junctions, report.t_junctions_fixed, report.rounds),
            (1, 1, 1)
        );
        assert_eq!((report.triangles_in, report.triangles_out), (6, 7));
        assert_eq!((report.points, report.inserted), (8, 1));
        assert_eq!(
            (report.remaining_t_junctions, report.remaining_degenerate),
            (0, 0)
        );
        assert_eq!(report.method, method);
        assert!(find_fast(&out, &o).unwrap().is_empty());
    }
}

#[test]
fn a_clean_mesh_is_returned_unchanged() {
    let mut m = two_quads();
    m.indices.truncate(2);
    m.tri_part.truncate(2);
    m.tri_material.truncate(2);
    let (out, report) = eliminate(&m, Method::Fast, &TJunctionOptions::default()).unwrap();
    assert_eq!(out, m);
    assert_eq!((report.t_junctions, report.rounds), (0, 0));
}

#[test]
fn degenerate_triangles_are_dropped_and_their_middle_vertex_inserted() {
    // Square (0,0)-(2,0)-(2,2)-(0,2) as two triangles, plus a sliver
    // (0,0)-(1,0)-(2,0) under the bottom edge: the sliver goes, and (1,0)
    // is a vertex of the mesh only through... nothing else, so nothing is
    // inserted. With a second triangle using (1,0) below, it is.
    let v = |x: f32, y: f32| Vec3::new(x, y, 0.0);
    let mut m = TriangleMesh::new(
        vec![
            v(0.0, 0.0),
            v(2.0, 0.0),
            v(2.0, 2.0),
            v(0.0, 2.0),
            v(1.0, 0.0),
        ],
        vec![[0, 1, 2], [0, 2, 3], [0, 4, 1]],
    );
    let o = TJunctionOptions::default();
    let (out, r) = eliminate(&m, Method::Naive, &o).unwrap();
    assert_eq!(out.indices, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!((r.degenerate_dropped, r.t_junctions, r.rounds), (1, 0, 1));
    m.positions.push(v(1.0, -1.0));
    m.indices.push([0, 5, 4]);
    m.indices.push([4, 5, 1]);
    let (out, r) = eliminate(&m, Method::Fast, &o).unwrap();
    assert_eq!(
        out.indices,
        vec![[2, 0, 4], [2, 4, 1], [0, 2, 3], [0, 5, 4], [4, 5, 1]]
    );
    assert_eq!((r.degenerate_dropped, r.t_junctions), (1, 1));
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let o = TJunctionOptions::default();
    let mut m = two_quads();
    m.indices[0][0] = 99;
    assert!(matches!(
        eliminate(&m, Method::Fast, &o),
        Err(TJunctionError::Invalid(_))
    ));
    assert!(matches!(
        find_naive(&TriangleMesh::default(), &o),
        Err(TJunctionError::Invalid(MeshError::Empty))
    ));
    for bad in [-1.0, f64::NAN, 0.5] {
        let o = TJunctionOptions {
            tolerance: bad,
            ..Default::default()
        };
        let e = find_fast(&two_quads(), &o).unwrap_err();
        assert!(e.to_string().contains("tolerance"), "{e}");
    }
}

#[test]
fn the_naive_finder_refuses_large_meshes_and_says_why() {
    // 40,000 separate triangles: 40,000 × 120,000 pairs > 2·10⁹.
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..40_000u32 {
        let o = Vec3::new(i as f32, 0.0, 0.0);
        positions.extend([o, o + Vec3::new(0.5, 0.0, 0.0), o + Vec3::Y]);
        indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let m = TriangleMesh::new(positions, indices);
    let e = find_naive(&m, &TJunctionOptions::default()).unwrap_err();
    assert_eq!(
        e,
        TJunctionError::TooLarge {
            triangles: 40_000,
            points: 120_000
        }
    );
    assert!(e.to_string().contains("fast"), "{e}");
    assert!(find_fast(&m, &TJunctionOptions::default())
        .unwrap()
        .is_empty());
}

#[test]
fn a_point_on_two_edges_next_to_a_corner_is_inserted_once() {
    // P is 1.4e-6 from corner A of (A, B, C): farther than the rounding
    // allowance (4.8e-7 here) but within the reach of both edges at A.
    let p = Vec3::new(1e-6, 1e-6, 0.0);
    let m = TriangleMesh::new(
        vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            p,
            p + Vec3::Z,
            p + Vec3::new(-1.0, -1.0, 0.5),
        ],
        vec![[0, 1, 2], [3, 4, 5]],
    );
    let o = TJunctionOptions {
        max_rounds: 1,
        ..Default::default()
    };
    let found = find_naive(&m, &o).unwrap();
    let on_first: Vec<_> = found
        .iter()
        .filter(|f| f.tri == 0)
        .map(|f| f.edge)
        .collect();
    assert_eq!(on_first, vec![0, 2], "{found:?}");
    let (a, _) = eliminate(&m, Method::Naive, &o).unwrap();
    let (b, _) = eliminate(&m, Method::Fast, &o).unwrap();
    assert_eq!(a, b);
    for (t, tri) in a.indices.iter().enumerate() {
        assert!(
            tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2],
            "triangle {t} repeats a vertex: {tri:?}"
        );
        assert!(a.face_normal(t).length() > 0.0, "triangle {t} has no area");
    }
}
