//! The horizon sweep for point lights: every point it decides agrees with
//! brute force (each segment to the light marched cell by cell, itself
//! checked against mesh ray casting in casters.rs), and the fast mask it
//! starts equals brute force everywhere. The surfaces are chosen to reach
//! every edge of the declared triangulation: smooth hills, rough noise,
//! ridges along rows, columns and both diagonals, and terraces full of
//! exactly equal heights; the lights sit on grid points, on grid lines, at
//! fractional positions, near edges and corners, low and high.

use raykit_core::rng::Pcg32;
use raykit_terrain::horizon::{point_light_mask, UNDECIDED};
use raykit_terrain::shadow::{light_above_ground, shadow_mask_for_targets, Light, ShadowMethod};
use raykit_terrain::{Dem, HeightField, MaxMipmap};

fn dem(w: usize, h: usize, sx: f64, sy: f64, f: impl Fn(usize, usize, &mut Pcg32) -> f32) -> Dem {
    let mut rng = Pcg32::new(11);
    let heights = (0..w * h).map(|k| f(k % w, k / w, &mut rng)).collect();
    let mut dem = Dem::from_heights(w, h, heights);
    dem.georef.pixel_width = sx;
    dem.georef.pixel_height = -sy;
    dem
}

/// The mask of `method` for targets `lift` metres up, without progress.
fn mask(
    field: &HeightField,
    pyramid: Option<&MaxMipmap>,
    light: &Light,
    method: ShadowMethod,
    lift: f64,
) -> Vec<u8> {
    shadow_mask_for_targets(field, pyramid, light, method, lift, &|_| {})
}

fn surfaces() -> Vec<(&'static str, Dem)> {
    vec![
        (
            "hills",
            dem(150, 120, 5.0, 5.0, |x, y, r| {
                let (x, y) = (x as f32, y as f32);
                40.0 * (x * 0.13).sin() * (y * 0.09).cos()
                    + 25.0 * ((x - y) * 0.05).sin()
                    + 3.0 * r.next_f32()
            }),
        ),
        (
            "noise",
            dem(97, 83, 1.0, 1.0, |_, _, r| 30.0 * r.next_f32()),
        ),
        (
            "ridges",
            dem(90, 110, 2.0, 2.0, |x, y, r| {
                let ridge = x % 7 == 0 || y % 5 == 0 || (x + y) % 9 == 0 || (x + 200 - y) % 11 == 0;
                if ridge {
                    12.0 + r.next_f32()
                } else {
                    0.0
                }
            }),
        ),
        // Long, thin grids: octants along the long side have many more
        // columns than rows.
        (
            "thin strip",
            dem(400, 3, 3.0, 2.0, |x, y, r| {
                8.0 * ((x as f32) * 0.07).sin() + (y as f32) + 2.0 * r.next_f32()
            }),
        ),
        (
            "thin column",
            dem(4, 300, 1.0, 1.5, |x, y, r| {
                6.0 * ((y as f32) * 0.05).cos() + (x as f32) * 0.5 + r.next_f32()
            }),
        ),
        (
            "terraces, anisotropic cells",
            dem(101, 77, 2.0, 7.0, |x, y, _| {
                let (x, y) = (x as f32, y as f32);
                (((x * 0.11).sin() + (y * 0.07).cos()) * 3.0).round() * 5.0
            }),
        ),
    ]
}

/// Lights as fractions of the grid (x, y) and metres above the ground.
fn lights(field: &HeightField) -> Vec<(f64, f64, f64)> {
    let (w, h) = ((field.width - 1) as f64, (field.height - 1) as f64);
    let mut rng = Pcg32::new(5);
    let mut out = vec![
        // On a grid point, on a grid line each way, at the corners and edges.
        ((w / 2.0).round() / w, (h / 2.0).round() / h, 20.0),
        ((30.0 / w).min(1.0), 0.437, 6.0),
        (0.381, (40.0 / h).min(1.0), 6.0),
        (0.0, 0.0, 15.0),
        (1.0, 1.0, 40.0),
        (0.997, 0.03, 3.0),
        (0.5, 1.0, 0.7),
        // On the ground: on a grid point, on a grid line, anywhere, and
        // within a rounding step of it.
        ((w / 3.0).round() / w, (h / 4.0).round() / h, 0.0),
        (0.618, (50.0 / h).min(1.0), 0.0),
        (0.291, 0.733, 0.0),
        (0.8, 0.4, 1e-8),
    ];
    for _ in 0..6 {
        let height = [0.5, 4.0, 25.0, 400.0][rng.next_u32() as usize % 4];
        out.push((rng.next_f64(), rng.next_f64(), height));
    }
    out
}

#[test]
fn decided_points_agree_with_brute_force_and_the_fast_mask_is_exact() {
    for (name, dem) in surfaces() {
        let field = HeightField::new(&dem).unwrap();
        let pyramid = MaxMipmap::new(&field);
        let (wx, wy) = (
            (field.width - 1) as f64 * field.sx,
            (field.height - 1) as f64 * field.sy,
        );
        let (mut decided, mut total, mut lit, mut dark) = (0usize, 0usize, 0usize, 0usize);
        let (mut ground_decided, mut ground_total) = (0usize, 0usize);
        for (fx, fy, above) in lights(&field) {
            let pos = light_above_ground(&field, fx * wx, -fy * wy, above).unwrap();
            let light = Light::Point(pos);
            for lift in [0.0, 1.5] {
                let what = format!("{name}, light {pos:?}, targets {lift} m up");
                let brute = mask(&field, None, &light, ShadowMethod::BruteForce, lift);
                let swept =
                    point_light_mask(&field, pos, lift).expect("the light is over the grid");
                for (k, (&s, &b)) in swept.iter().zip(&brute).enumerate() {
                    if s != UNDECIDED {
                        assert_eq!(
                            s,
                            b,
                            "{what}: the sweep says {s} at (col {}, row {}), brute force {b}",
                            k % field.width,
                            k / field.width
                        );
                        decided += 1;
                        if s == 1 {
                            lit += 1;
                        } else {
                            dark += 1;
                        }
                    }
                }
                total += swept.len();
                if above < 1e-6 {
                    ground_total += swept.len();
                    ground_decided += swept.iter().filter(|&&s| s != UNDECIDED).count();
                }
                // With a pyramid given and without one (the leftovers are
                // marched).
                for pyramid in [Some(&pyramid), None] {
                    let fast = mask(&field, pyramid, &light, ShadowMethod::Fast, lift);
                    let differ = fast.iter().zip(&brute).filter(|(a, b)| a != b).count();
                    assert_eq!(differ, 0, "{what}: the fast mask differs on {differ} cells");
                }
            }
        }
        // The sweep must decide nearly everything, lights on the ground
        // included, or the comparison above tests the fallback instead; and
        // both answers must occur.
        let share = decided as f64 / total as f64;
        let ground_share = ground_decided as f64 / ground_total as f64;
        assert!(
            ground_share > 0.75,
            "{name}: the sweep decided {ground_share:.3} of the points for lights on the ground"
        );
        assert!(
            share > 0.85,
            "{name}: the sweep decided {share:.3} of the points"
        );
        assert!(
            lit > total / 20 && dark > total / 20,
            "{name}: {lit} lit, {dark} dark"
        );
    }
}

#[test]
fn lights_the_sweep_cannot_take_are_refused() {
    let (_, dem) = surfaces().remove(0);
    let field = HeightField::new(&dem).unwrap();
    let ground = light_above_ground(&field, 100.0, -100.0, 0.0).unwrap();
    // Below the ground, off the grid, or with a bad target height; a light
    // on the ground, or within a rounding step below it, is swept.
    assert!(point_light_mask(&field, ground, 0.0).is_some());
    assert!(point_light_mask(&field, [ground[0], ground[1], ground[2] - 1e-8], 0.0).is_some());
    assert!(point_light_mask(&field, [ground[0], ground[1], ground[2] - 5.0], 0.0).is_none());
    assert!(point_light_mask(&field, [-10.0, -100.0, 500.0], 0.0).is_none());
    assert!(point_light_mask(&field, [100.0, 10.0, 500.0], 0.0).is_none());
    let above = [ground[0], ground[1], ground[2] + 10.0];
    assert!(point_light_mask(&field, above, f64::NAN).is_none());
    assert!(point_light_mask(&field, above, -1.0).is_none());
    assert!(point_light_mask(&field, above, 0.0).is_some());
}

#[test]
fn ground_beside_the_light_is_bounded() {
    // The light 10 m above the top of a cone falling 9 m per cell, with a
    // spike of 9.9 m on the grid point just north of it: the spike shadows
    // points to the north, which nothing else does. The sweep's bound on the
    // part of an octant nearest the light must keep it from lighting them.
    let (lc, lr) = (20.0f32, 60.0f32);
    let dem = dem(100, 100, 1.0, 1.0, |x, y, _| {
        if (x, y) == (20, 59) {
            9.9
        } else {
            -9.0 * (x as f32 - lc).hypot(y as f32 - lr)
        }
    });
    let field = HeightField::new(&dem).unwrap();
    let pos = [lc as f64, -lr as f64, 10.0];
    let brute = mask(
        &field,
        None,
        &Light::Point(pos),
        ShadowMethod::BruteForce,
        0.0,
    );
    let swept = point_light_mask(&field, pos, 0.0).expect("the light is over the grid");
    for (k, (&s, &b)) in swept.iter().zip(&brute).enumerate() {
        if s != UNDECIDED {
            assert_eq!(s, b, "(col {}, row {})", k % 100, k / 100);
        }
    }
    // The spike's shadow is there to be missed.
    let dark = brute.iter().filter(|&&b| b == 0).count();
    assert!(dark > 1000, "{dark} points in shadow");
}

#[test]
fn small_grids_and_stray_lights_match_brute_force() {
    // Grids from 2 x 2 up, where octants have few columns or none, with
    // lights anywhere over them at heights from the ground up.
    let mut rng = Pcg32::new(23);
    for trial in 0..300 {
        let (w, h) = (
            2 + rng.next_u32() as usize % 7,
            2 + rng.next_u32() as usize % 7,
        );
        let dem = dem(
            w,
            h,
            1.0 + rng.next_f64(),
            1.0 + rng.next_f64(),
            |_, _, r| (8.0 * r.next_f32()).round(),
        );
        let field = HeightField::new(&dem).unwrap();
        // Some lights on grid points; a light a rounding step off the grid
        // is taken by the segment walk alone, and must match too.
        let (mut gx, mut gy) = (
            rng.next_f64() * (w - 1) as f64,
            rng.next_f64() * (h - 1) as f64,
        );
        if trial % 3 == 0 {
            (gx, gy) = (gx.round(), gy.round());
        }
        let above = [0.0, 0.01, 1.0, 9.0][trial % 4];
        let pos = [
            gx * field.sx,
            -gy * field.sy,
            field.height_at(gx, gy) + above,
        ];
        let light = Light::Point(pos);
        let lift = if trial % 2 == 0 { 0.0 } else { 0.5 };
        let brute = mask(&field, None, &light, ShadowMethod::BruteForce, lift);
        let fast = mask(&field, None, &light, ShadowMethod::Fast, lift);
        assert_eq!(fast, brute, "{w}x{h}, light {pos:?}, targets {lift} m up");
    }
}
