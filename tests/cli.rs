//! The `raykit` binary as a user runs it: outputs checked against the
//! library computed independently in the test, and bad input giving a clear
//! error (file and location) with a non-zero exit, never a panic.

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn raykit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raykit"))
        .args(args)
        .output()
        .expect("the raykit binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn teapot() -> PathBuf {
    let dir = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data"));
    let p = dir.join("meshes/teapot_992.obj");
    assert!(
        p.is_file(),
        "test data not found at {} (set RAYKIT_SHARED_DATA)",
        p.display()
    );
    p
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

#[test]
fn rays_then_trace_matches_the_library_and_verifies() {
    let dir = tempfile::tempdir().unwrap();
    let mesh_path = teapot();
    let rays = dir.path().join("r.bin");
    let hits = dir.path().join("h.bin");
    let o = raykit(&[
        "rays",
        "--mesh",
        s(&mesh_path),
        "--kind",
        "incoherent",
        "--size",
        "64",
        "--out",
        s(&rays),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raykit(&[
        "trace",
        "--mesh",
        s(&mesh_path),
        "--rays",
        s(&rays),
        "--out",
        s(&hits),
        "--accel",
        "bvh-threaded",
        "--max-leaf",
        "1",
        "--test",
        "plucker",
        "--verify",
        "500",
        "--threads",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The stats line is JSON with the documented keys.
    let err = stderr(&o);
    let stats: serde_json::Value = serde_json::from_str(err.lines().next().unwrap()).unwrap();
    for key in [
        "accel", "test", "load_ms", "build_ms", "trace_ms", "rays", "mrays", "threads",
    ] {
        assert!(stats.get(key).is_some(), "missing {key} in {err}");
    }
    assert_eq!(stats["rays"], 64 * 64);
    assert_eq!(stats["threads"], 1);
    assert!(err.contains("\"ok\":true"), "{err}");
    // Independent check: the hit file equals brute force run in this process.
    let mesh = raykit_io::load_mesh(&mesh_path).unwrap();
    let ray_list = raykit_io::read_rays(&rays).unwrap();
    let got = raykit_io::read_hits(&hits).unwrap();
    let brute = build_accel(
        AccelKind::Brute,
        TestKind::Plucker,
        &mesh,
        &BuildOptions::default(),
    );
    assert_eq!(got.len(), ray_list.len());
    let mut n_hits = 0;
    for (r, g) in ray_list.iter().zip(&got) {
        let want = brute.intersect(r);
        assert_eq!(want.is_some(), g.is_some());
        if let (Some(w), Some(g)) = (want, g) {
            assert!((w.t - g.t).abs() <= 1e-5 * w.t, "{w:?} vs {g:?}");
            n_hits += 1;
        }
    }
    assert!(
        n_hits > 100,
        "the incoherent set should hit the teapot often"
    );
}

/// Without --accel, `raykit trace` uses the fastest structure (bvh8, SAH
/// build), says so in its JSON line, and its hits equal brute force's.
#[test]
fn trace_defaults_to_bvh8_and_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let mesh_path = teapot();
    let rays = dir.path().join("r.bin");
    let hits = dir.path().join("h.bin");
    let o = raykit(&[
        "rays",
        "--mesh",
        s(&mesh_path),
        "--kind",
        "primary",
        "--size",
        "48",
        "--out",
        s(&rays),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raykit(&[
        "trace",
        "--mesh",
        s(&mesh_path),
        "--rays",
        s(&rays),
        "--out",
        s(&hits),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let stats: serde_json::Value = serde_json::from_str(err.lines().next().unwrap()).unwrap();
    assert_eq!(stats["accel"], "bvh8", "{err}");
    assert_eq!(stats["bvh_build"], "sah", "{err}");
    assert_eq!(stats["test"], "moller", "{err}");
    let mesh = raykit_io::load_mesh(&mesh_path).unwrap();
    let brute = build_accel(
        AccelKind::Brute,
        TestKind::Moller,
        &mesh,
        &BuildOptions::default(),
    );
    let ray_list = raykit_io::read_rays(&rays).unwrap();
    let got = raykit_io::read_hits(&hits).unwrap();
    assert_eq!(got.len(), ray_list.len());
    let mut n_hits = 0;
    for (r, g) in ray_list.iter().zip(&got) {
        let want = brute.intersect(r);
        assert_eq!(want.is_some(), g.is_some(), "{r:?}");
        if let (Some(w), Some(g)) = (want, g) {
            assert!((w.t - g.t).abs() <= 1e-5 * w.t, "{w:?} vs {g:?}");
            n_hits += 1;
        }
    }
    assert!(n_hits > 100, "the primary set should hit the teapot");
}

#[test]
fn shadow_rays_and_occlusion_file() {
    let dir = tempfile::tempdir().unwrap();
    let mesh_path = teapot();
    let rays = dir.path().join("s.bin");
    let occ = dir.path().join("o.bin");
    let o = raykit(&[
        "rays",
        "--mesh",
        s(&mesh_path),
        "--kind",
        "shadow",
        "--size",
        "48",
        "--out",
        s(&rays),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = raykit(&[
        "trace",
        "--mesh",
        s(&mesh_path),
        "--rays",
        s(&rays),
        "--out",
        s(&occ),
        "--occlusion",
        "--verify",
        "10000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mesh = raykit_io::load_mesh(&mesh_path).unwrap();
    let ray_list = raykit_io::read_rays(&rays).unwrap();
    let got = raykit_io::read_occlusion(&occ).unwrap();
    let brute = build_accel(
        AccelKind::Brute,
        TestKind::Moller,
        &mesh,
        &BuildOptions::default(),
    );
    let shadowed = ray_list.iter().zip(&got).filter(|(r, g)| {
        assert_eq!(brute.occluded(r), **g);
        **g
    });
    let n = shadowed.count();
    assert!(
        n > 0 && n < ray_list.len(),
        "some but not all points are in shadow ({n})"
    );
}

#[test]
fn render_writes_a_png_of_the_requested_size() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("img.png");
    let o = raykit(&[
        "render",
        "--scene",
        "builtin:shirley6",
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&out).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (64, 48));
    // Not a blank image: many distinct colours.
    let mut colours: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    colours.sort();
    colours.dedup();
    assert!(colours.len() > 50, "{} colours", colours.len());
}

#[test]
fn bad_inputs_name_the_file_and_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n").unwrap();
    let out = dir.path().join("x.png");
    let o = raykit(&["render", "--scene", s(&bad), "--out", s(&out)]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("broken.obj") && err.contains(":3"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists(), "no output on failure");

    let rays = dir.path().join("short.bin");
    std::fs::write(&rays, [0u8; 40]).unwrap();
    let o = raykit(&[
        "trace",
        "--mesh",
        "builtin:cornell",
        "--rays",
        s(&rays),
        "--out",
        s(&dir.path().join("h.bin")),
    ]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("short.bin") && err.contains("byte"), "{err}");

    // An output that is also an input is refused, and the input survives.
    std::fs::write(&rays, [0u8; 64]).unwrap();
    let o = raykit(&[
        "trace",
        "--mesh",
        "builtin:cornell",
        "--rays",
        s(&rays),
        "--out",
        s(&rays),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("also an input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&rays).unwrap(), vec![0u8; 64]);

    // An AOV file is an output too: one that would replace the environment
    // map read is refused, and the map survives.
    let env = dir.path().join("x.depth.exr");
    let studio = teapot()
        .parent()
        .unwrap()
        .parent()
        .unwrap()
        .join("envmaps/studio.exr");
    std::fs::copy(&studio, &env).unwrap();
    let o = raykit(&[
        "render",
        "--scene",
        "builtin:cornell",
        "--width",
        "8",
        "--height",
        "6",
        "--env",
        s(&env),
        "--aov",
        "depth",
        "--out",
        s(&dir.path().join("x.png")),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("also an input"), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(&env).unwrap(),
        std::fs::read(&studio).unwrap()
    );

    // A device or a folder given as an input is refused before any work
    // (/dev/zero would be read without end), and a folder as the output.
    #[cfg(unix)]
    {
        let zero = dir.path().join("zero.obj");
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        let o = raykit(&[
            "trace",
            "--mesh",
            s(&zero),
            "--rays",
            s(&rays),
            "--out",
            s(&dir.path().join("h.bin")),
        ]);
        assert!(!o.status.success());
        let err = stderr(&o);
        assert!(
            err.contains("zero.obj") && err.contains("not a regular file"),
            "{err}"
        );
    }
    let folder = dir.path().join("folder.obj");
    std::fs::create_dir(&folder).unwrap();
    let o = raykit(&[
        "trace",
        "--mesh",
        s(&folder),
        "--rays",
        s(&rays),
        "--out",
        s(&dir.path().join("h.bin")),
    ]);
    assert!(
        stderr(&o).contains("not a regular file (a folder)"),
        "{}",
        stderr(&o)
    );
    let tri = dir.path().join("tri.obj");
    std::fs::write(&tri, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let o = raykit(&["tjunctions", s(&tri), s(&folder)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("is a folder"), "{}", stderr(&o));
    assert!(
        !dir.path().join("folder.mtl").exists(),
        "nothing written beside it"
    );
    let o = raykit(&[
        "render",
        "--scene",
        "builtin:cornell",
        "--orbit",
        "99999999",
        "--out",
        s(&dir.path().join("o.png")),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--orbit"), "{}", stderr(&o));

    let o = raykit(&["render", "--scene", "builtin:nosuch"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("cornell"),
        "lists the valid names: {}",
        stderr(&o)
    );

    let o = raykit(&[
        "trace",
        "--mesh",
        "builtin:cornell",
        "--rays",
        "x",
        "--out",
        "y",
        "--accel",
        "kd",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("bvh2"), "{}", stderr(&o));
}

/// A ray file of no rays is a batch of size zero: `trace` (nearest hits,
/// occlusion, several meshes) and `query count` all write outputs of zero
/// records and report zero rays at a rate of 0, not NaN.
#[test]
fn an_empty_ray_file_gives_empty_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = teapot();
    let rays = dir.path().join("none.bin");
    std::fs::write(&rays, []).unwrap();
    let out = dir.path().join("o.bin");
    let runs: [&[&str]; 4] = [
        &["trace", "--mesh", s(&mesh)],
        &["trace", "--occlusion", "--mesh", s(&mesh)],
        &["trace", "--mesh", s(&mesh), "--mesh", s(&mesh)],
        &["query", "count", "--mesh", s(&mesh)],
    ];
    for args in runs {
        let _ = std::fs::remove_file(&out);
        let mut all = args.to_vec();
        all.extend(["--rays", s(&rays), "--out", s(&out)]);
        let o = raykit(&all);
        let e = stderr(&o);
        assert!(o.status.success(), "{args:?}: {e}");
        assert_eq!(std::fs::read(&out).unwrap().len(), 0, "{args:?}");
        let stats: serde_json::Value = serde_json::from_str(e.lines().last().unwrap()).unwrap();
        assert_eq!(stats["per_s"], 0.0, "{args:?}: {e}");
    }
}

/// Two outputs of one command on one file, or an output in a folder that
/// takes no files, fail before the work, and no output is written.
#[test]
fn colliding_or_unwritable_outputs_fail_before_any_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = teapot();
    let out = dir.path().join("kept.obj");
    let png = dir.path().join("t.png");
    let runs: [(Vec<&str>, &Path, &str); 4] = [
        (
            vec!["cull", s(&mesh), s(&out), "--report", s(&out)],
            &out,
            "name the same file",
        ),
        (
            vec!["cull", s(&mesh), s(&out), "--report", "/proc/r.json"],
            &out,
            "does not take new files",
        ),
        (
            vec![
                "terrain",
                "render",
                "fractal:65",
                "--out",
                s(&png),
                "--heatmap",
                s(&png),
            ],
            &png,
            "name the same file",
        ),
        (
            vec![
                "terrain",
                "render",
                "fractal:65",
                "--out",
                s(&png),
                "--heatmap",
                "/proc/h.png",
            ],
            &png,
            "does not take new files",
        ),
    ];
    for (args, written, needle) in runs {
        let o = raykit(&args);
        let e = stderr(&o);
        assert!(!o.status.success(), "{args:?}");
        assert!(
            e.contains(needle) && !e.contains("panicked"),
            "{args:?}: {e}"
        );
        assert!(!written.exists(), "{args:?} wrote {}", written.display());
    }
}

/// An output that would replace a file an input reads (a glTF file's
/// external buffer) is refused before the work, and the file is kept.
#[test]
fn an_output_never_replaces_a_file_an_input_reads() {
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/io/tests/data");
    for name in ["transforms.gltf", "transforms.bin"] {
        std::fs::copy(data.join(name), dir.path().join(name)).unwrap();
    }
    let (gltf, bin) = (
        dir.path().join("transforms.gltf"),
        dir.path().join("transforms.bin"),
    );
    let before = std::fs::read(&bin).unwrap();
    let o = raykit(&["rays", "--mesh", s(&gltf), "--size", "8", "--out", s(&bin)]);
    let e = stderr(&o);
    assert!(!o.status.success(), "{e}");
    assert!(e.contains("transforms.gltf reads it"), "{e}");
    assert_eq!(std::fs::read(&bin).unwrap(), before);
    let other = dir.path().join("rays.bin");
    let o = raykit(&[
        "rays",
        "--mesh",
        s(&gltf),
        "--size",
        "8",
        "--out",
        s(&other),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Stopped by SIGINT, SIGTERM or SIGHUP while it writes its output, a
/// command removes the temporary file, keeps the old output and ends with the
/// shell's status for the signal, 128 + its number.
#[cfg(unix)]
#[test]
fn a_stopped_command_leaves_no_temporary_file() {
    stopped_by("INT", 130);
    stopped_by("TERM", 143);
    stopped_by("HUP", 129);
}

/// Under `nohup`, which starts it ignoring SIGHUP, a command goes on
/// through a SIGHUP and finishes its output.
#[cfg(unix)]
#[test]
fn a_command_under_nohup_survives_sighup() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rays.bin");
    let mut child = Command::new("nohup")
        .arg(env!("CARGO_BIN_EXE_raykit"))
        .args(["rays", "--mesh", "builtin:cornell", "--kind", "incoherent"])
        .args(["--size", "2048", "--out", s(&out)])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    signal_while_writing(&mut child, dir.path(), "HUP");
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{:?}: {}", o.status, stderr(&o));
    assert_eq!(std::fs::metadata(&out).unwrap().len(), 2048 * 2048 * 32);
}

#[cfg(unix)]
fn stopped_by(signal: &str, status: i32) {
    use std::os::unix::process::ExitStatusExt;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rays.bin");
    std::fs::write(&out, b"old").unwrap();
    let mut command = Command::new(env!("CARGO_BIN_EXE_raykit"));
    command
        .args(["rays", "--mesh", "builtin:cornell", "--kind", "incoherent"])
        .args(["--size", "4096", "--out", s(&out)])
        .stderr(std::process::Stdio::piped());
    // SAFETY: `signal` is async-signal-safe. The child starts with SIGHUP
    // at its default, whatever this test runner was started with.
    unsafe {
        use std::os::unix::process::CommandExt;
        command.pre_exec(|| {
            libc::signal(libc::SIGHUP, libc::SIG_DFL);
            Ok(())
        });
    }
    let mut child = command.spawn().unwrap();
    signal_while_writing(&mut child, dir.path(), signal);
    let o = child.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(status),
        "SIG{signal}: {:?}: {e}",
        o.status.signal()
    );
    assert!(!has_temporary(dir.path()), "a temporary file was left");
    assert_eq!(std::fs::read(&out).unwrap(), b"old");
}

/// Whether `dir` holds a temporary output file.
#[cfg(unix)]
fn has_temporary(dir: &Path) -> bool {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .any(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
}

/// Send `signal` to `child` once its temporary output file exists in
/// `dir`, while it is still running.
#[cfg(unix)]
fn signal_while_writing(child: &mut std::process::Child, dir: &Path, signal: &str) {
    let started = std::time::Instant::now();
    while !has_temporary(dir) && child.try_wait().unwrap().is_none() {
        assert!(started.elapsed().as_secs() < 600, "no output started");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    assert!(
        child.try_wait().unwrap().is_none(),
        "the command ended before it could be stopped"
    );
    let kill = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
}

/// Numbers no render, trace or benchmark can use are refused by their
/// flag before any work: sizes that would exhaust memory, NaN costs and
/// biases, a camera that looks nowhere or has no up direction, and a GPU
/// structure asked of the CPU.
#[test]
fn unusable_numbers_are_refused_by_their_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.png");
    let o = s(&out);
    let runs: [(&[&str], &str); 15] = [
        (
            &[
                "render",
                "--shadows",
                "maps",
                "--shadow-map-size",
                "30000",
                "--out",
                o,
            ],
            "--shadow-map-size",
        ),
        (
            &["render", "--shadows", "maps", "--pcf", "0", "--out", o],
            "--pcf",
        ),
        (
            &[
                "render",
                "--shadows",
                "maps",
                "--shadow-bias",
                "nan",
                "--out",
                o,
            ],
            "--shadow-bias",
        ),
        (&["render", "--exposure", "nan", "--out", o], "--exposure"),
        (
            &["render", "--eye", "0,1,0", "--target", "0,1,0", "--out", o],
            "same point",
        ),
        (
            &[
                "render", "--eye", "0,5,19", "--target", "0,5,0", "--up", "0,0,1", "--out", o,
            ],
            "parallel to the view",
        ),
        (
            &[
                "trace",
                "--traversal-cost",
                "nan",
                "--mesh",
                "builtin:cornell",
                "--rays",
                o,
                "--out",
                o,
            ],
            "--traversal-cost",
        ),
        (
            &[
                "trace",
                "--kd-isect-cost",
                "inf",
                "--mesh",
                "builtin:cornell",
                "--rays",
                o,
                "--out",
                o,
            ],
            "--kd-isect-cost",
        ),
        (&["bench", "--size", "100000"], "--size"),
        (&["bench", "--reps", "0"], "--reps"),
        (
            &["render", "--up", "0,0,0", "--out", o],
            "--up must be a direction",
        ),
        (
            &["render", "--eye", "3,1,0", "--up", "0,nan,0", "--out", o],
            "for '--up <UP>'",
        ),
        (
            &[
                "trace",
                "--accel",
                "cwbvh",
                "--mesh",
                "builtin:cornell",
                "--rays",
                o,
                "--out",
                o,
            ],
            "give --backend gpu",
        ),
        (
            &["tjunctions", "builtin:cornell", o, "--max-rounds", "0"],
            "--max-rounds",
        ),
        (
            &["bench", "--compare", "embree", "--backend", "gpu"],
            "does not take --backend gpu",
        ),
    ];
    for (args, needle) in runs {
        let r = raykit(args);
        let e = stderr(&r);
        assert!(!r.status.success(), "{args:?}");
        assert!(
            e.contains(needle) && !e.contains("panicked"),
            "{args:?}: {e}"
        );
        assert!(!out.exists(), "{args:?} wrote an output");
    }
}

/// One side given, `render` keeps the default's 4:3 shape; both given,
/// both are used; neither, 800 × 600.
#[test]
fn render_keeps_four_to_three_when_one_side_is_given() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.png");
    for (flags, want) in [
        (&["--width", "64"][..], (64, 48)),
        (&["--height", "90"][..], (120, 90)),
        (&["--width", "10", "--height", "20"][..], (10, 20)),
        (&["--width", "1"][..], (1, 1)),
        (&[][..], (800, 600)),
    ] {
        let mut args = vec!["render", "--scene", "builtin:cornell", "--out", s(&out)];
        args.extend_from_slice(flags);
        let o = raykit(&args);
        assert!(o.status.success(), "{flags:?}: {}", stderr(&o));
        let img = image::open(&out).unwrap();
        assert_eq!((img.width(), img.height()), want, "{flags:?}");
    }
}

/// A glTF camera so far from the origin that its target rounds onto its
/// eye is reported as the scene's camera, with the flags that replace it;
/// with them the render goes ahead.
#[test]
fn an_unusable_scene_camera_is_named_as_the_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("far.gltf");
    std::fs::write(
        &scene,
        r#"{"asset":{"version":"2.0"},
"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
"bufferViews":[{"buffer":0,"byteLength":36}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
"nodes":[{"mesh":0,"children":[1]},{"camera":0,"translation":[0,0,1e20]}],
"scenes":[{"nodes":[0]}],"scene":0,
"cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.01}}]}"#,
    )
    .unwrap();
    let out = dir.path().join("o.png");
    let render = |flags: &[&str]| {
        let mut args = vec![
            "render",
            "--scene",
            s(&scene),
            "--width",
            "16",
            "--out",
            s(&out),
        ];
        args.extend_from_slice(flags);
        raykit(&args)
    };
    let o = render(&[]);
    let e = stderr(&o);
    assert!(!o.status.success(), "{e}");
    assert!(
        e.contains("the camera of scene 'far.gltf'") && e.contains("give --eye and --target"),
        "{e}"
    );
    let o = render(&["--eye", "0.3,0.3,2", "--target", "0.3,0.3,0"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A standard output that cannot take the report (a full disk: Linux's
/// /dev/full) is an error naming stdout with status 1, not a panic; the
/// mesh a command wrote before its report stays whole.
#[cfg(target_os = "linux")]
#[test]
fn a_full_stdout_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("welded.obj");
    let teapot = teapot();
    for args in [
        vec!["info", "accels"],
        vec!["tjunctions", s(&teapot), s(&out), "--json"],
    ] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_raykit"))
            .args(&args)
            .stdout(full)
            .output()
            .unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("raykit: error: stdout: "), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    let written = raykit_io::load_mesh(&out).unwrap();
    assert_eq!(
        written.num_triangles(),
        raykit_io::load_mesh(&teapot).unwrap().num_triangles()
    );
}
