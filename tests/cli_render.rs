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

/// A model at UTM-like coordinates (5·10⁶ from the origin, written in full
/// f64 digits) renders as the same model at the origin does: framed by
/// default, and with --eye, --target and a point light given in the file's
/// coordinates. In f32 its vertices would be stored in steps of 0.5 on a
/// model 0.15 across.
#[test]
fn a_model_far_from_the_origin_renders_as_it_does_at_the_origin() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = raykit_io::load_mesh(&cli::data("meshes/bunny_3674.obj")).unwrap();
    let offset = [5.0e5, 2.0e5, 5.0e6];
    let write = |name: &str, shift: [f64; 3]| {
        let mut obj = String::new();
        for p in &bunny.positions {
            let q: Vec<String> = (0..3)
                .map(|k| format!("{:.9}", p[k] as f64 + shift[k]))
                .collect();
            obj += &format!("v {}\n", q.join(" "));
        }
        for t in &bunny.indices {
            obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        let path = dir.path().join(name);
        std::fs::write(&path, obj).unwrap();
        path
    };
    let (near, far) = (write("near.obj", [0.0; 3]), write("far.obj", offset));
    let at = |p: [f64; 3], shift: [f64; 3]| {
        format!(
            "{},{},{}",
            p[0] + shift[0],
            p[1] + shift[1],
            p[2] + shift[2]
        )
    };
    let render = |mesh: &Path, shift: [f64; 3], view: bool, out: &str| {
        let out = dir.path().join(out);
        let (eye, target) = (at([0.1, 0.25, 0.35], shift), at([-0.02, 0.1, 0.0], shift));
        let light = format!("point:{}", at([0.3, 0.5, 0.3], shift));
        let mut args = vec!["render", "--scene", s(mesh), "--width", W, "--height", H];
        if view {
            args.extend(["--eye", &eye, "--target", &target, "--light", &light]);
        }
        args.extend(["--out", s(&out)]);
        ok(&raykit(&args));
        rgb(&out)
    };
    for view in [false, true] {
        let (a, b) = (
            render(&near, [0.0; 3], view, "near.png"),
            render(&far, offset, view, "far.png"),
        );
        let differing = a
            .pixels()
            .zip(b.pixels())
            .filter(|(p, q)| (0..3).any(|k| p[k].abs_diff(q[k]) > 8))
            .count();
        // Rounding the far file's digits to the stored origin moves
        // vertices by about 1e-10: a few edge pixels may differ.
        assert!(
            differing <= 10,
            "{differing} pixels differ (view given: {view})"
        );
    }
}

/// `raykit export` writes no images: a textured material is named in a
/// warning, and the file it writes indeed holds none.
#[test]
fn export_says_which_textures_it_leaves_out() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("checker.png");
    image::RgbImage::from_fn(2, 2, |x, y| {
        image::Rgb(if (x + y) % 2 == 0 {
            [255, 0, 0]
        } else {
            [0, 0, 255]
        })
    })
    .save(&png)
    .unwrap();
    std::fs::write(
        dir.path().join("quad.mtl"),
        "newmtl checker\nKd 1 1 1\nmap_Kd checker.png\nnewmtl plain\nKd 0 1 0\n",
    )
    .unwrap();
    let obj = dir.path().join("quad.obj");
    std::fs::write(
        &obj,
        "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
         usemtl checker\nf 1/1 2/2 3/3\nusemtl plain\nf 1/1 3/3 4/4\n",
    )
    .unwrap();
    let out = dir.path().join("quad.gltf");
    let o = raykit(&["export", "--scene", s(&obj), "--out", s(&out)]);
    ok(&o);
    let err = text(&o.stderr);
    assert!(
        err.contains("1 of 2 materials have a base-colour texture"),
        "{err}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert!(json.get("images").is_none(), "{json}");
}

/// `raykit export` of a glTF file keeps its instancing: the 2CylinderEngine
/// (67 nodes placing 29 meshes) comes out with 29 meshes, each node with
/// its mesh and transform, and renders as the input does (the flattened
/// scene, traced through the same camera).
#[test]
fn export_keeps_a_gltf_files_instancing() {
    let dir = tempfile::tempdir().unwrap();
    let input = cli::data("meshes/2CylinderEngine.glb");
    let out = dir.path().join("engine.glb");
    let o = raykit(&["export", "--scene", s(&input), "--out", s(&out)]);
    ok(&o);
    assert!(
        text(&o.stderr).contains("instancing kept: 67 nodes placing 29 meshes"),
        "{}",
        text(&o.stderr)
    );
    let before = raykit_io::load_gltf_instances(&input).unwrap();
    let after = raykit_io::load_gltf_instances(&out).unwrap();
    assert_eq!(after.geometries.len(), 29);
    assert_eq!(after.instances.len(), before.instances.len());
    for (a, b) in after.instances.iter().zip(&before.instances) {
        assert_eq!(a.geometry, b.geometry, "{}", b.name);
        assert!(
            a.to_world_f64.abs_diff_eq(b.to_world_f64, 1e-9),
            "{}",
            b.name
        );
        let (g, h) = (
            &after.geometries[a.geometry as usize],
            &before.geometries[b.geometry as usize],
        );
        assert_eq!(g.indices, h.indices, "{}", b.name);
        assert_eq!(g.positions, h.positions, "{}", b.name);
    }
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    for (scene, png) in [(&input, &a), (&out, &b)] {
        ok(&raykit(&[
            "render",
            "--scene",
            s(scene),
            "--width",
            W,
            "--height",
            H,
            "--aov",
            "id",
            "--out",
            s(png),
        ]));
    }
    let (ia, ib) = (rgb(&a), rgb(&b));
    let differing = ia.pixels().zip(ib.pixels()).filter(|(p, q)| p != q).count();
    // Corners placed by f64 transforms may round a last bit apart from the
    // input's: a ray grazing an edge can take the neighbour.
    assert!(differing * 200 <= ia.len() / 3, "{differing} pixels differ");
}
