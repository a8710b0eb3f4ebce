//! `raykit experiment terrain`: (a) speed of the
//! per-frame box method against the per-cell march and per-ray maximum
//! mipmap for τ = 4..4096 at 1600×900 on a 4096² DEM, with heat maps of the
//! steps per ray; (b) Min's (2008) terrain shadow-map times for growing DEMs,
//! brute force against the fast method; (c) gdal_viewshed on the same DEM
//! and light, in the same run: time ratio and the cells where the masks
//! differ.

use super::{write_csv, write_text};
use crate::args::ranges::{self, image_side, in_range};
use crate::measure::{median_min_max, median_ms, spread, spread_percent, timed};
use crate::plot::{write_svg, LineChart, Series};
use anyhow::{bail, Context, Result};
use clap::Args;
use raykit_terrain::shadow::{light_above_ground, shadow_mask, Light, ShadowMethod};
use raykit_terrain::view::{cast_image, CastImage, Caster};
use raykit_terrain::{Dem, HeightField, MaxMipmap, TerrainCamera};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

/// Speed of the box method: τ, speed ratio A:B (box vs per-cell), A:C (box vs
/// per-ray max mipmap), Radeon HD5870, 1600×900, Puget Sound 4096².
const PAPER_TABLE1: [(f64, f64, f64); 11] = [
    (4.0, 8.0, 0.89),
    (8.0, 29.0, 3.22),
    (16.0, 42.5, 4.72),
    (32.0, 26.0, 2.89),
    (64.0, 15.5, 1.72),
    (128.0, 11.0, 1.22),
    (256.0, 9.5, 1.07),
    (512.0, 5.0, 0.55),
    (1024.0, 3.0, 0.33),
    (2048.0, 1.5, 0.16),
    (4096.0, 1.0, 0.111),
];

/// The most views of part (a)'s fly-through (`--flythrough`).
const MAX_VIEWS: usize = 1000;

/// Arguments of `raykit experiment terrain`.
#[derive(Args)]
#[command(
    after_help = "The DEM is generated (fractal:SIZE, seed 1, 10 m cells, 0..2000 m) so every run sees the\n\
same data. Part (c) needs gdal_viewshed (apt-get install gdal-bin; scripts/terrain-experiment.sh\n\
installs it and runs this command); without it part (c) is reported as skipped.\n\
Writes results.md, CSV, heat maps (PNG) and SVG plots into --out."
)]
pub struct TerrainExperimentArgs {
    /// Side of the generated DEM of parts (a) and (c).
    #[arg(long, default_value_t = 4096)]
    size: usize,
    /// Image width of part (a), 1 to 16384.
    #[arg(long, default_value_t = 1600)]
    width: u32,
    /// Image height of part (a), 1 to 16384.
    #[arg(long, default_value_t = 900)]
    height: u32,
    /// τ values of part (a).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "4,8,16,32,64,128,256,512,1024,2048,4096"
    )]
    taus: Vec<f64>,
    /// DEM sides of part (b).
    #[arg(long, value_delimiter = ',', default_value = "256,512,1024,2048,4096")]
    shadow_sizes: Vec<usize>,
    /// Views of part (a): 1 is the single view of Table 1 of the quadtree terrain ray-casting paper; more
    /// fly along the DEM's diagonal (each view moved by an equal step to the
    /// north-east, same direction), and part (a) reports the average frame;
    /// 1 to 1000.
    #[arg(long, default_value_t = 1)]
    flythrough: usize,
    /// Repetitions (medians are reported), 1 to 1000; the brute-force shadow
    /// masks of DEMs above 1024² run once.
    #[arg(long, default_value_t = 3)]
    reps: usize,
    /// Parts to run: any of a, b, c.
    #[arg(long, value_delimiter = ',', default_value = "a,b,c")]
    parts: Vec<char>,
    /// Part (c) on this DEM file (e.g. a GeoTIFF warped by gdalwarp)
    /// instead of the generated one.
    #[arg(long, value_name = "FILE")]
    gdal_dem: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "experiments/terrain")]
    out: PathBuf,
}

#[derive(Serialize)]
struct CastRow {
    method: String,
    tau: Option<f64>,
    ms: f64,
    noise: Option<f64>,
    boxes: usize,
    cells_per_ray: f64,
    nodes_per_ray: f64,
    speedup_vs_march: f64,
    speedup_vs_maxmip: f64,
    paper_vs_march: Option<f64>,
    paper_vs_maxmip: Option<f64>,
    pixels_differing_from_march: usize,
}

#[derive(Serialize)]
struct ShadowRow {
    size: usize,
    light: String,
    brute_s: f64,
    fast_s: f64,
    speedup: f64,
    cells_differing: usize,
    lit_pct: f64,
}

#[derive(Serialize)]
struct GdalRow {
    dem: String,
    light: String,
    /// The mask alone, in this process.
    ours_s: f64,
    /// `raykit terrain shadow` as a command: load, mask, GeoTIFF, preview.
    ours_command_s: Option<f64>,
    /// Spread of the command's runs, (max − min) / median.
    ours_noise: Option<f64>,
    gdal_s: Option<f64>,
    gdal_noise: Option<f64>,
    ours_over_gdal: Option<f64>,
    cells_differing_pct: Option<f64>,
    lit_by_us_shadowed_by_gdal: Option<usize>,
    shadowed_by_us_lit_by_gdal: Option<usize>,
    note: String,
}

/// Views flying over the DEM from the south-west, like a flight over
/// terrain: the first looks from the south-west corner towards the middle,
/// the others are moved along the diagonal by equal steps (at most 35% of
/// the DEM's width and height in all), looking the same way.
fn flight_cameras(
    field: &HeightField,
    width: u32,
    height: u32,
    views: usize,
) -> Vec<TerrainCamera> {
    let (wx, wy) = (
        (field.width - 1) as f64 * field.sx,
        (field.height - 1) as f64 * field.sy,
    );
    let z = field.zmax as f64;
    (0..views.max(1))
        .map(|i| {
            let s = if views > 1 {
                0.35 * i as f64 / (views - 1) as f64
            } else {
                0.0
            };
            TerrainCamera {
                eye: [(0.08 + s) * wx, (-0.92 + s) * wy, z + 0.05 * wx.max(wy)],
                target: [(0.55 + s) * wx, (-0.45 + s) * wy, field.zmin as f64],
                vfov_deg: 45.0,
                width,
                height,
            }
        })
        .collect()
}

fn differing(a: &CastImage, b: &CastImage) -> usize {
    a.hits
        .iter()
        .zip(&b.hits)
        .filter(|(x, y)| match (x, y) {
            (Some(p), Some(q)) => {
                (p.col, p.row) != (q.col, q.row) || (p.t - q.t).abs() > 1e-9 * p.t
            }
            (None, None) => false,
            _ => true,
        })
        .count()
}

/// Steps per ray as the heat map of `raykit terrain render --heatmap`, on
/// the common scale `max`.
fn write_heatmap(path: &Path, img: &CastImage, width: u32, height: u32, max: f64) -> Result<()> {
    let rgb = raykit_terrain::shade::heatmap_scaled(&img.steps, max as u32);
    raykit_io::write_png(path, width, height, &rgb)
        .with_context(|| format!("writing {}", path.display()))
}

fn part_a(args: &TerrainExperimentArgs, dem: &Dem) -> Result<Vec<CastRow>> {
    let field = HeightField::new(dem).map_err(anyhow::Error::msg)?;
    let pyramid = MaxMipmap::new(&field);
    let cams = flight_cameras(&field, args.width, args.height, args.flythrough);
    let rays = (args.width * args.height) as f64 * cams.len() as f64;
    // Per repetition the average frame over the views; the images of every
    // view kept from the last repetition.
    let run = |caster: Caster| -> (Vec<CastImage>, Vec<f64>) {
        let mut times = Vec::new();
        let mut last = Vec::new();
        for _ in 0..args.reps.max(1) {
            let (imgs, s) = timed(|| {
                cams.iter()
                    .map(|cam| cast_image(&field, &pyramid, cam, caster))
                    .collect::<Vec<_>>()
            });
            times.push(s / cams.len() as f64);
            last = imgs;
        }
        (last, times)
    };
    eprintln!(
        "(a) per-cell march, {}x{} on {}²",
        args.width, args.height, dem.width
    );
    let (march_img, march_t) = run(Caster::March);
    eprintln!("(a) per-ray maximum mipmap");
    let (mm_img, mm_t) = run(Caster::MaxMipmap);
    let (march_ms, march_noise) = median_ms(&march_t);
    let (mm_ms, mm_noise) = median_ms(&mm_t);
    let steps = |imgs: &[CastImage]| -> (f64, f64) {
        let all = || imgs.iter().flat_map(|img| img.steps.iter());
        (
            all().map(|s| s.cells as f64).sum::<f64>() / rays,
            all().map(|s| s.nodes as f64).sum::<f64>() / rays,
        )
    };
    let differing_all = |a: &[CastImage], b: &[CastImage]| -> usize {
        a.iter().zip(b).map(|(x, y)| differing(x, y)).sum()
    };
    let heat_max = march_img[0]
        .steps
        .iter()
        .map(|s| (s.cells + s.nodes) as f64)
        .fold(1.0, f64::max);
    write_heatmap(
        &args.out.join("heat-march.png"),
        &march_img[0],
        args.width,
        args.height,
        heat_max,
    )?;
    write_heatmap(
        &args.out.join("heat-maxmip.png"),
        &mm_img[0],
        args.width,
        args.height,
        heat_max,
    )?;
    let mut rows = vec![
        CastRow {
            method: "B: per-cell march".into(),
            tau: None,
            ms: march_ms,
            noise: march_noise,
            boxes: 0,
            cells_per_ray: steps(&march_img).0,
            nodes_per_ray: steps(&march_img).1,
            speedup_vs_march: 1.0,
            speedup_vs_maxmip: mm_ms / march_ms,
            paper_vs_march: None,
            paper_vs_maxmip: None,
            pixels_differing_from_march: 0,
        },
        CastRow {
            method: "C: per-ray max mipmap".into(),
            tau: None,
            ms: mm_ms,
            noise: mm_noise,
            boxes: 0,
            cells_per_ray: steps(&mm_img).0,
            nodes_per_ray: steps(&mm_img).1,
            speedup_vs_march: march_ms / mm_ms,
            speedup_vs_maxmip: 1.0,
            paper_vs_march: None,
            paper_vs_maxmip: None,
            pixels_differing_from_march: differing_all(&march_img, &mm_img),
        },
    ];
    for &tau in &args.taus {
        eprintln!("(a) boxes, tau {tau}");
        let (img, t) = run(Caster::Boxes { tau });
        let (ms, noise) = median_ms(&t);
        if heat_tau(&args.taus) == Some(tau) {
            write_heatmap(
                &args.out.join(boxes_heatmap_name(tau)),
                &img[0],
                args.width,
                args.height,
                heat_max,
            )?;
        }
        let paper = PAPER_TABLE1.iter().find(|p| p.0 == tau);
        rows.push(CastRow {
            method: "A: boxes (per-frame quadtree boxes)".into(),
            tau: Some(tau),
            ms,
            noise,
            boxes: img.iter().map(|i| i.boxes).sum::<usize>() / img.len().max(1),
            cells_per_ray: steps(&img).0,
            nodes_per_ray: steps(&img).1,
            speedup_vs_march: march_ms / ms,
            speedup_vs_maxmip: mm_ms / ms,
            paper_vs_march: paper.map(|p| p.1),
            paper_vs_maxmip: paper.map(|p| p.2),
            pixels_differing_from_march: differing_all(&march_img, &img),
        });
    }
    Ok(rows)
}

/// A point light 50 m above the grid point nearest the centre (a sample,
/// so that gdal_viewshed, which moves its observer to the centre of the
/// cell it lies in, stands at the same place).
fn point_light(field: &HeightField) -> (Light, [f64; 2], f64) {
    let (col, row) = ((field.width - 1) / 2, (field.height - 1) / 2);
    let (x, y, h) = (col as f64 * field.sx, -(row as f64) * field.sy, 50.0);
    let pos = light_above_ground(field, x, y, h).expect("the centre is inside");
    (Light::Point(pos), [x, y], h)
}

fn part_b(args: &TerrainExperimentArgs) -> Result<Vec<ShadowRow>> {
    let mut rows = Vec::new();
    for &size in &args.shadow_sizes {
        let dem = raykit_terrain::fractal::fractal(size, 1, 0.55);
        let field = HeightField::new(&dem).map_err(anyhow::Error::msg)?;
        let pyramid = MaxMipmap::new(&field);
        let (light, _, h) = point_light(&field);
        let brute_reps = if size > 1024 { 1 } else { args.reps.max(1) };
        eprintln!("(b) shadow mask {size}², brute force x{brute_reps}");
        let mut bt = Vec::new();
        let mut brute = Vec::new();
        for _ in 0..brute_reps {
            let (m, s) = timed(|| shadow_mask(&field, &pyramid, &light, ShadowMethod::BruteForce));
            bt.push(s);
            brute = m;
        }
        eprintln!("(b) shadow mask {size}², fast");
        let mut ft = Vec::new();
        let mut fast = Vec::new();
        for _ in 0..args.reps.max(1) {
            let (m, s) = timed(|| shadow_mask(&field, &pyramid, &light, ShadowMethod::Fast));
            ft.push(s);
            fast = m;
        }
        let (b, f) = (median_min_max(&bt).0, median_min_max(&ft).0);
        rows.push(ShadowRow {
            size,
            light: format!("point, centre, {h} m above ground"),
            brute_s: b,
            fast_s: f,
            speedup: b / f,
            cells_differing: brute.iter().zip(&fast).filter(|(a, b)| a != b).count(),
            lit_pct: 100.0 * fast.iter().map(|&m| m as f64).sum::<f64>() / fast.len() as f64,
        });
    }
    Ok(rows)
}

/// Part (c): our mask and gdal_viewshed's from the same point light on the
/// same DEM. Both are timed as commands (`raykit terrain shadow` with its
/// defaults, a DEFLATE GeoTIFF and a PNG preview; gdal_viewshed writing its
/// GeoTIFF), run in turn `--reps` times; the mask alone is timed in this
/// process too.
/// Part (c) on `given` (the `--gdal-dem` file, loaded before any part ran)
/// or else on the generated DEM.
fn part_c(
    args: &TerrainExperimentArgs,
    generated: Option<&Dem>,
    given: Option<(PathBuf, Dem)>,
) -> Result<GdalRow> {
    let dir = args.out.join("gdal");
    std::fs::create_dir_all(&dir)?;
    let (input, loaded, name) = match given {
        Some((path, dem)) => {
            let name = path.display().to_string();
            (path, dem, name)
        }
        None => {
            let generated = generated.expect("the DEM is generated when none is given");
            let input = dir.join("dem.tif");
            raykit_terrain::io::write_dem_geotiff(&input, generated)?;
            (input, generated.clone(), format!("fractal:{}", args.size))
        }
    };
    let dem = &loaded;
    let field = HeightField::new(dem).map_err(anyhow::Error::msg)?;
    let pyramid = MaxMipmap::new(&field);
    let (light, [x, y], h) = point_light(&field);
    // Map coordinates of the light for both commands: world → grid → map.
    let (col, row) = (x / field.sx, -y / field.sy);
    let (mx, my) = dem.grid_to_map(col, row);
    let mut ours_t = Vec::new();
    let mut ours = Vec::new();
    for _ in 0..args.reps.max(1) {
        let (m, s) = timed(|| shadow_mask(&field, &pyramid, &light, ShadowMethod::Fast));
        ours_t.push(s);
        ours = m;
    }
    let ours_s = median_min_max(&ours_t).0;
    let light_text = format!("point at map ({mx:.1}, {my:.1}), {h} m above ground");
    let mut row = GdalRow {
        dem: format!("{name}, {}x{}", dem.width, dem.height),
        light: light_text,
        ours_s,
        ours_command_s: None,
        ours_noise: None,
        gdal_s: None,
        gdal_noise: None,
        ours_over_gdal: None,
        cells_differing_pct: None,
        lit_by_us_shadowed_by_gdal: None,
        shadowed_by_us_lit_by_gdal: None,
        note: String::new(),
    };
    if Command::new("gdal_viewshed")
        .arg("--help")
        .output()
        .is_err()
    {
        row.note = "skipped: gdal_viewshed is not installed (apt-get install gdal-bin, or run scripts/terrain-experiment.sh)".into();
        eprintln!("(c) {}", row.note);
        return Ok(row);
    }
    let output = dir.join("viewshed.tif");
    let ours_out = dir.join("raykit.tif");
    let exe = std::env::current_exe().context("finding the raykit executable")?;
    let run = |mut cmd: Command, what: &str| -> Result<f64> {
        let (ran, s) = timed(|| cmd.output());
        let ran = ran.with_context(|| format!("running {what}"))?;
        if !ran.status.success() {
            bail!(
                "{what} failed with {}: {}",
                ran.status,
                String::from_utf8_lossy(&ran.stderr)
            );
        }
        Ok(s)
    };
    let (mut gt, mut ot) = (Vec::new(), Vec::new());
    for _ in 0..args.reps.max(1) {
        let _ = std::fs::remove_file(&output);
        let mut gdal = Command::new("gdal_viewshed");
        gdal.args(["-q", "-ox", &mx.to_string(), "-oy", &my.to_string()])
            .args(["-oz", &h.to_string()])
            .args(["-tz", "0", "-cc", "0", "-vv", "1", "-iv", "0", "-ov", "0"])
            .arg(&input)
            .arg(&output);
        // gdal complains on stderr when the DEM has no CRS; only a failure
        // is worth showing.
        gt.push(run(gdal, "gdal_viewshed")?);
        let mut raykit = Command::new(&exe);
        raykit
            .args(["terrain", "shadow"])
            .arg(&input)
            .arg("--light")
            .arg(format!("{mx},{my},{h}"))
            .arg("--out")
            .arg(&ours_out);
        ot.push(run(raykit, "raykit terrain shadow")?);
    }
    let noise = |t: &[f64]| (median_min_max(t).0, spread(t));
    let (gdal_s, gdal_noise) = noise(&gt);
    let (command_s, command_noise) = noise(&ot);
    let theirs = raykit_terrain::io::read_geotiff(&output)?;
    let written = raykit_terrain::io::read_geotiff(&ours_out)?;
    if (theirs.width, theirs.height) != (dem.width, dem.height) {
        bail!(
            "gdal_viewshed wrote {}x{}, expected {}x{}",
            theirs.width,
            theirs.height,
            dem.width,
            dem.height
        );
    }
    // The command's mask is this process's mask, written out.
    let same = written
        .heights
        .iter()
        .zip(&ours)
        .all(|(&w, &m)| w.is_nan() || (w > 0.5) == (m == 1));
    if !same {
        bail!("raykit terrain shadow wrote a mask that differs from the library's");
    }
    // Cells without data are neither tool's to light: left out of the
    // counts and of the share.
    let (mut a, mut b, mut with_data) = (0usize, 0usize, 0usize);
    for ((&o, &t), h) in ours.iter().zip(&theirs.heights).zip(&dem.heights) {
        if h.is_nan() {
            continue;
        }
        with_data += 1;
        match (o, t > 0.5) {
            (1, false) => a += 1,
            (0, true) => b += 1,
            _ => {}
        }
    }
    row.ours_command_s = Some(command_s);
    row.ours_noise = command_noise;
    row.gdal_s = Some(gdal_s);
    row.gdal_noise = gdal_noise;
    row.ours_over_gdal = Some(command_s / gdal_s);
    row.cells_differing_pct = Some(100.0 * (a + b) as f64 / with_data.max(1) as f64);
    row.lit_by_us_shadowed_by_gdal = Some(a);
    row.shadowed_by_us_lit_by_gdal = Some(b);
    row.note = format!(
        "gdal_viewshed -cc 0 (flat earth, no refraction), -tz 0; commands run in turn, median of {}",
        args.reps.max(1)
    );
    Ok(row)
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{v:.digits$}"))
}

/// Run the three parts and write the report.
pub fn run(args: TerrainExperimentArgs) -> Result<ExitCode> {
    if args.taus.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        bail!("--taus must be positive numbers");
    }
    image_side("--width", args.width)?;
    image_side("--height", args.height)?;
    ranges::reps(args.reps)?;
    in_range("--flythrough", args.flythrough, 1, MAX_VIEWS)?;
    if let Some(p) = args.parts.iter().find(|p| !"abc".contains(**p)) {
        bail!("--parts: unknown part '{p}'; the parts are a, b and c");
    }
    let part = |p: char| args.parts.contains(&p);
    // Only the parts asked for read their sizes.
    let generate = part('a') || (part('c') && args.gdal_dem.is_none());
    if generate && !(16..=16384).contains(&args.size) {
        bail!("--size must be between 16 and 16384, got {}", args.size);
    }
    if let Some(s) = args
        .shadow_sizes
        .iter()
        .find(|&&s| !(16..=16384).contains(&s))
    {
        if part('b') {
            bail!("--shadow-sizes must be between 16 and 16384, got {s}");
        }
    }
    // A bad --gdal-dem is refused before any part runs or writes.
    let given = match (&args.gdal_dem, part('c')) {
        (Some(path), true) => Some((
            path.clone(),
            raykit_terrain::io::load_dem(path, &Default::default())?,
        )),
        _ => None,
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let head = super::provenance();
    let dem = generate.then(|| raykit_terrain::fractal::fractal(args.size, 1, 0.55));
    let a = if let (true, Some(dem)) = (part('a'), &dem) {
        part_a(&args, dem)?
    } else {
        Vec::new()
    };
    let b = if part('b') {
        part_b(&args)?
    } else {
        Vec::new()
    };
    let c = if part('c') {
        Some(part_c(&args, dem.as_ref(), given)?)
    } else {
        None
    };
    let mut md = format!("# Terrain experiment\n\n{head}\n");
    if !a.is_empty() {
        write_csv(&args.out, "cast.csv", &a)?;
        md += &part_a_table(&args, &a);
    }
    if !b.is_empty() {
        write_csv(&args.out, "shadow.csv", &b)?;
        md += &part_b_table(&b);
    }
    if let Some(c) = &c {
        write_csv(&args.out, "gdal.csv", std::slice::from_ref(c))?;
        md += &part_c_table(c);
    }
    write_text(&args.out, "results.md", &md)?;
    print!("{md}");
    if !a.is_empty() {
        table1_plot(&args, &a)?;
    }
    let differs = a.iter().any(|r| r.pixels_differing_from_march > 0)
        || b.iter().any(|r| r.cells_differing > 0);
    Ok(if differs {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// Part (a)'s table.
fn part_a_table(args: &TerrainExperimentArgs, a: &[CastRow]) -> String {
    let mut md = format!(
        "## (a) Per-frame quadtree boxes against per-cell and maximum-mipmap casting: fractal:{} DEM, {}x{}, {}, median of {} runs\n\n\
         | method | τ | ms | noise | boxes | cells/ray | nodes or boxes/ray | A:B (ours) | A:B (paper) | A:C (ours) | A:C (paper) | pixels ≠ march |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        args.size,
        args.width,
        args.height,
        if args.flythrough > 1 {
            format!("the average frame of a {}-view fly-through (ms per frame; counts per ray over all views)", args.flythrough)
        } else {
            "one view".to_string()
        },
        args.reps
    );
    for r in a {
        md += &format!(
            "| {} | {} | {:.1} | {} | {} | {:.1} | {:.1} | {:.2} | {} | {:.2} | {} | {} |\n",
            r.method,
            opt(r.tau, 0),
            r.ms,
            spread_percent(r.noise),
            r.boxes,
            r.cells_per_ray,
            r.nodes_per_ray,
            r.speedup_vs_march,
            opt(r.paper_vs_march, 2),
            r.speedup_vs_maxmip,
            opt(r.paper_vs_maxmip, 2),
            r.pixels_differing_from_march
        );
    }
    md += "\nHeat maps (steps per ray, same scale): heat-march.png, heat-maxmip.png";
    if let Some(tau) = heat_tau(&args.taus) {
        md += &format!(", {}", boxes_heatmap_name(tau));
    }
    md += ".\n\n";
    md
}

/// The τ whose box method gets a heat map: 16 (the paper's best) when it is
/// among `taus`, else the nearest one on a log scale; `None` without τ values.
fn heat_tau(taus: &[f64]) -> Option<f64> {
    taus.iter()
        .copied()
        .min_by(|a, b| (a.log2() - 4.0).abs().total_cmp(&(b.log2() - 4.0).abs()))
}

/// The file name of the box method's heat map at `tau`.
fn boxes_heatmap_name(tau: f64) -> String {
    format!("heat-boxes-tau{tau}.png")
}

/// Part (b)'s table.
fn part_b_table(b: &[ShadowRow]) -> String {
    let mut md = String::from(
        "## (b) Terrain shadow map (Min 2008), brute force against fast\n\n\
         | DEM | light | brute force s | fast s | speed-up | cells ≠ | lit % |\n|---:|---|---:|---:|---:|---:|---:|\n",
    );
    for r in b {
        md += &format!(
            "| {}² | {} | {:.3} | {:.3} | {:.1}x | {} | {:.1} |\n",
            r.size, r.light, r.brute_s, r.fast_s, r.speedup, r.cells_differing, r.lit_pct
        );
    }
    md.push('\n');
    md
}

/// Part (c)'s table.
fn part_c_table(c: &GdalRow) -> String {
    format!(
        "## (c) gdal_viewshed on the same DEM and light\n\n\
         Cells differing: of the cells with data.\n\n\
         | DEM | light | ours, mask s | ours, command s (noise) | gdal_viewshed s (noise) | command ÷ gdal | cells differing % | lit by us, not by gdal | lit by gdal, not by us | note |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---|\n\
         | {} | {} | {:.3} | {} ({}) | {} ({}) | {} | {} | {} | {} | {} |\n",
        c.dem,
        c.light,
        c.ours_s,
        opt(c.ours_command_s, 3),
        spread_percent(c.ours_noise),
        opt(c.gdal_s, 3),
        spread_percent(c.gdal_noise),
        opt(c.ours_over_gdal, 2),
        opt(c.cells_differing_pct, 3),
        c.lit_by_us_shadowed_by_gdal.map_or("–".into(), |v| v.to_string()),
        c.shadowed_by_us_lit_by_gdal.map_or("–".into(), |v| v.to_string()),
        c.note
    )
}

/// The plot of part (a)'s speed-ups against the paper's Table 1.
fn table1_plot(args: &TerrainExperimentArgs, a: &[CastRow]) -> Result<()> {
    let boxes: Vec<&CastRow> = a.iter().filter(|r| r.tau.is_some()).collect();
    let series = |f: &dyn Fn(&CastRow) -> Option<f64>| -> Vec<(f64, f64)> {
        boxes
            .iter()
            .filter_map(|r| Some((r.tau?.log2(), f(r)?)))
            .collect()
    };
    write_svg(
        &LineChart {
            title: format!(
                "Per-frame quadtree boxes on this CPU: speed-up, {}x{}",
                args.width, args.height
            ),
            x_label: "log2 τ",
            y_label: "speed-up of the box method",
            series: vec![
                Series {
                    name: "A:B ours (vs per-cell march)".into(),
                    points: series(&|r| Some(r.speedup_vs_march)),
                },
                Series {
                    name: "A:B paper (GPU)".into(),
                    points: series(&|r| r.paper_vs_march),
                },
                Series {
                    name: "A:C ours (vs per-ray max mipmap)".into(),
                    points: series(&|r| Some(r.speedup_vs_maxmip)),
                },
                Series {
                    name: "A:C paper (GPU)".into(),
                    points: series(&|r| r.paper_vs_maxmip),
                },
            ],
            reference: vec![("1 (equal speed)".into(), 1.0)],
        },
        &args.out.join("table1.svg"),
    )?;
    Ok(())
}
