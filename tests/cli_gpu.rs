//! `raykit render --backend gpu` as a user runs it: the PNG equals the CPU
//! renderer's within a small tolerance for both organisations (the CUDA kd-tree
//! tracer's single kernel, Purcell et al. (2002)'s stream), and options the GPU renderer does
//! not implement are refused with an error naming them. Needs a wgpu
//! adapter (Mesa's lavapipe in CI); without one the render fails and so
//! does the test, with the adapter error in the message.

use std::path::Path;

#[path = "support/cli.rs"]
mod cli;
use cli::{raykit, s, text};

const SIZE: [&str; 4] = ["--width", "96", "--height", "72"];

fn render(extra: &[&str], out: &Path) -> std::process::Output {
    let mut args = vec!["render", "--out", s(out)];
    args.extend(SIZE);
    args.extend(extra);
    raykit(&args)
}

fn rgb(path: &Path) -> Vec<u8> {
    image::open(path).unwrap().to_rgb8().into_raw()
}

#[test]
fn gpu_png_equals_the_cpu_png() {
    let dir = tempfile::tempdir().unwrap();
    for scene in ["builtin:whitted", "builtin:shirley6"] {
        let cpu = dir.path().join("cpu.png");
        let o = render(&["--scene", scene, "--spp", "2"], &cpu);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let want = rgb(&cpu);
        for integrator in ["recursive", "wavefront"] {
            let gpu = dir.path().join(format!("gpu-{integrator}.png"));
            let o = render(
                &[
                    "--scene",
                    scene,
                    "--spp",
                    "2",
                    "--backend",
                    "gpu",
                    "--integrator",
                    integrator,
                ],
                &gpu,
            );
            let err = text(&o.stderr);
            assert!(o.status.success(), "--backend gpu failed: {err}");
            assert!(err.contains("GPU: "), "the adapter is named: {err}");
            assert!(err.contains("Mrays/s"), "{err}");
            let got = rgb(&gpu);
            assert_eq!(got.len(), want.len());
            let diffs: Vec<u8> = want.iter().zip(&got).map(|(a, b)| a.abs_diff(*b)).collect();
            let pixels = diffs.len() / 3;
            let off = diffs.chunks(3).filter(|c| c.iter().any(|&d| d > 1)).count();
            let max = diffs.iter().copied().max().unwrap_or(0);
            eprintln!("{scene} {integrator}: {off} of {pixels} pixels differ by more than 1/255, max {max}/255");
            assert!(
                off * 1000 <= pixels * 5,
                "{scene} {integrator}: {off} pixels differ"
            );
        }
    }
}

#[test]
fn unsupported_options_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let cases: [(&[&str], &str); 5] = [
        (&["--shadows", "maps"], "--shadows maps"),
        (&["--primary", "raster"], "--primary raster"),
        (&["--accel", "bvh4"], "--accel bvh4"),
        (&["--test", "projection"], "--test projection"),
        (&["--depth", "20"], "--depth 20"),
    ];
    for (extra, named) in cases {
        let mut args = vec!["--backend", "gpu"];
        args.extend(extra);
        let o = render(&args, &out);
        let err = text(&o.stderr);
        assert!(!o.status.success(), "{extra:?} should fail");
        assert!(
            err.contains("not supported by --backend gpu") && err.contains(named),
            "{extra:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists(), "no image is written");
    }
}

#[test]
fn gpu_environment_box_png_equals_the_cpu_png() {
    let data = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("data"));
    let map = data.join("envmaps/studio.exr");
    assert!(
        map.is_file(),
        "{} missing (set RAYKIT_SHARED_DATA): this test needs the test data",
        map.display()
    );
    let dir = tempfile::tempdir().unwrap();
    let (cpu, gpu) = (dir.path().join("cpu.png"), dir.path().join("gpu.png"));
    let env = ["--scene", "builtin:shirley6", "--env", s(&map), "--env-box"];
    let o = render(&env, &cpu);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let mut args = env.to_vec();
    args.extend(["--backend", "gpu", "--integrator", "wavefront"]);
    let o = render(&args, &gpu);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let (want, got) = (rgb(&cpu), rgb(&gpu));
    let off = want
        .chunks(3)
        .zip(got.chunks(3))
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 1))
        .count();
    eprintln!(
        "environment box: {off} of {} pixels differ by more than 1/255",
        want.len() / 3
    );
    assert!(off * 1000 <= want.len() / 3 * 5, "{off} pixels differ");
}

#[test]
fn gpu_aovs_equal_the_cpu_aovs() {
    let dir = tempfile::tempdir().unwrap();
    let (cpu, gpu) = (dir.path().join("cpu.png"), dir.path().join("gpu.png"));
    let o = render(&["--aov", "id,depth"], &cpu);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = render(&["--aov", "id,depth", "--backend", "gpu"], &gpu);
    assert!(o.status.success(), "{}", text(&o.stderr));
    for kind in ["id", "depth"] {
        let want = rgb(&dir.path().join(format!("cpu.{kind}.png")));
        let got = rgb(&dir.path().join(format!("gpu.{kind}.png")));
        let off = want
            .chunks(3)
            .zip(got.chunks(3))
            .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 1))
            .count();
        eprintln!("{kind} AOV: {off} of {} pixels differ", want.len() / 3);
        assert!(
            off * 1000 <= want.len() / 3 * 5,
            "{kind}: {off} pixels differ"
        );
    }
}

#[test]
fn a_missing_adapter_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_raykit"))
        .args(["render", "--backend", "gpu", "--out", s(&out)])
        .args(SIZE)
        .env("WGPU_BACKEND", "vulkan")
        .env("VK_DRIVER_FILES", dir.path().join("no-such-driver.json"))
        .env("VK_ICD_FILENAMES", dir.path().join("no-such-driver.json"))
        .output()
        .unwrap();
    let err = text(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("no GPU adapter found") && err.contains("--backend cpu"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists());
}
