//! GPU against CPU terrain ray casting on one view: the maximum-mipmap
//! kernel's Mrays/s (Tevs et al. 2008) and the
//! quadtree-box caster's boxes kernel (kernel time, submission to completion) beside the
//! CPU's maxmip and boxes casters (all cores, rays made and cast).
//!
//! `cargo run --release -p raykit-gpu --example terrain_timing -- DEM [WIDTH HEIGHT REPS]`
//! with DEM a file raykit-terrain reads or `fractal:SIZE`.

use raykit_gpu::{time_terrain_boxes, time_terrain_casts, GpuContext};
use raykit_terrain::io::{load_dem, LoadOptions};
use raykit_terrain::view::{cast_image, Caster};
use raykit_terrain::{HeightField, MaxMipmap, TerrainCamera};
use std::time::Instant;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dem_arg = args
        .first()
        .ok_or("usage: terrain_timing DEM [WIDTH HEIGHT REPS]")?;
    let num = |k: usize, d: u32| -> Result<u32, String> {
        args.get(k).map_or(Ok(d), |s| {
            s.parse().map_err(|e| format!("argument {k}: {e}"))
        })
    };
    let (w, h, reps) = (num(1, 800)?, num(2, 600)?, num(3, 5)?);
    let dem = match dem_arg.strip_prefix("fractal:") {
        Some(n) => raykit_terrain::fractal::fractal(
            n.parse().map_err(|e| format!("{dem_arg}: {e}"))?,
            7,
            0.55,
        ),
        None => load_dem(dem_arg, &LoadOptions::default()).map_err(|e| e.to_string())?,
    };
    let field = HeightField::new(&dem)?;
    let pyramid = MaxMipmap::new(&field);
    let (wx, wy) = (
        (field.width - 1) as f64 * field.sx,
        (field.height - 1) as f64 * field.sy,
    );
    // A low oblique view across the whole terrain from its north-west corner.
    let cam = TerrainCamera {
        eye: [-0.1 * wx, 0.1 * wy, field.zmax as f64 + 0.05 * wx.max(wy)],
        target: [0.6 * wx, -0.6 * wy, field.zmin as f64],
        vfov_deg: 50.0,
        width: w,
        height: h,
    };
    let ctx = GpuContext::new().map_err(|e| e.to_string())?;
    let t = time_terrain_casts(&ctx, &field, &pyramid, &cam, reps as usize)
        .map_err(|e| e.to_string())?;
    println!(
        "{dem_arg} {}x{} samples, view {w}x{h}, {} hits, {:.1} steps/ray",
        field.width, field.height, t.hits, t.mean_steps
    );
    println!(
        "device {}: storage binding limit {} MiB",
        ctx.describe(),
        ctx.limits.max_storage_buffer_binding_size >> 20
    );
    println!(
        "gpu maxmip ({}): best {:.2} Mrays/s, median {:.2} (kernel); setup {:.0} ms, rays {:.0} ms",
        ctx.describe(),
        t.best_mrays,
        t.median_mrays,
        t.setup_seconds * 1e3,
        t.ray_seconds * 1e3
    );
    let b = time_terrain_boxes(&ctx, &field, &pyramid, &cam, 16.0, reps as usize)
        .map_err(|e| e.to_string())?;
    println!(
        "gpu boxes tau 16: best {:.2} Mrays/s, median {:.2} (kernel); boxes selected and rays {:.0} ms",
        b.best_mrays,
        b.median_mrays,
        b.ray_seconds * 1e3
    );
    for (name, caster) in [
        ("maxmip", Caster::MaxMipmap),
        ("boxes tau 16", Caster::Boxes { tau: 16.0 }),
    ] {
        let mut best = f64::MAX;
        for _ in 0..reps.max(1) {
            let start = Instant::now();
            let img = cast_image(&field, &pyramid, &cam, caster);
            best = best.min(start.elapsed().as_secs_f64());
            std::hint::black_box(img);
        }
        println!(
            "cpu {name} ({} threads): best {:.2} Mrays/s",
            rayon::current_num_threads(),
            (w as f64 * h as f64) / best / 1e6
        );
    }
    Ok(())
}
