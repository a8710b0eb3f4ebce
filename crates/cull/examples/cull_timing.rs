//! Times Min's (2008) culling on a box of icospheres (1,280,192 triangles at
//! the defaults): `cargo run --release -p raykit-cull --example cull_timing
//! -- [RESOLUTION] [SPHERES_PER_AXIS] [SUBDIVISIONS]`.

use raykit_cull::synthetic::box_of_spheres;
use raykit_cull::{cull, CullOptions};

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let res = args.first().copied().unwrap_or(256);
    let k = args.get(1).copied().unwrap_or(10);
    let s = args.get(2).copied().unwrap_or(3) as u32;
    let mesh = box_of_spheres(4, k, s);
    println!(
        "{} triangles, {} parts",
        mesh.num_triangles(),
        mesh.parts.len()
    );
    for (name, options) in [
        ("paper", CullOptions::paper(res)),
        ("conservative", CullOptions::conservative(res)),
    ] {
        let t = std::time::Instant::now();
        let r = cull(&mesh, &options).expect("valid mesh");
        println!(
            "{name}: total {:.2} s\n{}",
            t.elapsed().as_secs_f64(),
            serde_json::to_string_pretty(&r.stats).unwrap()
        );
    }
}
