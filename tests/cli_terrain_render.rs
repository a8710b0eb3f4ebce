//! `raykit terrain render` as a user runs it, on the Terragen DEM of data/ at
//! 160×90: the PNG's size, sky above and terrain below in the default view
//! (told apart by how they react to the light, not by their colours), the
//! three exact casters giving byte-identical images, the GPU backend giving
//! the same image, the heat map, a short fly-through, and clear errors.

use std::path::{Path, PathBuf};
use std::process::Output;

#[path = "support/cli.rs"]
mod cli;
use cli::{data, raykit, s, text};

const W: u32 = 160;
const H: u32 = 90;

fn ter() -> PathBuf {
    data("terrain/RealisticTerrain_Large.ter")
}

/// `raykit terrain render TER --width 160 --height 90 EXTRA...`.
fn render(out: &Path, extra: &[&str]) -> Output {
    let dem = ter();
    let (w, h) = (W.to_string(), H.to_string());
    let mut args = vec![
        "terrain",
        "render",
        s(&dem),
        "--width",
        &w,
        "--height",
        &h,
        "--out",
        s(out),
    ];
    args.extend_from_slice(extra);
    raykit(&args)
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "raykit failed: {}\n{}",
        text(&o.stderr),
        text(&o.stdout)
    );
}

fn read(p: &Path) -> image::RgbImage {
    image::open(p)
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        .to_rgb8()
}

fn row(img: &image::RgbImage, y: u32) -> Vec<[u8; 3]> {
    (0..img.width()).map(|x| img.get_pixel(x, y).0).collect()
}

/// The default camera is documented as: eye above the highest point of the
/// DEM, looking 20° below the horizontal with a 50° vertical field of view.
/// So the top row's rays rise 5° above the horizontal from above every
/// point of the terrain and can hit nothing (sky), while the bottom row's
/// descend at 45° towards the DEM's centre from inside the DEM's extent and
/// must meet the ground. Sky depends only on the ray direction, terrain on
/// the light: render under two suns and compare.
#[test]
fn default_view_has_sky_on_top_and_terrain_below_at_the_requested_size() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    ok(&render(&a, &["--sun", "135,35", "--no-shadows"]));
    ok(&render(&b, &["--sun", "315,60", "--no-shadows"]));
    let (ia, ib) = (read(&a), read(&b));
    assert_eq!(ia.dimensions(), (W, H));
    assert_eq!(ib.dimensions(), (W, H));

    // Top row: sky — unchanged by the light and the same across the row
    // (the sky gradient depends only on the elevation of the ray, and the
    // top row's rays differ in elevation by a fraction of a degree).
    let (ta, tb) = (row(&ia, 0), row(&ib, 0));
    assert_eq!(ta, tb, "the top row changed with the light: not sky");
    for p in &ta {
        for k in 0..3 {
            assert!(
                (p[k] as i32 - ta[W as usize / 2][k] as i32).abs() <= 2,
                "top row not uniform: {:?}",
                ta
            );
        }
    }
    // Bottom row: terrain — nearly every pixel changes with the light.
    let (ba, bb) = (row(&ia, H - 1), row(&ib, H - 1));
    let changed = ba.iter().zip(&bb).filter(|(p, q)| p != q).count();
    assert!(
        changed * 10 >= 9 * W as usize,
        "only {changed} of {W} bottom-row pixels react to the light: not terrain"
    );
}

#[test]
fn the_three_casters_give_byte_identical_images() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for caster in ["march", "maxmip", "boxes"] {
        let out = dir.path().join(format!("{caster}.png"));
        let o = render(&out, &["--caster", caster]);
        ok(&o);
        if caster == "boxes" {
            assert!(text(&o.stderr).contains("boxes"), "{}", text(&o.stderr));
        }
        files.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(files[0], files[1], "march and maxmip differ");
    assert_eq!(files[0], files[2], "march and boxes differ");
}

/// `--backend gpu` (raykit-gpu's kernels, f32) gives the CPU's image with
/// both GPU casters: the host shades both from the hit cells and
/// distances, which differ only where f32 rounding decides (a hit on a cell
/// border, a grazing ray; crates/gpu/tests/terrain.rs counts and explains
/// them), so at most 0.1% of the pixels may differ. Needs a wgpu adapter
/// (lavapipe in CI): without one the render fails and so does this test.
#[test]
fn gpu_backend_gives_the_cpu_image() {
    let dir = tempfile::tempdir().unwrap();
    let (g, c) = (dir.path().join("gpu.png"), dir.path().join("cpu.png"));
    ok(&render(&c, &[]));
    let cpu = read(&c);
    for caster in ["maxmip", "boxes"] {
        let o = render(&g, &["--backend", "gpu", "--caster", caster]);
        ok(&o);
        assert!(
            text(&o.stderr).contains("on the GPU"),
            "{}",
            text(&o.stderr)
        );
        let gpu = read(&g);
        assert_eq!(gpu.dimensions(), (W, H));
        let differ = gpu
            .pixels()
            .zip(cpu.pixels())
            .filter(|(a, b)| a != b)
            .count();
        eprintln!("gpu {caster} vs cpu: {differ} of {} pixels differ", W * H);
        assert!(
            differ * 1000 <= (W * H) as usize,
            "{differ} of {} pixels differ between --backend gpu --caster {caster} and the CPU",
            W * H
        );
    }

    let o = render(&g, &["--backend", "gpu"]);
    ok(&o);
    let e = text(&o.stderr);
    assert!(
        e.contains("maxmip on the GPU"),
        "the GPU's default caster: {e}"
    );

    let o = render(&g, &["--backend", "gpu", "--caster", "march"]);
    assert!(!o.status.success(), "--backend gpu --caster march accepted");
    let e = text(&o.stderr);
    assert!(
        e.contains("--caster march") && e.contains("--backend cpu"),
        "{e}"
    );
}

#[test]
fn heatmap_is_written_and_its_scale_reported() {
    let dir = tempfile::tempdir().unwrap();
    let (out, heat) = (dir.path().join("t.png"), dir.path().join("heat.png"));
    let o = render(&out, &["--heatmap", s(&heat)]);
    ok(&o);
    assert_eq!(read(&heat).dimensions(), (W, H));
    let err = text(&o.stderr);
    assert!(err.contains("steps/ray"), "{err}");
}

/// The eye and target the single-frame summary reports, map coordinates.
fn summary_camera(stderr: &str) -> ([f64; 3], [f64; 3]) {
    let grab = |key: &str| -> [f64; 3] {
        let rest = &stderr[stderr.find(key).expect("camera in summary") + key.len()..];
        let word = rest.split_whitespace().next().unwrap();
        let v: Vec<f64> = word.split(',').map(|c| c.parse().unwrap()).collect();
        [v[0], v[1], v[2]]
    };
    (grab(" eye "), grab(" target "))
}

#[test]
fn a_fly_through_of_three_frames_writes_three_files() {
    let dir = tempfile::tempdir().unwrap();
    let o = render(&dir.path().join("one.png"), &["--no-shadows"]);
    ok(&o);
    // Fly from the default eye half way towards the target, at eye height.
    let (e, t) = summary_camera(&text(&o.stderr));
    let mid = [(e[0] + t[0]) / 2.0, (e[1] + t[1]) / 2.0, e[2]];
    let path = format!(
        "{},{},{}:{},{},{}",
        e[0], e[1], e[2], mid[0], mid[1], mid[2]
    );
    let pattern = dir.path().join("frames").join("f{}.png");
    let o = render(&pattern, &["--path", &path, "--frames", "3"]);
    ok(&o);
    let mut names: Vec<String> = std::fs::read_dir(dir.path().join("frames"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["f0.png", "f1.png", "f2.png"]);
    for n in &names {
        assert_eq!(
            read(&dir.path().join("frames").join(n)).dimensions(),
            (W, H)
        );
    }
    assert!(text(&o.stderr).contains("fps"), "{}", text(&o.stderr));
}

#[test]
fn bad_arguments_name_the_flag_or_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.png");
    for eye in ["1,2", "a,b,c", "1e12,0,100"] {
        let o = render(&out, &["--eye", eye]);
        assert!(!o.status.success(), "--eye {eye} accepted");
        assert!(text(&o.stderr).contains("--eye"), "{}", text(&o.stderr));
    }
    let o = render(&dir.path().join("f.png"), &["--path", "0,0,1:1,1,1"]);
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("--out"), "{}", text(&o.stderr));

    // The outputs are PNGs, and named so.
    for (flag, name) in [("--out", "t.jpg"), ("--heatmap", "h.tif")] {
        let wrong = dir.path().join(name);
        let o = match flag {
            "--out" => render(&wrong, &[]),
            _ => render(&out, &["--heatmap", s(&wrong)]),
        };
        let e = text(&o.stderr);
        assert!(
            !o.status.success() && e.contains(&format!("{flag} (a PNG) must end in .png")),
            "{e}"
        );
        assert!(!wrong.exists() && !out.exists());
    }

    let missing = dir.path().join("no_such_dem.ter");
    let o = raykit(&["terrain", "render", s(&missing), "--out", s(&out)]);
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("no_such_dem.ter"),
        "{}",
        text(&o.stderr)
    );
    assert!(!out.exists());
}
