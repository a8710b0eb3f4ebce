//! Cull a mesh file by rays and print what each step found:
//! `cargo run --release -p raykit-cull --example cull_by_rays -- MODEL
//! [ROUNDS [MIN_OPENING [FRONTIER_FACTOR]]]`. MODEL `shell:ENGINE.glb` or
//! `hole:ENGINE.glb` culls eight copies of ENGINE in a closed box shell of
//! 100 × 100 squares per face (with a 20 × 20-square hole).

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_cull::rays::visible_by_rays_with_progress;
use raykit_cull::RayOptions;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: cull_by_rays MODEL [ROUNDS]")?;
    let mesh = match path.split_once(':') {
        Some((kind @ ("shell" | "hole"), file)) => {
            let engine = raykit_io::load_mesh(std::path::Path::new(file))?;
            let eight = raykit_cull::synthetic::copies(&engine, [2, 2, 2], 0.1);
            let hole = (kind == "hole").then_some(20);
            raykit_cull::synthetic::shell_around(&eight, 0.05, 100, hole)
        }
        _ => raykit_io::load_mesh(std::path::Path::new(&path))?,
    };
    let mut options = RayOptions::default();
    if let Some(r) = args.next() {
        options.max_rounds = r.parse()?;
    }
    if let Some(w) = args.next() {
        options.min_opening = w.parse()?;
    }
    if let Some(f) = args.next() {
        options.frontier_factor = f.parse()?;
    }
    let clock = Instant::now();
    let accel = build_accel(
        AccelKind::Bvh8,
        TestKind::Moller,
        &mesh,
        &BuildOptions::default(),
    );
    println!(
        "{} triangles, BVH8 in {:.2} s",
        mesh.num_triangles(),
        clock.elapsed().as_secs_f64()
    );
    let clock = Instant::now();
    let (visible, stats) = visible_by_rays_with_progress(&mesh, accel.as_ref(), &options, &|s| {
        println!(
            "{:7.2} s: views {} ({:.2} s), escapes {}, rays {}, last round {:?}",
            clock.elapsed().as_secs_f64(),
            s.by_views,
            s.views_seconds,
            s.by_escape_rays,
            s.rays,
            s.round_log.last()
        );
    });
    let kept = visible.iter().filter(|&&v| v).count();
    let parts = mesh.parts.len().max(1);
    let mut part_kept = vec![false; parts];
    for (t, &v) in visible.iter().enumerate() {
        part_kept[mesh.part_of(t) as usize] |= v;
    }
    println!(
        "parts kept {} of {parts}",
        part_kept.iter().filter(|&&k| k).count()
    );
    println!(
        "kept {kept} of {} in {:.2} s; rounds {}, converged {}, rays/removed {}",
        visible.len(),
        clock.elapsed().as_secs_f64(),
        stats.rounds,
        stats.converged,
        stats.rays_per_removed
    );
    Ok(())
}
