//! Work per shadow segment of the fast method, with and without blocker
//! hints: `cargo run --release -p raykit-terrain --example shadow_steps -- 2048`.

use raykit_terrain::shadow::{
    light_above_ground, occluded, occluded_with_hint, Light, ShadowMethod,
};
use raykit_terrain::{HeightField, MaxMipmap, Steps};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map_or(1024, |a| a.parse().expect("a size"));
    let dem = raykit_terrain::fractal::fractal(n, 1, 0.55);
    let field = HeightField::new(&dem).unwrap();
    let pyramid = MaxMipmap::new(&field);
    let (wx, wy) = ((n - 1) as f64 * field.sx, (n - 1) as f64 * field.sy);
    let light = Light::Point(light_above_ground(&field, 0.5 * wx, -0.5 * wy, 50.0).unwrap());
    let (mut plain, mut hinted) = (Steps::default(), Steps::default());
    let mut lit = 0;
    let t = std::time::Instant::now();
    for row in (0..n).step_by(8) {
        for col in 0..n {
            lit += usize::from(!occluded(
                &field,
                &pyramid,
                &light,
                col,
                row,
                ShadowMethod::Fast,
                &mut plain,
            ));
        }
    }
    let a = t.elapsed();
    let t = std::time::Instant::now();
    for row in (0..n).step_by(8) {
        let mut hint = None;
        for col in 0..n {
            occluded_with_hint(
                &field,
                &pyramid,
                &light,
                col,
                row,
                ShadowMethod::Fast,
                &mut hint,
                &mut hinted,
            );
        }
    }
    let b = t.elapsed();
    let rays = (n * n.div_ceil(8)) as f64;
    println!("lit {:.1}%: plain {:.1} nodes {:.2} cells per ray {:?}; hinted {:.1} nodes {:.2} cells {:?}", 100.0 * lit as f64 / rays, plain.nodes as f64 / rays, plain.cells as f64 / rays, a, hinted.nodes as f64 / rays, hinted.cells as f64 / rays, b);
}
