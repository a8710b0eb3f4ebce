//! Quick timing of the three terrain casters on a synthetic DEM:
//! `cargo run --release -p raykit-terrain --example cast_speed -- 2049 400 225`
//! (grid size, image width and height). `raykit experiment terrain` is the
//! full, recorded measurement.

use raykit_terrain::view::{cast_image, Caster};
use raykit_terrain::{Dem, HeightField, MaxMipmap, TerrainCamera};
use std::time::Instant;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("numbers"))
        .collect();
    let (n, w, h) = (
        args.first().copied().unwrap_or(1025),
        args.get(1).copied().unwrap_or(400),
        args.get(2).copied().unwrap_or(225),
    );
    let heights = (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as f32, (k / n) as f32);
            300.0 * (x * 0.004).sin() * (y * 0.003).cos()
                + 80.0 * ((x * 0.031).sin() + (y * 0.027).cos())
                + 20.0 * ((x + 2.0 * y) * 0.1).sin()
        })
        .collect();
    let mut dem = Dem::from_heights(n, n, heights);
    dem.georef.pixel_width = 10.0;
    dem.georef.pixel_height = -10.0;
    let field = HeightField::new(&dem).unwrap();
    let t = Instant::now();
    let pyramid = MaxMipmap::new(&field);
    eprintln!(
        "{n}² grid, pyramid {:.0} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
    let span = (n - 1) as f64 * 10.0;
    let cam = TerrainCamera {
        eye: [0.05 * span, -0.05 * span, 900.0],
        target: [0.6 * span, -0.7 * span, 0.0],
        vfov_deg: 50.0,
        width: w as u32,
        height: h as u32,
    };
    let mut reference = None;
    for caster in [
        Caster::March,
        Caster::MaxMipmap,
        Caster::Boxes { tau: 4.0 },
        Caster::Boxes { tau: 16.0 },
        Caster::Boxes { tau: 64.0 },
    ] {
        let t = Instant::now();
        let img = cast_image(&field, &pyramid, &cam, caster);
        let s = t.elapsed().as_secs_f64();
        let cells: u64 = img.steps.iter().map(|s| s.cells as u64).sum();
        let nodes: u64 = img.steps.iter().map(|s| s.nodes as u64).sum();
        let hits: Vec<_> = img.hits.iter().map(|h| h.map(|h| (h.col, h.row))).collect();
        let same = reference.as_ref().is_none_or(|r: &Vec<_>| *r == hits);
        reference.get_or_insert(hits);
        println!("{caster:?}: {:.1} ms, {:.1} cells/ray, {:.1} nodes/ray, boxes {}, same hit cells as march: {same}", s * 1e3, cells as f64 / (w * h) as f64, nodes as f64 / (w * h) as f64, img.boxes);
    }
}
