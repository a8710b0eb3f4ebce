//! T-junction elimination (Kim 2013) checked against an independent
//! brute-force f64 checker on meshes cut by axis planes the way a
//! game-heuristic kd-tree build cuts polygons: the naive and fast finders
//! agree with each other and with the checker, and after elimination no point
//! lies on any edge, area (per part) is preserved, no triangle is flat, and a
//! closed mesh is closed again.

mod tjunction_support;

use raykit_core::rng::Pcg32;
use raykit_core::tjunction::{
    eliminate, find_fast, find_naive, EdgeVertex, Method, TJunctionOptions,
};
use raykit_core::{TriangleMesh, Vec3};
use tjunction_support::*;

fn key(p: Vec3) -> [u32; 3] {
    p.to_array().map(|c| (c + 0.0).to_bits())
}

/// The finder's answer in the checker's terms.
fn as_brute(mesh: &TriangleMesh, found: &[EdgeVertex]) -> Vec<(u32, u8, [u32; 3])> {
    let mut v: Vec<_> = found
        .iter()
        .map(|f| (f.tri, f.edge, key(mesh.positions[f.vertex as usize])))
        .collect();
    v.sort_unstable();
    v
}

/// Plane-cut grids, spheres and soups with several seeds.
fn cut_cases() -> Vec<(String, TriangleMesh)> {
    let mut cases = Vec::new();
    for seed in 0..4u64 {
        for (name, base) in [
            ("grid", grid(12 + 4 * seed as u32)),
            ("sphere", sphere(2 + (seed % 3) as u32)),
            ("soup", soup(150, seed)),
        ] {
            let planes = random_planes(&base, 3 + seed as u32, seed);
            cases.push((format!("{name} seed {seed}"), cut(&base, &planes)));
        }
    }
    cases
}

#[test]
fn hand_made_two_quads_have_exactly_one_t_junction_which_is_fixed() {
    // Left quad (0,0)-(1,1) as two triangles; right quad (1,0)-(2,1) cut at
    // y = 0.5 by the cutter: (1, 0.5) lies on the left quad's edge x = 1.
    let left = TriangleMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let right = TriangleMesh::new(
        [(1.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0)]
            .map(|(x, y)| Vec3::new(x, y, 0.0))
            .to_vec(),
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let plane = Plane {
        axis: 1,
        at: 0.5,
        region: (Vec3::new(1.0, -1.0, -1.0), Vec3::splat(3.0)),
    };
    let mut m = left.clone();
    m.append(&cut(&right, &[plane]));
    let o = TJunctionOptions::default();
    let found = find_naive(&m, &o).unwrap();
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!((found[0].tri, found[0].edge, found[0].t), (0, 1, 0.5));
    assert_eq!(
        m.positions[found[0].vertex as usize],
        Vec3::new(1.0, 0.5, 0.0)
    );
    assert_eq!(as_brute(&m, &found), brute_t_junctions(&m));
    let (out, report) = eliminate(&m, Method::Fast, &o).unwrap();
    assert_eq!((report.t_junctions, report.remaining_t_junctions), (1, 0));
    assert_eq!(out.num_triangles(), m.num_triangles() + 1);
    assert!(brute_t_junctions(&out).is_empty());
    assert!((out.area() - 2.0).abs() < 1e-6);
}

#[test]
fn plane_cuts_make_t_junctions_and_both_finders_agree_with_brute_force() {
    let o = TJunctionOptions::default();
    for (name, m) in cut_cases() {
        let naive = find_naive(&m, &o).unwrap();
        let fast = find_fast(&m, &o).unwrap();
        assert_eq!(naive, fast, "{name}");
        assert_eq!(as_brute(&m, &naive), brute_t_junctions(&m), "{name}");
        if !name.starts_with("soup") {
            assert!(!naive.is_empty(), "{name}: the cuts made no T-junction");
        }
    }
}

#[test]
fn naive_and_fast_elimination_give_identical_meshes() {
    let o = TJunctionOptions::default();
    let mut total = 0;
    for (name, m) in cut_cases() {
        let (a, ra) = eliminate(&m, Method::Naive, &o).unwrap();
        let (b, rb) = eliminate(&m, Method::Fast, &o).unwrap();
        assert_eq!(a, b, "{name}");
        assert_eq!(
            (ra.t_junctions, ra.triangles_out, ra.rounds),
            (rb.t_junctions, rb.triangles_out, rb.rounds),
            "{name}"
        );
        total += ra.t_junctions;
    }
    assert!(total > 100, "only {total} T-junctions in all cases");
}

#[test]
fn after_elimination_no_point_lies_on_an_edge_and_area_is_kept() {
    let o = TJunctionOptions::default();
    for (name, m) in cut_cases() {
        let (out, report) = eliminate(&m, Method::Fast, &o).unwrap();
        assert_eq!(report.remaining_t_junctions, 0, "{name}");
        assert_eq!(report.remaining_degenerate, 0, "{name}");
        assert_eq!(report.degenerate_dropped, 0, "{name}");
        let left = brute_t_junctions(&out);
        assert!(
            left.is_empty(),
            "{name}: {} left: {:?}",
            left.len(),
            &left[..1]
        );
        for t in 0..out.num_triangles() {
            assert!(tri_area(&out, t) > 0.0, "{name}: triangle {t} is flat");
        }
        for (part, (x, y)) in area_by_part(&m).iter().zip(area_by_part(&out)).enumerate() {
            assert!((x - y).abs() <= 1e-6 * x, "{name}: part {part}: {x} → {y}");
        }
        assert_eq!(out.tri_part.len(), out.num_triangles(), "{name}");
        assert_eq!(report.inserted, report.t_junctions_fixed, "{name}");
        assert_eq!(
            report.triangles_out,
            report.triangles_in + report.inserted,
            "{name}: n points inserted make n more triangles"
        );
    }
}

#[test]
fn a_closed_sphere_cut_into_pieces_is_watertight_again() {
    for seed in 0..6u64 {
        let base = sphere(3);
        assert!(edge_uses(&base).values().all(|&n| n == 2));
        let planes = random_planes(&base, 2 + seed as u32 % 4, 100 + seed);
        let m = cut(&base, &planes);
        let open = edge_uses(&m).values().filter(|&&n| n != 2).count();
        assert!(open > 0, "seed {seed}: the cut sphere has no open edge");
        let (out, report) = eliminate(&m, Method::Fast, &TJunctionOptions::default()).unwrap();
        let bad: Vec<_> = edge_uses(&out)
            .into_iter()
            .filter(|&(_, n)| n != 2)
            .collect();
        assert!(
            bad.is_empty(),
            "seed {seed}: {} of the edges are not shared by two triangles ({} before), {report:?}",
            bad.len(),
            open
        );
    }
}

#[test]
fn points_planted_around_the_tolerance_give_the_same_answer_in_both_finders() {
    // Triangles with extra small triangles whose corner sits near an edge of
    // another: at 0.5, 0.9, 1.1 and 2 times the allowed distance, near the
    // ends and in the middle, far from and near the origin.
    let o = TJunctionOptions::default();
    let mut rng = Pcg32::new(9);
    for (scale, offset) in [(1.0f32, 0.0f32), (0.01, 100.0)] {
        let mut m = soup(60, 3);
        for p in &mut m.positions {
            *p = *p * scale + Vec3::splat(offset);
        }
        let base = m.num_triangles();
        let r = rounding_allowance(&m);
        for t in 0..base {
            let tri = m.triangle(t);
            let e = rng.below(3) as usize;
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            let s = [0.5f64, 1e-4, 0.9999, rng.next_f64()][rng.below(4) as usize];
            let f = [0.5f64, 0.9, 1.1, 2.0][rng.below(4) as usize];
            let (da, db) = (a.as_dvec3(), b.as_dvec3());
            let len = da.distance(db);
            let reach = TOL * len + r;
            let perp = (db - da).any_orthonormal_vector();
            let v = (da + (db - da) * s + perp * (f * reach)).as_vec3();
            let n = m.positions.len() as u32;
            let w = rng.unit_vector() * 0.05 * scale;
            m.positions.extend([v, v + w, v + w.cross(Vec3::Z)]);
            m.indices.push([n, n + 1, n + 2]);
        }
        let naive = find_naive(&m, &o).unwrap();
        assert_eq!(naive, find_fast(&m, &o).unwrap(), "scale {scale}");
        assert!(naive.len() > base / 4, "scale {scale}: {}", naive.len());
        let (a, _) = eliminate(&m, Method::Naive, &o).unwrap();
        let (b, _) = eliminate(&m, Method::Fast, &o).unwrap();
        assert_eq!(a, b, "scale {scale}");
    }
}
