//! The GPU terrain casters (per-ray maximum-mipmap traversal, Tevs et al.
//! 2008; per-frame quadtree boxes; in f32) against
//! the CPU's f64 casters of the same kind on every pixel of test views of the test DEMs and a fractal
//! one: same hit or miss and same hit cell, distances within 1e-4
//! relative. Pixels may differ only where f32 rounding decides: each
//! difference must be explained and they must be under 0.1% of the pixels.

mod support;

use raykit_gpu::terrain::GpuGridRay;
use raykit_gpu::{time_terrain_boxes, time_terrain_casts, GpuCaster, GpuTerrain};
use raykit_terrain::io::{load_dem, LoadOptions};
use raykit_terrain::maxmip::trace;
use raykit_terrain::view::{cast_image, Caster};
use raykit_terrain::{GridRay, HeightField, MaxMipmap, Steps, TerrainCamera, TerrainHit};
use support::{gpu, shared_data};

/// Relative distance tolerance.
const REL_T: f64 = 1e-4;

/// Grazing: the ray's height above the surface, relative to the height's
/// magnitude plus the distance travelled (the scale of f32's rounding of
/// the ray and of the kernel's plane tests).
const GRAZE: f64 = 1e-5;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= REL_T * a.abs().max(b.abs()).max(1e-6)
}

/// Same cell and distance.
fn same(a: &Option<TerrainHit>, b: &Option<TerrainHit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => (a.col, a.row) == (b.col, b.row) && close(a.t, b.t),
        _ => false,
    }
}

/// Neighbouring cells (sharing an edge or a corner) at the same distance:
/// a hit on their common border.
fn border_tie(a: &Option<TerrainHit>, b: &Option<TerrainHit>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => {
            a.col.abs_diff(b.col) <= 1 && a.row.abs_diff(b.row) <= 1 && close(a.t, b.t)
        }
        _ => false,
    }
}

/// How the pixels where the GPU and the CPU differ are explained.
#[derive(Debug, Default)]
struct Agreement {
    pixels: usize,
    hits: usize,
    /// The CPU's f64 caster on the GPU's f32-rounded ray gives the GPU's
    /// answer: the difference is the ray's rounding.
    rounding: usize,
    /// Neighbouring cells at the same distance (a hit on a cell border).
    border: usize,
    /// The nearer of the two answers is a point the CPU's f64 ray passes
    /// within [`GRAZE`] of (height above the surface, relative): the ray
    /// grazes the surface there, and which side of it f32 rounding puts the
    /// ray decides hit or miss.
    grazing: usize,
    /// Largest relative clearance among the grazing pixels.
    max_graze: f64,
    /// Not explained (must be none).
    unexplained: Vec<String>,
    /// One line per explained difference.
    notes: Vec<String>,
    /// Pixels whose step counts equal the CPU's.
    same_steps: usize,
}

impl Agreement {
    fn differing(&self) -> usize {
        self.rounding + self.border + self.grazing + self.unexplained.len()
    }
}

/// The relative clearance of `ray` above the surface at `t`.
fn clearance(field: &HeightField, ray: &GridRay, t: f64) -> f64 {
    let p = ray.at(t);
    (p[2] - field.height_at(p[0], p[1])).abs() / (p[2].abs() + t.abs()).max(1.0)
}

/// The clearance of `ray` at the nearer of two answers.
fn graze(
    field: &HeightField,
    ray: &GridRay,
    a: &Option<TerrainHit>,
    b: &Option<TerrainHit>,
) -> f64 {
    let t = match (a, b) {
        (Some(a), Some(b)) => a.t.min(b.t),
        (Some(h), None) | (None, Some(h)) => h.t,
        (None, None) => return 0.0,
    };
    clearance(field, ray, t)
}

/// The CPU's maximum-mipmap caster on the ray as the GPU sees it.
fn cpu_on_gpu_ray(field: &HeightField, pyramid: &MaxMipmap, r: &GpuGridRay) -> Option<TerrainHit> {
    if !r.meets_grid() {
        return None;
    }
    let mut steps = Steps::default();
    trace(
        field,
        pyramid,
        &r.grid_ray(),
        0.0,
        f64::INFINITY,
        &mut steps,
    )
    .map(|h| TerrainHit { t: h.t + r.t0, ..h })
}

fn compare(
    field: &HeightField,
    pyramid: &MaxMipmap,
    cam: &TerrainCamera,
    caster: GpuCaster,
    what: &str,
) -> Agreement {
    let ctx = gpu();
    let cpu = cast_image(
        field,
        pyramid,
        cam,
        match caster {
            GpuCaster::MaxMipmap => Caster::MaxMipmap,
            GpuCaster::Boxes { tau } => Caster::Boxes { tau },
        },
    );
    let terrain = GpuTerrain::new(ctx, field, pyramid).unwrap();
    let got = terrain.cast(ctx, field, pyramid, cam, caster).unwrap();
    let rays = raykit_gpu::terrain::view_rays(field, cam, 0, cpu.hits.len());
    let mut a = Agreement {
        pixels: cpu.hits.len(),
        hits: cpu.hits.iter().filter(|h| h.is_some()).count(),
        ..Agreement::default()
    };
    assert_eq!(got.hits.len(), a.pixels);
    let frame = cam.frame();
    let w = cam.width as usize;
    for (k, (c, g)) in cpu.hits.iter().zip(&got.hits).enumerate() {
        if got.steps[k] == cpu.steps[k] {
            a.same_steps += 1;
        }
        if same(c, g) {
            continue;
        }
        let rounded = cpu_on_gpu_ray(field, pyramid, &rays[k]);
        let ray = frame.ray(field, (k % w) as u32, (k / w) as u32);
        let clear = graze(field, &ray, c, g);
        if same(&rounded, g) {
            a.rounding += 1;
            a.notes.push(format!(
                "{what} pixel {k}: ray rounding, cpu {c:?} gpu {g:?}"
            ));
        } else if border_tie(c, g) || border_tie(&rounded, g) {
            a.border += 1;
            a.notes
                .push(format!("{what} pixel {k}: border tie, cpu {c:?} gpu {g:?}"));
        } else if clear <= GRAZE {
            a.grazing += 1;
            a.max_graze = a.max_graze.max(clear);
            a.notes.push(format!(
                "{what} pixel {k}: grazing (clearance {clear:.1e}), cpu {c:?} gpu {g:?}"
            ));
        } else {
            a.unexplained.push(format!(
                "{what} pixel {k} ({}, {}): cpu {c:?} gpu {g:?}, cpu on the f32 ray {rounded:?}, \
                 clearance {clear:e}, ray {:?}",
                k % cam.width as usize,
                k / cam.width as usize,
                rays[k]
            ));
        }
    }
    eprintln!(
        "{what}: {} pixels, {} hits; differing {} (rounding of the ray {}, border ties {}, \
         grazing {} (clearance <= {:.1e}), unexplained {}); steps equal on {}",
        a.pixels,
        a.hits,
        a.differing(),
        a.rounding,
        a.border,
        a.grazing,
        a.max_graze,
        a.unexplained.len(),
        a.same_steps
    );
    for n in &a.notes {
        eprintln!("  {n}");
    }
    a
}

/// Test views: a low oblique view across the whole terrain (most rays
/// graze), one from inside looking along a row, one straight down.
fn views(field: &HeightField) -> Vec<TerrainCamera> {
    let (wx, wy) = (
        (field.width - 1) as f64 * field.sx,
        (field.height - 1) as f64 * field.sy,
    );
    let z = field.zmax as f64;
    let span = wx.max(wy);
    vec![
        TerrainCamera {
            eye: [-0.1 * wx, 0.1 * wy, z + 0.05 * span],
            target: [0.6 * wx, -0.6 * wy, field.zmin as f64],
            vfov_deg: 50.0,
            width: 160,
            height: 120,
        },
        TerrainCamera {
            eye: [0.5 * wx, -0.5 * wy, z + 10.0],
            target: [wx, -0.5 * wy, z - 20.0],
            vfov_deg: 70.0,
            width: 160,
            height: 120,
        },
        TerrainCamera {
            eye: [0.3 * wx, -0.3 * wy, z + span],
            target: [0.3 * wx + 1e-3, -0.3 * wy, 0.0],
            vfov_deg: 40.0,
            width: 120,
            height: 120,
        },
    ]
}

fn check_dem(name: &str, field: &HeightField) {
    let pyramid = MaxMipmap::new(field);
    let mut total = Agreement::default();
    let casters = [GpuCaster::MaxMipmap, GpuCaster::Boxes { tau: 16.0 }];
    for (v, cam) in views(field).iter().enumerate() {
        for caster in casters {
            let a = compare(
                field,
                &pyramid,
                cam,
                caster,
                &format!("{name} {caster:?} view {v}"),
            );
            assert!(a.hits > 0, "{name} view {v} sees no terrain");
            total.pixels += a.pixels;
            total.rounding += a.rounding;
            total.border += a.border;
            total.grazing += a.grazing;
            total.unexplained.extend(a.unexplained);
        }
    }
    assert!(
        total.unexplained.is_empty(),
        "{name}: {} pixels differ unexplained:\n{}",
        total.unexplained.len(),
        total.unexplained[..total.unexplained.len().min(5)].join("\n")
    );
    assert!(
        total.differing() * 1000 < total.pixels,
        "{name}: {} of {} pixels differ (explained, but more than 0.1%)",
        total.differing(),
        total.pixels
    );
}

fn shared_dem(file: &str) -> HeightField {
    let path = shared_data().join("terrain").join(file);
    assert!(path.is_file(), "{} is missing", path.display());
    let dem = load_dem(&path, &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    HeightField::new(&dem).unwrap()
}

#[test]
fn gpu_casters_equal_cpu_on_the_lidar_dem() {
    check_dem("lidar_dem_400.tif", &shared_dem("lidar_dem_400.tif"));
}

#[test]
fn gpu_casters_equal_cpu_on_srtm() {
    check_dem("N57E011.hgt", &shared_dem("N57E011.hgt"));
}

#[test]
fn gpu_casters_equal_cpu_on_terragen() {
    check_dem(
        "RealisticTerrain_Large.ter",
        &shared_dem("RealisticTerrain_Large.ter"),
    );
}

#[test]
fn gpu_casters_equal_cpu_on_a_fractal() {
    let dem = raykit_terrain::fractal::fractal(513, 7, 0.55);
    check_dem("fractal:513:7", &HeightField::new(&dem).unwrap());
}

#[test]
fn timing_reports_throughput() {
    let dem = raykit_terrain::fractal::fractal(129, 3, 0.55);
    let field = HeightField::new(&dem).unwrap();
    let pyramid = MaxMipmap::new(&field);
    let cam = views(&field)[0];
    let t = time_terrain_casts(gpu(), &field, &pyramid, &cam, 2).unwrap();
    assert_eq!(t.rays, 160 * 120);
    assert_eq!(t.seconds.len(), 2);
    assert!(t.best_mrays > 0.0 && t.best_mrays >= t.median_mrays);
    assert!(t.hits > 0 && t.mean_steps > 1.0);
    let b = time_terrain_boxes(gpu(), &field, &pyramid, &cam, 16.0, 2).unwrap();
    assert_eq!(b.hits, t.hits);
}

#[test]
fn oversized_grids_are_refused_with_a_reason() {
    let dem = raykit_terrain::Dem::from_heights(65_537, 2, vec![1.0; 65_537 * 2]);
    let field = HeightField::new(&dem).unwrap();
    let pyramid = MaxMipmap::new(&field);
    let err = GpuTerrain::new(gpu(), &field, &pyramid)
        .err()
        .expect("refused");
    let text = err.to_string();
    assert!(
        text.contains("65537x2") && text.contains("65535 cells"),
        "{text}"
    );
}

/// A DEM whose heights exceed one storage binding (a 16k² DEM on many
/// devices) is refused naming the buffer and the limit, never panics: the
/// device's limit is lowered here to make a small DEM too big.
#[test]
fn a_dem_over_the_binding_limit_names_the_limit() {
    let mut ctx = gpu().clone();
    ctx.limits.max_storage_buffer_binding_size = 4096;
    let field = HeightField::new(&raykit_terrain::fractal::fractal(65, 1, 0.55)).unwrap();
    let pyramid = MaxMipmap::new(&field);
    let err = GpuTerrain::new(&ctx, &field, &pyramid)
        .err()
        .expect("refused");
    let text = err.to_string();
    assert!(
        text.contains("heights of a 65x65 DEM") && text.contains("max_storage_buffer_binding_size"),
        "{text}"
    );
}
