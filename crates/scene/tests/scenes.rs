//! Geometry of the built-in scenes: counts, determinism, validity, normals,
//! closed objects and a camera that sees the scene.

use raykit_core::accel::{Accel, BruteForce};
use raykit_core::tri::Moller;
use raykit_core::{glam::Vec3, TriangleMesh};
use raykit_scene::{builtin, cornell, scatter, shirley6, terrain, Icosphere, Scene};
use std::collections::HashMap;

/// Small versions of every scene.
fn small_scenes() -> Vec<Scene> {
    [
        "cornell",
        "shirley6",
        "terrain:triangles=2000",
        "scatter:triangles=8000",
    ]
    .iter()
    .map(|s| builtin(s).unwrap())
    .collect()
}

#[test]
fn triangle_counts_are_as_documented() {
    assert_eq!(cornell::TRIANGLES, 1314);
    assert_eq!(builtin("cornell").unwrap().mesh.num_triangles(), 1314);
    assert_eq!(shirley6::TRIANGLES, 804);
    assert_eq!(builtin("shirley6").unwrap().mesh.num_triangles(), 804);
    assert_eq!(terrain::grid_size(200_000), 316);
    assert_eq!(terrain::grid_size(1_000_000), 707);
    assert_eq!(terrain::grid_size(1), 1);
    let t = builtin("terrain").unwrap();
    assert_eq!(t.mesh.num_triangles(), 2 * 316 * 316);
    assert_eq!(t.mesh.positions.len(), 317 * 317);
    assert_eq!(
        builtin("terrain:triangles=2").unwrap().mesh.num_triangles(),
        2
    );
    assert_eq!(scatter::sphere_count(500_000), 6250);
    let s = builtin("scatter").unwrap();
    assert_eq!(s.mesh.num_triangles(), 500_000);
    assert_eq!(s.mesh.parts.len(), 6250);
    assert_eq!(
        builtin("scatter:triangles=1000")
            .unwrap()
            .mesh
            .num_triangles(),
        1040
    );
}

#[test]
fn same_seed_same_scene_other_seed_other_scene() {
    for name in [
        "cornell",
        "shirley6",
        "terrain:triangles=5000",
        "scatter:triangles=5000",
    ] {
        let sep = if name.contains(':') { ',' } else { ':' };
        let a = builtin(&format!("{name}{sep}seed=5")).unwrap();
        let b = builtin(&format!("{name}{sep}seed=5")).unwrap();
        let c = builtin(&format!("{name}{sep}seed=6")).unwrap();
        assert_eq!(a, b, "{name}");
        assert_eq!(a.mesh.indices, c.mesh.indices, "{name}: same topology");
        assert_ne!(a.mesh.positions, c.mesh.positions, "{name}");
    }
}

#[test]
fn meshes_are_valid_with_unit_normals_facing_out() {
    for s in small_scenes() {
        let m = &s.mesh;
        m.validate().unwrap_or_else(|e| panic!("{}: {e}", s.name));
        assert!(!s.lights.is_empty(), "{}", s.name);
        assert!(s.camera.is_some(), "{}", s.name);
        assert!(!m.materials.is_empty() && m.tri_material.len() == m.num_triangles());
        assert!(m
            .tri_material
            .iter()
            .all(|&k| (k as usize) < m.materials.len()));
        assert!(m.tri_part.iter().all(|&k| (k as usize) < m.parts.len()));
        let normals = m.normals.as_ref().expect("normals");
        for n in normals {
            assert!((n.length() - 1.0).abs() < 1e-5, "{}: {n}", s.name);
        }
        for (i, tri) in m.indices.iter().enumerate() {
            let f = m.face_normal(i);
            assert!(f.length() > 0.0, "{}: degenerate triangle {i}", s.name);
            for &v in tri {
                assert!(normals[v as usize].dot(f) > 0.0, "{}: triangle {i}", s.name);
            }
        }
        for mat in &m.materials {
            assert!(mat.diffuse.iter().all(|&c| (0.0..=1.0).contains(&c)));
        }
    }
}

#[test]
fn flat_faces_have_face_normals() {
    let s = builtin("cornell").unwrap();
    let normals = s.mesh.normals.as_ref().unwrap();
    for (i, tri) in s.mesh.indices.iter().enumerate() {
        let name = &s.mesh.parts[s.mesh.part_of(i) as usize].name;
        if name != "sphere" {
            let f = s.mesh.face_normal(i).normalize();
            for &v in tri {
                assert!((normals[v as usize] - f).length() < 1e-5, "{name}");
            }
        }
    }
}

/// Triangles of `mesh` grouped by part name.
fn parts(mesh: &TriangleMesh) -> HashMap<String, Vec<usize>> {
    let mut out: HashMap<String, Vec<usize>> = HashMap::new();
    for i in 0..mesh.num_triangles() {
        let name = mesh.parts[mesh.part_of(i) as usize].name.clone();
        out.entry(name).or_default().push(i);
    }
    out
}

/// Panics unless `tris` form a closed, consistently oriented 2-manifold
/// enclosing positive volume: with edges keyed by the exact positions of their
/// ends (flat faces have their own vertices), each directed edge occurs once
/// and its reverse once, so every edge is shared by exactly two triangles.
fn assert_closed(mesh: &TriangleMesh, tris: &[usize], what: &str) {
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut directed: HashMap<_, u32> = HashMap::new();
    let mut volume = 0.0f64;
    for &i in tris {
        let [a, b, c] = mesh.triangle(i);
        for (p, q) in [(a, b), (b, c), (c, a)] {
            *directed.entry((key(p), key(q))).or_default() += 1;
        }
        volume += a.dot(b.cross(c)) as f64 / 6.0;
    }
    let mut undirected: HashMap<_, u32> = HashMap::new();
    for (&(p, q), &n) in &directed {
        assert_eq!(n, 1, "{what}: directed edge used {n} times");
        assert_eq!(directed.get(&(q, p)), Some(&1), "{what}: open edge");
        *undirected
            .entry(if p < q { (p, q) } else { (q, p) })
            .or_default() += n;
    }
    assert!(undirected.values().all(|&n| n == 2), "{what}");
    assert_eq!(undirected.len() * 2, tris.len() * 3, "{what}");
    assert!(volume > 0.0, "{what}: inward-facing (volume {volume})");
}

#[test]
fn objects_are_closed_two_manifolds() {
    let ico = Icosphere::new(2);
    assert_eq!((ico.positions.len(), ico.indices.len()), (162, 320));
    let c = builtin("cornell").unwrap();
    let p = parts(&c.mesh);
    for name in ["tall box", "short box", "sphere"] {
        assert_closed(&c.mesh, &p[name], name);
    }
    let s = builtin("shirley6").unwrap();
    let p = parts(&s.mesh);
    for name in ["sphere 0", "sphere 1", "box 0", "box 1", "box 2"] {
        assert_closed(&s.mesh, &p[name], name);
    }
    let s = builtin("scatter:triangles=8000,seed=3").unwrap();
    let p = parts(&s.mesh);
    assert_eq!(p.len(), 100);
    for (name, tris) in &p {
        assert_eq!(tris.len(), 80);
        assert_closed(&s.mesh, tris, name);
    }
}

#[test]
fn scenes_stay_inside_expected_bounds() {
    let c = builtin("cornell").unwrap();
    let b = c.mesh.bounds();
    assert!(
        b.min.cmpge(Vec3::new(-5.0, 0.0, -5.0)).all()
            && b.max.cmple(Vec3::new(5.0, 10.0, 5.0)).all()
    );
    let t = builtin("terrain:triangles=2000").unwrap();
    let b = t.mesh.bounds();
    assert_eq!((b.min.x, b.max.x), (-50.0, 50.0));
    assert!(b.max.y - b.min.y > 5.0, "the terrain is not flat");
}

#[test]
fn camera_sees_the_scene_and_lights_are_outside_objects() {
    for s in small_scenes() {
        let accel = BruteForce::<Moller>::new(&s.mesh);
        let cam = s.camera.unwrap();
        let rays = cam.rays(32, 24);
        let hits = (0..24)
            .flat_map(|y| (0..32).map(move |x| (x, y)))
            .filter(|&(x, y)| accel.intersect(&rays.pixel(x, y)).is_some())
            .count();
        // The scattered spheres leave gaps; the others fill most of the view.
        let min = if s.name == "scatter" {
            768 / 20
        } else {
            768 / 3
        };
        assert!(hits > min, "{}: only {hits} of 768 rays hit", s.name);
        // The camera is not inside the geometry: the centre ray hits far away.
        let centre = accel.intersect(&rays.pixel(16, 12));
        assert!(centre.is_some_and(|h| h.t > 1.0), "{}", s.name);
        // Some hit point sees the light.
        let lit = (0..24)
            .flat_map(|y| (0..32).map(move |x| (x, y)))
            .any(|(x, y)| {
                let r = rays.pixel(x, y);
                accel.intersect(&r).is_some_and(|h| {
                    let p = r.at(h.t * 0.999);
                    let d = s.lights[0].position().expect("a point light") - p;
                    !accel.occluded(&raykit_core::Ray::segment(p, d, 1e-4, 0.999))
                })
            });
        assert!(lit, "{}", s.name);
    }
}
