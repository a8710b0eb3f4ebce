//! `raykit render` and `raykit export` as a user runs them: a glTF scene
//! with its own camera and lights renders without options (checked against
//! the built-in scene it was exported from), EXR output agrees with the PNG,
//! AOVs are written, malformed scenes and out-of-range options give clear
//! errors, and a far point light still lights the scene.

use std::path::Path;

#[path = "support/cli.rs"]
mod cli;
use cli::{raykit, s, text};

const W: &str = "96";
const H: &str = "72";

fn ok(o: &std::process::Output) {
    assert!(o.status.success(), "{}", text(&o.stderr));
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path).unwrap().to_rgb8()
}

#[test]
fn exported_gltf_scene_renders_without_options_like_its_builtin() {
    let dir = tempfile::tempdir().unwrap();
    let gltf = dir.path().join("whitted.gltf");
    ok(&raykit(&[
        "export",
        "--scene",
        "builtin:whitted",
        "--out",
        s(&gltf),
    ]));
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    ok(&raykit(&[
        "render",
        "--scene",
        s(&gltf),
        "--width",
        W,
        "--height",
        H,
        "--aov",
        "id",
        "--out",
        s(&a),
    ]));
    ok(&raykit(&[
        "render",
        "--scene",
        "builtin:whitted",
        "--width",
        W,
        "--height",
        H,
        "--aov",
        "id",
        "--out",
        s(&b),
    ]));
    // Same camera and geometry: every pixel sees the same triangle.
    let (ia, ib) = (
        rgb(&dir.path().join("a.id.png")),
        rgb(&dir.path().join("b.id.png")),
    );
    assert_eq!(
        ia, ib,
        "the glTF camera frames the same triangles as the built-in camera"
    );
    // Same lights and materials, up to the metallic-roughness round trip
    // (the walls gain glTF's 4% dielectric specular).
    let (pa, pb) = (rgb(&a), rgb(&b));
    let diff: u64 = pa
        .as_raw()
        .iter()
        .zip(pb.as_raw())
        .map(|(x, y)| x.abs_diff(*y) as u64)
        .sum();
    let mean = diff as f64 / pa.as_raw().len() as f64;
    assert!(mean < 3.0, "mean difference {mean} of 255");
    let mut colours: Vec<[u8; 3]> = pa.pixels().map(|p| p.0).collect();
    colours.sort();
    colours.dedup();
    assert!(
        colours.len() > 200,
        "a real picture: {} colours",
        colours.len()
    );
}

fn srgb(x: f32) -> u8 {
    let x = (x as f64).clamp(0.0, 1.0);
    let y = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (y * 255.0).round() as u8
}

#[test]
fn exr_output_holds_the_radiance_the_png_encodes_and_aovs_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let (png, exr) = (dir.path().join("f.png"), dir.path().join("f.exr"));
    let common = [
        "--width",
        W,
        "--height",
        H,
        "--spp",
        "2",
        "--integrator",
        "wavefront",
    ];
    ok(&raykit(
        &[&["render", "--out", s(&png)][..], &common].concat(),
    ));
    ok(&raykit(
        &[
            &["render", "--out", s(&exr), "--aov", "depth,normal,id"][..],
            &common,
        ]
        .concat(),
    ));
    let img = rgb(&png);
    let layer = exr::prelude::read_first_rgba_layer_from_file(
        &exr,
        |res, _| vec![[0f32; 3]; res.width() * res.height()],
        |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * 96 + pos.x()] = [r, g, b];
        },
    )
    .unwrap();
    let px = &layer.layer_data.channel_data.pixels;
    assert_eq!(px.len(), 96 * 72);
    for (i, p) in img.pixels().enumerate() {
        let want = px[i].map(srgb);
        for k in 0..3 {
            assert!(
                p.0[k].abs_diff(want[k]) <= 1,
                "pixel {i}: PNG {:?}, EXR encodes to {want:?}",
                p.0
            );
        }
    }
    for aov in ["depth", "normal", "id"] {
        for ext in ["exr", "png"] {
            let f = dir.path().join(format!("f.{aov}.{ext}"));
            assert!(f.is_file(), "{} missing", f.display());
        }
    }
}

#[test]
fn malformed_scenes_and_options_give_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let bad_json = dir.path().join("broken.gltf");
    std::fs::write(
        &bad_json,
        br#"{"asset":{"version":"2.0"},"nodes":[{"mesh":0}],"#,
    )
    .unwrap();
    let o = raykit(&["render", "--scene", s(&bad_json), "--out", s(&out)]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(err.contains("broken.gltf"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists());

    let glb = dir.path().join("short.glb");
    let mut bytes = b"glTF".to_vec();
    bytes.extend_from_slice(&2u32.to_le_bytes());
    bytes.extend_from_slice(&1000u32.to_le_bytes());
    std::fs::write(&glb, &bytes).unwrap();
    let o = raykit(&["render", "--scene", s(&glb), "--out", s(&out)]);
    let err = text(&o.stderr);
    assert!(
        !o.status.success() && err.contains("short.glb") && err.contains("byte"),
        "{err}"
    );

    for (args, needle) in [
        (vec!["--light", "spot:0,1,0:0,0,0:120"], "angle"),
        (vec!["--env", "nosuch.exr"], "nosuch.exr"),
        (vec!["--material", "velvet"], "glass"),
        (vec!["--aov", "albedo"], "depth"),
        (vec!["--out", "x.jpg"], ".png or .exr"),
    ] {
        let o = raykit(&[&["render", "--width", "8", "--height", "8"][..], &args].concat());
        let err = text(&o.stderr);
        assert!(
            !o.status.success() && err.contains(needle),
            "{args:?}: {err}"
        );
    }
}

/// Options out of range are refused naming the option and the value, and
/// write nothing: a light beyond the bound on camera coordinates (its
/// intensity would overflow f32 and the light be lost), a non-finite
/// environment rotation, a tile count of 0.
#[test]
fn out_of_range_lights_rotations_and_tiles_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let env = cli::data("envmaps/studio.exr");
    let far = format!("{:e},5,0", raykit_core::MAX_CAMERA_COORDINATE * 100.0);
    let far_target = format!(
        "spot:0,5,0:{:e},0,0:30",
        raykit_core::MAX_CAMERA_COORDINATE * 100.0
    );
    for (args, needles) in [
        (vec!["--light", far.as_str()], vec!["--light", "1e18"]),
        (
            vec!["--light", far_target.as_str()],
            vec!["--light", "target"],
        ),
        (
            vec!["--env", s(&env), "--env-rotate", "inf"],
            vec!["--env-rotate", "inf"],
        ),
        (
            vec!["--env", s(&env), "--env-rotate", "NaN"],
            vec!["--env-rotate", "NaN"],
        ),
        (vec!["--tile", "0/0"], vec!["--tile", "at least 1"]),
    ] {
        let o = raykit(
            &[
                &["render", "--width", "8", "--height", "8", "--out", s(&out)][..],
                &args,
            ]
            .concat(),
        );
        let err = text(&o.stderr);
        assert!(!o.status.success(), "{args:?} was accepted");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}

/// A point light far away, but within the bound, still lights the scene:
/// as a directional light from the same side with the same irradiance does.
#[test]
fn a_far_point_light_lights_as_a_directional_light_does() {
    let dir = tempfile::tempdir().unwrap();
    let (point, parallel, unlit) = (
        dir.path().join("p.png"),
        dir.path().join("d.png"),
        dir.path().join("u.png"),
    );
    let (x, y, z) = (1e17f32, 3e16f32, 2e16f32);
    for (light, out) in [
        (format!("{x:e},{y:e},{z:e}"), &point),
        (format!("dir:{:e},{:e},{:e}", -x, -y, -z), &parallel),
        (format!("dir:{:e},{:e},{:e}:0,0,0", -x, -y, -z), &unlit),
    ] {
        ok(&raykit(&[
            "render",
            "--width",
            W,
            "--height",
            H,
            "--light",
            &light,
            "--out",
            s(out),
        ]));
    }
    let mean_diff = |a: &image::RgbImage, b: &image::RgbImage| -> f64 {
        a.as_raw()
            .iter()
            .zip(b.as_raw())
            .map(|(&p, &q)| (p as f64 - q as f64).abs())
            .sum::<f64>()
            / a.as_raw().len() as f64
    };
    let (a, b) = (rgb(&point), rgb(&parallel));
    let diff = mean_diff(&a, &b);
    assert!(diff < 1.0, "mean difference {diff} levels");
    // The light matters to the picture: without it, it differs.
    let without = mean_diff(&b, &rgb(&unlit));
    assert!(without > 5.0 * diff.max(0.2), "{without} against {diff}");
}

/// `render --help` names every structure the GPU backend takes.
#[test]
fn the_accel_help_names_what_the_gpu_backend_takes() {
    let o = raykit(&["render", "--help"]);
    ok(&o);
    let help = text(&o.stdout);
    // The option's own lines: up to the next option's line, which is
    // indented less than the descriptions.
    let accel = help
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("--accel <ACCEL>"))
        .skip(1)
        .take_while(|l| {
            let indent = l.len() - l.trim_start().len();
            !(l.trim_start().starts_with('-') && indent <= 6)
        })
        .collect::<Vec<_>>()
        .join(" ");
    assert!(!accel.is_empty(), "--accel missing from the help");
    for kind in raykit_gpu::GpuAccelKind::ALL {
        assert!(
            accel.contains(kind.name()),
            "{} missing: {accel}",
            kind.name()
        );
    }
}

/// `raykit render` under `ulimit -v limit_kib` with `args`: status 1 (an
/// error, not an abort), stderr naming each of `named`, and no image.
#[cfg(target_os = "linux")]
fn refused_under_limit(limit_kib: u64, args: &[&str], named: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.png");
    let script = format!(
        "ulimit -v {limit_kib}; exec {} render {} --out {}",
        env!("CARGO_BIN_EXE_raykit"),
        args.join(" "),
        s(&out)
    );
    let o = std::process::Command::new("bash")
        .args(["-c", &script])
        .output()
        .unwrap();
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    for n in named {
        assert!(e.contains(n), "{n:?} not in {e}");
    }
    assert!(!out.exists());
}

/// A frame larger than the process may allocate is an error that points at
/// tiles; it used to abort in the first buffer's allocation.
#[cfg(target_os = "linux")]
#[test]
fn a_frame_beyond_the_memory_limit_is_an_error_not_an_abort() {
    refused_under_limit(
        1_500_000,
        &["--width", "16384", "--height", "16384", "--depth", "1"],
        &["268435456 pixels", "--tile"],
    );
}

/// A Radiance header claiming 16384² texels with no pixels behind it, under
/// a limit below what decoding would need: an error naming the file, where
/// the decoder's allocation used to abort the process.
#[cfg(target_os = "linux")]
#[test]
fn an_environment_map_beyond_the_memory_limit_is_an_error_not_an_abort() {
    let dir = tempfile::tempdir().unwrap();
    let hdr = dir.path().join("huge.hdr");
    std::fs::write(
        &hdr,
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16384 +X 16384\n",
    )
    .unwrap();
    refused_under_limit(
        2_000_000,
        &["--width", "64", "--height", "48", "--env", s(&hdr)],
        &["huge.hdr", "16384×16384"],
    );
}
