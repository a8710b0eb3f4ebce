//! Shadow masks: the fast method (min/max quadtree with early exits) equals
//! brute force (every segment marched cell by cell, itself
//! checked against testing every cell and against mesh ray casting in
//! casters.rs) on synthetic and shared DEMs, for point and sun lights.

use raykit_core::rng::Pcg32;
use raykit_terrain::io::{load_dem, LoadOptions};
use raykit_terrain::shadow::{light_above_ground, occluded, shadow_mask, Light, ShadowMethod};
use raykit_terrain::{Dem, HeightField, MaxMipmap, Steps};
use std::path::{Path, PathBuf};

fn shared_terrain(name: &str) -> PathBuf {
    let root = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data"));
    let p = root.join("terrain").join(name);
    assert!(
        p.is_file(),
        "{} is missing: the tests need the test data folder (set RAYKIT_SHARED_DATA)",
        p.display()
    );
    p
}

fn hills(w: usize, h: usize, seed: u64) -> Dem {
    let mut rng = Pcg32::new(seed);
    let heights = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32, (k / w) as f32);
            40.0 * (x * 0.13).sin() * (y * 0.09).cos()
                + 25.0 * ((x - y) * 0.05).sin()
                + 3.0 * rng.next_f32()
        })
        .collect();
    let mut dem = Dem::from_heights(w, h, heights);
    dem.georef.pixel_width = 5.0;
    dem.georef.pixel_height = -5.0;
    dem
}

/// Compare the two masks; return the lit fraction.
fn same_masks(field: &HeightField, light: &Light, what: &str) -> f64 {
    let pyramid = MaxMipmap::new(field);
    let brute = shadow_mask(field, &pyramid, light, ShadowMethod::BruteForce);
    let fast = shadow_mask(field, &pyramid, light, ShadowMethod::Fast);
    let differ: Vec<usize> = (0..brute.len()).filter(|&k| brute[k] != fast[k]).collect();
    assert!(
        differ.is_empty(),
        "{what}, {light:?}: {} cells differ, first at index {}",
        differ.len(),
        differ[0]
    );
    brute.iter().map(|&m| m as f64).sum::<f64>() / brute.len() as f64
}

#[test]
fn fast_equals_brute_force_on_synthetic_hills() {
    let dem = hills(150, 120, 7);
    let field = HeightField::new(&dem).unwrap();
    let (wx, wy) = (149.0 * 5.0, 119.0 * 5.0);
    let lights = [
        Light::Point(light_above_ground(&field, 0.5 * wx, -0.5 * wy, 2.0).unwrap()),
        Light::Point(light_above_ground(&field, 0.1 * wx, -0.8 * wy, 30.0).unwrap()),
        Light::Point([0.3 * wx, -0.2 * wy, 500.0]),
        Light::Sun {
            azimuth_deg: 135.0,
            elevation_deg: 5.0,
        },
        Light::Sun {
            azimuth_deg: 290.0,
            elevation_deg: 30.0,
        },
        Light::Sun {
            azimuth_deg: 0.0,
            elevation_deg: 12.0,
        },
    ];
    for light in lights {
        let lit = same_masks(&field, &light, "hills");
        // Neither all lit nor all dark, or the comparison proves little.
        assert!(lit > 0.05 && lit < 0.995, "{light:?}: lit fraction {lit}");
    }
}

#[test]
fn the_fast_method_does_less_work() {
    let field = HeightField::new(&hills(200, 200, 3)).unwrap();
    let pyramid = MaxMipmap::new(&field);
    let light = Light::Sun {
        azimuth_deg: 200.0,
        elevation_deg: 8.0,
    };
    let (mut brute, mut fast) = (Steps::default(), Steps::default());
    for row in (0..200).step_by(7) {
        for col in (0..200).step_by(7) {
            let a = occluded(
                &field,
                &pyramid,
                &light,
                col,
                row,
                ShadowMethod::BruteForce,
                &mut brute,
            );
            let b = occluded(
                &field,
                &pyramid,
                &light,
                col,
                row,
                ShadowMethod::Fast,
                &mut fast,
            );
            assert_eq!(a, b, "({col}, {row})");
        }
    }
    assert!(
        fast.cells * 4 < brute.cells,
        "fast tested {} cells, brute force {}",
        fast.cells,
        brute.cells
    );
}

#[test]
fn fast_equals_brute_force_on_the_shared_dems() {
    for (name, lights) in [
        (
            "RealisticTerrain_Large.ter",
            vec![(0.5, 0.5, 50.0), (0.2, 0.7, 5.0)],
        ),
        ("lidar_dem_400.tif", vec![(0.5, 0.5, 2.0), (0.9, 0.1, 10.0)]),
        ("N57E011.hgt", vec![(0.37, 0.41, 20.0)]),
    ] {
        let dem = load_dem(shared_terrain(name), &LoadOptions::default()).unwrap();
        let field = HeightField::new(&dem).unwrap();
        let (wx, wy) = (
            (field.width - 1) as f64 * field.sx,
            (field.height - 1) as f64 * field.sy,
        );
        for (fx, fy, h) in lights {
            let light = Light::Point(light_above_ground(&field, fx * wx, -fy * wy, h).unwrap());
            let lit = same_masks(&field, &light, name);
            assert!(lit > 0.001 && lit < 0.999, "{name}: lit fraction {lit}");
        }
        let lit = same_masks(
            &field,
            &Light::Sun {
                azimuth_deg: 225.0,
                elevation_deg: 4.0,
            },
            name,
        );
        assert!(
            lit < 0.9999,
            "{name}: the low sun lights everything ({lit})"
        );
    }
}

/// A grid of `w` × `h` points, 1 m cells, with height `f(col, row)`.
fn surface(w: usize, h: usize, f: impl Fn(f32, f32) -> f32) -> HeightField {
    let heights = (0..w * h)
        .map(|k| f((k % w) as f32, (k / w) as f32))
        .collect();
    HeightField::new(&Dem::from_heights(w, h, heights)).unwrap()
}

/// Both methods' masks, which must agree, against `expected(col, row)`.
fn masks_match(field: &HeightField, light: &Light, expected: impl Fn(usize, usize) -> bool) {
    same_masks(field, light, "analytic surface");
    let pyramid = MaxMipmap::new(field);
    let mask = shadow_mask(field, &pyramid, light, ShadowMethod::Fast);
    let w = field.width;
    let wrong: Vec<(usize, usize)> = (0..mask.len())
        .map(|k| (k % w, k / w))
        .filter(|&(c, r)| (mask[r * w + c] == 1) != expected(c, r))
        .collect();
    assert!(
        wrong.is_empty(),
        "{light:?}: {} cells wrong, the first at (col, row) {:?}",
        wrong.len(),
        &wrong[..wrong.len().min(5)]
    );
}

#[test]
fn a_light_on_the_ground_does_not_see_through_its_hill() {
    // A ridge along the rows, its top on column 50 and both flanks planar:
    // from a light on the west flank, segments to the west flank lie in
    // its plane (lit: they touch the surface without crossing it), and
    // segments to the east flank pass under the top, so that they leave
    // the light into the ground (in shadow). From a light on the top, both
    // flanks fall away in their planes: everything is lit.
    let field = surface(101, 41, |x, _| 10.0 - (x - 50.0).abs());
    for (x, y) in [(45.0, -10.0), (44.3, -17.6), (30.5, -20.0), (50.0, -3.0)] {
        let light = Light::Point(light_above_ground(&field, x, y, 0.0).unwrap());
        masks_match(&field, &light, |c, _| c <= 50 || x == 50.0);
    }
}

#[test]
fn a_slope_facing_away_from_a_low_sun_is_in_shadow() {
    // A plane falling 10 m per cell to the east under a sun 10° up in the
    // west-south-west: its segments leave every point into the ground and
    // stay below the plane to the grid's border. Only the border points
    // whose segments leave the grid at once (the west column, the south
    // row) have no triangle to leave through and stay lit. Facing the sun
    // instead, the plane is lit everywhere.
    let (w, h) = (61, 37);
    let sun = Light::Sun {
        azimuth_deg: 240.0,
        elevation_deg: 10.0,
    };
    let away = surface(w, h, |x, _| 1000.0 - 10.0 * x);
    masks_match(&away, &sun, |c, r| c == 0 || r == h - 1);
    let facing = surface(w, h, |x, _| 1000.0 + 10.0 * x);
    masks_match(&facing, &sun, |_, _| true);
}
