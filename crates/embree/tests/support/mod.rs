//! Test support: the shared data's meshes (read with raykit-io), rays at a
//! mesh, and the check of an Embree answer against raykit-core's. Embree's
//! triangle test does not widen its edges and ours does (by a bound on its
//! own rounding, `raykit_core::tri`), so a ray crossing the nearer answer's
//! triangle within that band of an edge may be caught by one engine and
//! missed by the other; every other difference fails the test.
#![allow(dead_code)]

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::rng::Pcg32;
use raykit_core::tri::reference::{edge_distance_f64, plane_t_f64};
use raykit_core::tri::{TestKind, MAX_EDGE_TOLERANCE};
use raykit_core::{Accel, Hit, Ray, TriangleMesh, Vec3};
use std::path::PathBuf;

/// Relative tolerance on hit distances.
const T_TOLERANCE: f32 = 1e-5;

/// Distance from an edge, relative to the triangle's size, within which
/// the engines may disagree: 2√3 times the widest edge widening of our
/// tests, as the CLI's comparison allows.
const EDGE_BAND: f64 = 2.0 * 1.732_050_8 * MAX_EDGE_TOLERANCE as f64;

/// The test data folder: `data/` in the repository, or
/// `$RAYKIT_SHARED_DATA` (as the other crates' tests find it).
pub fn shared_data() -> PathBuf {
    let root = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data"));
    assert!(
        root.is_dir(),
        "{} is missing: the tests need the test data folder (set RAYKIT_SHARED_DATA)",
        root.display()
    );
    root
}

/// The mesh `meshes/NAME` of the shared data.
pub fn data_mesh(name: &str) -> TriangleMesh {
    let path = shared_data().join("meshes").join(name);
    raykit_io::load_mesh(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// raykit-core's `kind` over `mesh` (Möller's test), the reference.
pub fn ours(kind: AccelKind, mesh: &TriangleMesh) -> Box<dyn Accel> {
    build_accel(kind, TestKind::Moller, mesh, &BuildOptions::default())
}

/// Rays at a mesh and raykit-core's answers for them.
pub struct Reference {
    /// The rays ([`rays_at`]).
    pub rays: Vec<Ray>,
    /// Nearest hits.
    pub hits: Vec<Option<Hit>>,
    /// Occlusion.
    pub occluded: Vec<bool>,
}

/// `n` rays at `mesh` (seed `seed`) answered by our `kind`, checked to
/// make a telling test: a quarter of the rays hit, some segments are free.
pub fn reference(kind: AccelKind, mesh: &TriangleMesh, n: usize, seed: u64) -> Reference {
    let ours = ours(kind, mesh);
    let rays = rays_at(mesh, n, seed);
    let mut hits = vec![None; rays.len()];
    ours.intersect_batch(&rays, &mut hits);
    let mut occluded = vec![false; rays.len()];
    ours.occluded_batch(&rays, &mut occluded);
    let hit = hits.iter().filter(|h| h.is_some()).count();
    assert!(hit > rays.len() / 4, "only {hit} rays hit: a poor test");
    assert!(occluded.iter().any(|&o| !o), "every segment blocked");
    Reference {
        rays,
        hits,
        occluded,
    }
}

/// Give `build` the teapot with triangle 17 naming a vertex past the end:
/// it must refuse with an error naming the triangle and the index.
pub fn check_index_error<T>(build: impl FnOnce(&[Vec3], &[[u32; 3]]) -> anyhow::Result<T>) {
    let mesh = data_mesh("teapot_992.obj");
    let mut indices = mesh.indices.clone();
    let past = mesh.positions.len() as u32 + 5;
    indices[17][1] = past;
    let err = build(&mesh.positions, &indices).err().expect("an error");
    assert_eq!(
        err.to_string(),
        format!(
            "triangle 17: vertex index {past} is past the {} vertices",
            mesh.positions.len()
        )
    );
}

/// `n` segments at `mesh`: from a box half again the mesh's size towards
/// points of its box, 1.5 times as long as the way there, so that some
/// stop short, some pass through and some miss.
pub fn rays_at(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Pcg32::new(seed);
    let b = mesh.bounds();
    let pad = (b.max - b.min) * 0.5;
    (0..n)
        .map(|_| {
            let o = rng.in_box(b.min - pad, b.max + pad);
            let target = rng.in_box(b.min, b.max);
            let to = target - o;
            Ray::segment(o, to.normalize(), 0.0, to.length() * 1.5)
        })
        .collect()
}

/// Whether `ray` grazes triangle `prim`: it crosses the triangle's plane
/// (f64) within [`EDGE_BAND`] of an edge, or runs parallel to it, where
/// `t` is ill-conditioned.
fn grazes(mesh: &TriangleMesh, ray: &Ray, prim: u32) -> bool {
    let [a, b, c] = mesh.triangle(prim as usize).map(|p| p.as_dvec3());
    let (o, d) = (ray.origin.as_dvec3(), ray.dir().as_dvec3());
    match plane_t_f64(a, b, c, o, d) {
        Some(t) => edge_distance_f64(a, b, c, o + d * t) < EDGE_BAND,
        None => true,
    }
}

/// Two nearest hits agree: both miss, or both hit at the same distance
/// (another triangle at that distance is a tie).
fn same(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (Some(x), Some(y)) => {
            (x.t - y.t).abs() <= T_TOLERANCE * x.t.abs().max(y.t.abs()).max(f32::MIN_POSITIVE)
        }
        (x, y) => x.is_some() == y.is_some(),
    }
}

/// The nearer of two answers.
fn nearer(a: Option<Hit>, b: Option<Hit>) -> Option<Hit> {
    match (a, b) {
        (Some(x), Some(y)) => Some(if x.t <= y.t { x } else { y }),
        _ => a.or(b),
    }
}

/// Check `got` (from `engine`) against the reference `want`, ray by ray:
/// each difference must be a graze of the nearer answer's triangle, and
/// grazes must stay under 1% of the rays. Returns the grazes.
pub fn check_hits(
    engine: &str,
    mesh: &TriangleMesh,
    rays: &[Ray],
    want: &[Option<Hit>],
    got: &[Option<Hit>],
) -> usize {
    assert_eq!((want.len(), got.len()), (rays.len(), rays.len()));
    let mut grazed = 0;
    for ((ray, &w), &g) in rays.iter().zip(want).zip(got) {
        if same(w, g) {
            continue;
        }
        let near = nearer(w, g).expect("a difference has a hit");
        assert!(
            grazes(mesh, ray, near.prim),
            "{engine}: {ray:?}: Embree {g:?}, raykit {w:?}, not at an edge"
        );
        grazed += 1;
    }
    assert!(
        grazed * 100 <= rays.len(),
        "{engine}: {grazed} of {} nearest hits differ at edges",
        rays.len()
    );
    grazed
}

/// Check occlusion answers `got` against `want` as [`check_hits`] does:
/// where they differ, the nearer of the blockers the two engines find
/// along the segment (`want_hits`, `got_hits`) must be grazed.
pub fn check_occlusion(
    engine: &str,
    mesh: &TriangleMesh,
    rays: &[Ray],
    (want, want_hits): (&[bool], &[Option<Hit>]),
    (got, got_hits): (&[bool], &[Option<Hit>]),
) -> usize {
    assert_eq!((want.len(), got.len()), (rays.len(), rays.len()));
    let mut grazed = 0;
    for i in (0..rays.len()).filter(|&i| want[i] != got[i]) {
        let blocker = nearer(want_hits[i], got_hits[i]);
        assert!(
            blocker.is_some_and(|h| grazes(mesh, &rays[i], h.prim)),
            "{engine}: {:?}: Embree occluded {}, raykit {}, blocker {blocker:?} not at an edge",
            rays[i],
            got[i],
            want[i]
        );
        grazed += 1;
    }
    assert!(
        grazed * 100 <= rays.len(),
        "{engine}: {grazed} of {} occlusion answers differ at edges",
        rays.len()
    );
    grazed
}

/// Check what an Embree scene reports of itself through the [`Accel`]
/// trait against `mesh`: every triangle referenced, and one region, the
/// mesh's bounds, holding them all.
pub fn check_regions(scene: &dyn Accel, mesh: &TriangleMesh) {
    assert_eq!(scene.stats().triangle_refs, mesh.num_triangles());
    let mut regions = Vec::new();
    let mut held = Vec::new();
    scene.visit_regions(
        &mut |b| {
            regions.push(*b);
            true
        },
        &mut |tris| held.extend_from_slice(tris),
    );
    assert_eq!(regions, vec![mesh.bounds()]);
    held.sort_unstable();
    assert_eq!(held, (0..mesh.num_triangles() as u32).collect::<Vec<_>>());
}
