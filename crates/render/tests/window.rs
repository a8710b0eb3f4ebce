//! Crop windows against the whole frame: rendering rectangles separately
//! and pasting them together gives the whole frame's image bit for bit, for
//! both renderers, every integrator and primary source, and jittered
//! samples.

use raykit_render::whitted::{Frame, IntegratorKind, PrimaryMode, WhittedOptions};
use raykit_render::{render, RenderOptions, Tile};

#[path = "support/builtin_frame.rs"]
mod builtin_frame;
use builtin_frame::{whitted_frame, whitted_scene};

/// Windows that cover a `w` × `h` frame once: uneven bands and a grid of
/// rectangles that do not line up with the renderer's 32-pixel tiles.
fn splits(w: u32, h: u32) -> Vec<Vec<Tile>> {
    let bands = (0..3).map(|i| Tile::band(i, 3, w, h).unwrap()).collect();
    let cols = [0, 13, 50, w];
    let rows = [0, 29, h];
    let mut grid = Vec::new();
    for r in rows.windows(2) {
        for c in cols.windows(2) {
            grid.push(Tile {
                x: c[0],
                y: r[0],
                width: c[1] - c[0],
                height: r[1] - r[0],
            });
        }
    }
    vec![bands, grid]
}

/// Paste per-window values (row-major within each window) into a frame.
fn paste<T: Copy + Default>(w: u32, h: u32, parts: &[(Tile, Vec<T>)], per_pixel: usize) -> Vec<T> {
    let mut out = vec![T::default(); (w * h) as usize * per_pixel];
    for (t, v) in parts {
        assert_eq!(v.len(), t.pixels() as usize * per_pixel);
        for (i, (x, y)) in t.coords().enumerate() {
            let dst = (y * w + x) as usize * per_pixel;
            out[dst..dst + per_pixel].copy_from_slice(&v[i * per_pixel..(i + 1) * per_pixel]);
        }
    }
    out
}

#[test]
fn whitted_windows_assemble_into_the_whole_frame() {
    let (w, h) = (77u32, 58u32);
    for (spp, integrator, primary) in [
        (1, IntegratorKind::Recursive, PrimaryMode::Traced),
        (3, IntegratorKind::Recursive, PrimaryMode::Traced),
        (2, IntegratorKind::Wavefront, PrimaryMode::Traced),
        (1, IntegratorKind::Recursive, PrimaryMode::Rasterized),
    ] {
        let opts = WhittedOptions {
            width: w,
            height: h,
            samples_per_pixel: spp,
            integrator,
            primary,
            ..WhittedOptions::default()
        };
        let whole = whitted_frame(&opts);
        for split in splits(w, h) {
            let parts: Vec<Frame> = split
                .iter()
                .map(|t| {
                    whitted_frame(&WhittedOptions {
                        window: Some(*t),
                        ..opts.clone()
                    })
                })
                .collect();
            let rgb: Vec<(Tile, Vec<u8>)> = split
                .iter()
                .zip(&parts)
                .map(|(t, f)| {
                    assert_eq!((f.image.width, f.image.height), (t.width, t.height));
                    (*t, f.image.rgb.clone())
                })
                .collect();
            let what = format!(
                "{spp} spp {integrator:?} {primary:?}, {} windows",
                split.len()
            );
            assert!(
                paste(w, h, &rgb, 3) == whole.image.rgb,
                "{what}: 8-bit image"
            );
            let bits = |f: &Frame| -> Vec<u32> {
                f.image
                    .linear
                    .iter()
                    .flat_map(|c| c.to_array().map(f32::to_bits))
                    .collect()
            };
            let linear: Vec<(Tile, Vec<u32>)> = split
                .iter()
                .zip(&parts)
                .map(|(t, f)| (*t, bits(f)))
                .collect();
            assert!(
                paste(w, h, &linear, 3) == bits(&whole),
                "{what}: linear image"
            );
            let hits: Vec<(Tile, Vec<_>)> = split
                .iter()
                .zip(&parts)
                .map(|(t, f)| (*t, f.first_hits.clone()))
                .collect();
            assert!(
                paste(w, h, &hits, 1) == whole.first_hits,
                "{what}: first hits"
            );
        }
    }
}

#[test]
fn blinn_phong_windows_assemble_into_the_whole_frame() {
    let (scene, accel) = whitted_scene();
    let camera = scene.camera.unwrap();
    let (w, h) = (70u32, 45u32);
    for spp in [1, 4] {
        let opts = RenderOptions {
            width: w,
            height: h,
            samples_per_pixel: spp,
            ..RenderOptions::default()
        };
        let draw = |o: &RenderOptions| {
            render(
                &scene.mesh,
                &scene.lights,
                accel.as_ref(),
                &camera,
                o,
                &|_| {},
            )
        };
        let whole = draw(&opts);
        for split in splits(w, h) {
            let parts: Vec<(Tile, Vec<u8>)> = split
                .iter()
                .map(|t| {
                    let img = draw(&RenderOptions {
                        window: Some(*t),
                        ..opts.clone()
                    });
                    assert_eq!((img.width, img.height), (t.width, t.height));
                    (*t, img.rgb)
                })
                .collect();
            assert!(
                paste(w, h, &parts, 3) == whole.rgb,
                "{spp} spp, {} windows",
                split.len()
            );
        }
    }
    // A window reaching past the frame is clipped to it.
    let clipped = draw_window(
        &scene,
        accel.as_ref(),
        &camera,
        w,
        h,
        Tile {
            x: 60,
            y: 40,
            width: 50,
            height: 50,
        },
    );
    assert_eq!((clipped.width, clipped.height), (10, 5));
}

fn draw_window(
    scene: &raykit_scene::Scene,
    accel: &dyn raykit_core::Accel,
    camera: &raykit_core::Camera,
    w: u32,
    h: u32,
    window: Tile,
) -> raykit_render::Image {
    let opts = RenderOptions {
        width: w,
        height: h,
        window: Some(window),
        ..RenderOptions::default()
    };
    render(&scene.mesh, &scene.lights, accel, camera, &opts, &|_| {})
}
