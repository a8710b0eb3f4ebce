//! The three terrain casters (per-cell march, per-ray maximum mipmap,
//! per-frame quadtree boxes) against each other on every pixel of test views,
//! and the march against two independent references: testing every cell of
//! the grid, and mesh ray casting through raykit's BVH of the same surface.

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::rng::Pcg32;
use raykit_core::tri::TestKind;
use raykit_core::{Ray, Vec3};
use raykit_terrain::march::march;
use raykit_terrain::maxmip::trace;
use raykit_terrain::view::{cast_image, CastImage, Caster};
use raykit_terrain::{Dem, HeightField, MaxMipmap, Steps, TerrainCamera};

/// Rolling hills plus noise, with cliffs (step edges) and a flat plateau
/// (exact ties between neighbouring cells).
fn hills(w: usize, h: usize, seed: u64) -> Dem {
    let mut rng = Pcg32::new(seed);
    let heights = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32, (k / w) as f32);
            let base = 40.0 * (x * 0.11).sin() * (y * 0.07).cos() + 25.0 * ((x + y) * 0.03).sin();
            let cliff = if x > w as f32 * 0.6 { 30.0 } else { 0.0 };
            let plateau = x > w as f32 * 0.2 && x < w as f32 * 0.35 && y > h as f32 * 0.4;
            if plateau {
                60.0
            } else {
                base + cliff + 4.0 * rng.next_f32()
            }
        })
        .collect();
    let mut dem = Dem::from_heights(w, h, heights);
    dem.georef.pixel_width = 10.0;
    dem.georef.pixel_height = -12.5;
    dem
}

/// The first hit found by testing every cell (nearest t wins).
fn every_cell(field: &HeightField, ray: &raykit_terrain::GridRay) -> Option<f64> {
    let (cw, ch) = field.cells();
    let mut best: Option<f64> = None;
    for r in 0..ch {
        for c in 0..cw {
            if let Some(t) = field.hit_cell(c, r, ray, 0.0, f64::INFINITY) {
                best = Some(best.map_or(t, |b: f64| b.min(t)));
            }
        }
    }
    best
}

fn random_ray(field: &HeightField, rng: &mut Pcg32) -> ([f64; 3], [f64; 3]) {
    let (wx, wy) = (
        (field.width - 1) as f64 * field.sx,
        (field.height - 1) as f64 * field.sy,
    );
    let o = [
        (rng.next_f32() as f64 * 1.4 - 0.2) * wx,
        -(rng.next_f32() as f64 * 1.4 - 0.2) * wy,
        field.zmax as f64 + 5.0 + rng.next_f32() as f64 * 100.0,
    ];
    let target = [
        rng.next_f32() as f64 * wx,
        -(rng.next_f32() as f64) * wy,
        field.zmin as f64,
    ];
    let d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    (o, [d[0] / l, d[1] / l, d[2] / l])
}

#[test]
fn march_and_maxmip_equal_testing_every_cell() {
    let field = HeightField::new(&hills(37, 29, 3)).unwrap();
    let pyramid = MaxMipmap::new(&field);
    let mut rng = Pcg32::new(11);
    let mut hits = 0;
    for _ in 0..3000 {
        let (o, d) = random_ray(&field, &mut rng);
        let ray = field.grid_ray(o, d);
        let want = every_cell(&field, &ray);
        let a = march(&field, &ray, 0.0, f64::INFINITY, &mut Steps::default());
        let b = trace(
            &field,
            &pyramid,
            &ray,
            0.0,
            f64::INFINITY,
            &mut Steps::default(),
        );
        assert_eq!(a.map(|h| h.t), want, "march vs every cell, ray {o:?} {d:?}");
        assert_eq!(a, b, "march vs max mipmap, ray {o:?} {d:?}");
        hits += usize::from(want.is_some());
    }
    assert!(
        hits > 2000,
        "only {hits} of 3000 rays hit: the test rays are too easy"
    );
}

#[test]
fn march_agrees_with_mesh_ray_casting_of_the_same_surface() {
    let field = HeightField::new(&hills(65, 49, 5)).unwrap();
    let mesh = field.to_mesh();
    let accel = build_accel(
        AccelKind::Bvh2,
        TestKind::Moller,
        &mesh,
        &BuildOptions::default(),
    );
    let mut rng = Pcg32::new(17);
    let (mut both, mut differ) = (0, 0);
    for _ in 0..20_000 {
        let (o, d) = random_ray(&field, &mut rng);
        let ray = field.grid_ray(o, d);
        let ours = march(&field, &ray, 0.0, f64::INFINITY, &mut Steps::default());
        let mesh_ray = Ray::new(
            Vec3::new(o[0] as f32, o[1] as f32, o[2] as f32),
            Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32),
        );
        let theirs = accel.intersect(&mesh_ray);
        match (ours, theirs) {
            (Some(a), Some(b)) => {
                both += 1;
                let rel = (a.t - b.t as f64).abs() / a.t;
                assert!(rel < 1e-4, "t {} vs mesh {} ({rel:e})", a.t, b.t);
                // The mesh triangle is one of the hit cell's two.
                let cell = b.prim as usize / 2;
                let (cw, _) = field.cells();
                let (c, r) = ((cell % cw) as u32, (cell / cw) as u32);
                if (c, r) != (a.col, a.row) {
                    // Only on a shared edge: the two cells give the same t.
                    assert!(
                        c.abs_diff(a.col) <= 1 && r.abs_diff(a.row) <= 1,
                        "cell ({c},{r}) vs ({},{})",
                        a.col,
                        a.row
                    );
                }
            }
            (None, None) => {}
            _ => differ += 1,
        }
    }
    // f32 mesh casting against f64: only rays grazing an edge may differ.
    assert!(both > 15_000, "{both}");
    assert!(
        differ <= 3,
        "{differ} rays hit in one and missed in the other"
    );
}

/// Same hit cell and distance (within 1e-9 relative) on every pixel.
fn same_hits(reference: &CastImage, img: &CastImage, what: &str) {
    for (k, (a, b)) in reference.hits.iter().zip(&img.hits).enumerate() {
        match (a, b) {
            (Some(a), Some(b)) => {
                assert_eq!((a.col, a.row), (b.col, b.row), "{what} pixel {k}");
                assert!(
                    (a.t - b.t).abs() <= 1e-9 * a.t,
                    "{what} pixel {k}: {} vs {}",
                    a.t,
                    b.t
                );
            }
            (None, None) => {}
            _ => panic!("{what} pixel {k}: {a:?} vs {b:?}"),
        }
    }
}

fn views(field: &HeightField) -> Vec<TerrainCamera> {
    let (wx, wy) = (
        (field.width - 1) as f64 * field.sx,
        (field.height - 1) as f64 * field.sy,
    );
    let z = field.zmax as f64;
    let span = wx.max(wy);
    vec![
        // Low oblique view across the whole terrain (most rays graze).
        TerrainCamera {
            eye: [-0.1 * wx, 0.1 * wy, z + 0.05 * span],
            target: [0.6 * wx, -0.6 * wy, field.zmin as f64],
            vfov_deg: 50.0,
            width: 96,
            height: 54,
        },
        // From inside, looking along a row.
        TerrainCamera {
            eye: [0.5 * wx, -0.5 * wy, z + 10.0],
            target: [wx, -0.5 * wy, z - 20.0],
            vfov_deg: 70.0,
            width: 80,
            height: 60,
        },
        // Straight down from high above (corner of the frustum outside the grid).
        TerrainCamera {
            eye: [0.3 * wx, -0.3 * wy, z + span],
            target: [0.3 * wx + 1e-3, -0.3 * wy, 0.0],
            vfov_deg: 40.0,
            width: 64,
            height: 64,
        },
    ]
}

#[test]
fn the_three_casters_agree_on_every_pixel() {
    for (w, h, seed) in [(129, 97, 1), (200, 257, 2)] {
        let field = HeightField::new(&hills(w, h, seed)).unwrap();
        let pyramid = MaxMipmap::new(&field);
        for (v, cam) in views(&field).iter().enumerate() {
            let reference = cast_image(&field, &pyramid, cam, Caster::March);
            let hits = reference.hits.iter().filter(|h| h.is_some()).count();
            assert!(hits > 0, "view {v} of {w}x{h} sees no terrain");
            for caster in [
                Caster::MaxMipmap,
                Caster::Boxes { tau: 1.0 },
                Caster::Boxes { tau: 4.0 },
                Caster::Boxes { tau: 16.0 },
                Caster::Boxes { tau: 1e6 },
            ] {
                let img = cast_image(&field, &pyramid, cam, caster);
                same_hits(&reference, &img, &format!("{w}x{h} {caster:?} view {v}"));
            }
        }
    }
}

#[test]
fn the_three_casters_agree_on_views_of_the_shared_dems() {
    use raykit_terrain::io::{load_dem, LoadOptions};
    let root = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data"));
    for name in [
        "RealisticTerrain_Large.ter",
        "lidar_dem_400.tif",
        "N57E011.hgt",
    ] {
        let path = root.join("terrain").join(name);
        assert!(
            path.is_file(),
            "{} is missing: the tests need the test data folder (set RAYKIT_SHARED_DATA)",
            path.display()
        );
        let dem = load_dem(&path, &LoadOptions::default()).unwrap();
        let field = HeightField::new(&dem).unwrap();
        let pyramid = MaxMipmap::new(&field);
        for (v, cam) in views(&field).iter().enumerate() {
            let reference = cast_image(&field, &pyramid, cam, Caster::March);
            assert!(
                reference.hits.iter().any(|h| h.is_some()),
                "{name} view {v} sees no terrain"
            );
            for caster in [
                Caster::MaxMipmap,
                Caster::Boxes { tau: 4.0 },
                Caster::Boxes { tau: 16.0 },
            ] {
                let img = cast_image(&field, &pyramid, cam, caster);
                same_hits(&reference, &img, &format!("{name} {caster:?} view {v}"));
            }
        }
    }
}

/// A surface needs finite heights and cells of a sane size: an infinite
/// height is refused at its cell (NaN stays no data), and so are cells
/// too small or too large for the casters' arithmetic.
#[test]
fn infinite_heights_and_absurd_cells_are_refused() {
    let mut dem = hills(9, 7, 3);
    dem.heights[2] = f32::NAN;
    assert!(HeightField::new(&dem).is_ok());
    dem.heights[9 * 4 + 5] = f32::NEG_INFINITY;
    let e = HeightField::new(&dem).err().unwrap();
    assert!(
        e.contains("row 4, column 5") && e.contains("not finite"),
        "{e}"
    );
    // Finite heights whose differences overflow float32 are refused too;
    // heights up to the bound are kept.
    for (h, ok) in [(3e38f32, false), (-2e9, false), (1e9, true), (-1e9, true)] {
        let mut dem = hills(9, 7, 3);
        dem.heights[9 * 2 + 1] = h;
        match HeightField::new(&dem) {
            Ok(_) => assert!(ok, "{h} accepted"),
            Err(e) => assert!(
                !ok && e.contains("row 2, column 1") && e.contains("beyond"),
                "{h}: {e}"
            ),
        }
    }
    for size in [1e-200, 0.0, 1e12, f64::INFINITY] {
        let mut dem = hills(9, 7, 3);
        dem.georef.pixel_width = size;
        let e = HeightField::new(&dem).err().unwrap();
        assert!(e.contains("cell size"), "{size}: {e}");
    }
}

/// A surface met at its lowest or highest height lies on a face of the
/// grid's bounding box, whose end and the cell's own `t` for the same hit
/// come from different formulas: a grid flat throughout, and a coast whose
/// sea (half the grid) lies flat at the lowest height. Every caster finds
/// every hit that testing every cell finds, at the same `t`.
#[test]
fn surfaces_at_the_lowest_and_highest_heights_are_hit_by_every_caster() {
    let (w, h) = (48, 40);
    let flat = Dem::from_heights(w, h, vec![100.0; w * h]);
    let mut coast = hills(w, h, 5);
    for (k, z) in coast.heights.iter_mut().enumerate() {
        *z = if k % w < w / 2 { 0.0 } else { 1.0 + z.abs() };
    }
    for (name, dem) in [("flat", flat), ("coast", coast)] {
        let field = HeightField::new(&dem).unwrap();
        let pyramid = MaxMipmap::new(&field);
        let (eye, target) = raykit_terrain::camera::default_camera(&field);
        let camera = TerrainCamera {
            eye,
            target,
            vfov_deg: 50.0,
            width: 64,
            height: 48,
        };
        let mut hits = 0;
        for caster in [Caster::March, Caster::MaxMipmap, Caster::Boxes { tau: 4.0 }] {
            let img = cast_image(&field, &pyramid, &camera, caster);
            for (i, got) in img.hits.iter().enumerate() {
                let (x, y) = ((i % 64) as u32, (i / 64) as u32);
                let want = every_cell(&field, &camera.ray(&field, x, y));
                match (want, got) {
                    (None, None) => {}
                    (Some(a), Some(b)) if (a - b.t).abs() <= 1e-9 * a.max(1.0) => hits += 1,
                    _ => panic!(
                        "{name}, {caster:?}, pixel ({x}, {y}): every cell gives {want:?}, \
                         the caster {:?}",
                        got.map(|g| g.t)
                    ),
                }
            }
        }
        assert!(hits > 3 * 64 * 48 / 2, "{name}: {hits} hits");
    }
}
