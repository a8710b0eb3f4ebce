//! Load each mesh named on the command line and print its size and load time.
//!
//! `cargo run --release -p raykit-io --example load_time -- dragon_vrip.ply.gz`

use std::time::Instant;

fn main() {
    let mut failed = false;
    for arg in std::env::args().skip(1) {
        let t0 = Instant::now();
        match raykit_io::load(std::path::Path::new(&arg)) {
            Ok(l) => {
                let dt = t0.elapsed();
                println!(
                    "{arg}: {} vertices, {} triangles, {:?}{} in {:.3} s",
                    l.mesh.positions.len(),
                    l.mesh.num_triangles(),
                    l.format,
                    if l.gzip { " gzip" } else { "" },
                    dt.as_secs_f64()
                );
                for w in &l.warnings {
                    println!("  warning: {w}");
                }
            }
            Err(e) => {
                eprintln!("{e}");
                failed = true;
            }
        }
    }
    if failed {
        std::process::exit(1);
    }
}
