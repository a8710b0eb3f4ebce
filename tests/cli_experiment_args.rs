//! `raykit experiment` refuses out-of-range options before any work starts:
//! a non-zero exit, a message naming the option, and no output folder; and
//! the terrain experiment's report links only heat maps it wrote.

#[path = "support/cli.rs"]
mod cli;
use cli::{raykit, s, text};

/// Run `experiment ARGS --out DIR` and check that it was refused naming
/// every one of `needles`, without creating DIR.
fn refused(args: &[&str], needles: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = raykit(&[&["experiment"][..], args, &["--out", s(&out)]].concat());
    let err = text(&o.stderr);
    assert!(!o.status.success(), "{args:?} was accepted: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: '{n}' not in: {err}");
    }
    assert!(!out.exists(), "{args:?} created {}", out.display());
}

#[test]
fn sizes_reps_and_counts_out_of_range_are_refused_up_front() {
    let big = (raykit_io::MAX_IMAGE_SIDE + 1).to_string();
    let mesh = ["--mesh", "builtin:cornell"];
    for (args, needles) in [
        // Checked before the GPU is opened: no adapter needed.
        (
            vec!["gpu", "--size", "0", "--dem", "none"],
            vec!["--size", "0"],
        ),
        (
            vec!["gpu", "--size", &big, "--dem", "none"],
            vec!["--size", &big],
        ),
        (
            vec!["gpu", "--dem", "nonexist.tif"],
            vec!["--dem", "nonexist.tif"],
        ),
        (vec!["kdtree-traversal", "--size", "0"], vec!["--size", "0"]),
        (
            vec!["kdtree-traversal", "--size", &big],
            vec!["--size", &big],
        ),
        (vec!["kdtree-traversal", "--reps", "0"], vec!["--reps", "0"]),
        (vec!["split-heuristic", "--size", "0"], vec!["--size", "0"]),
        (
            vec!["split-heuristic", "--size", &big],
            vec!["--size", &big],
        ),
        (vec!["split-heuristic", "--reps", "0"], vec!["--reps", "0"]),
        (
            vec!["split-heuristic", "--frustums", "0"],
            vec!["--frustums"],
        ),
        (vec!["terrain", "--reps", "0"], vec!["--reps", "0"]),
        (
            vec!["terrain", "--flythrough", "0"],
            vec!["--flythrough", "0"],
        ),
        (vec!["terrain", "--width", "0"], vec!["--width", "0"]),
        (vec!["terrain", "--size", "15"], vec!["--size", "15"]),
        (
            vec!["terrain", "--parts", "c", "--size", "16385"],
            vec!["--size", "16385"],
        ),
        (
            vec!["terrain", "--parts", "b", "--shadow-sizes", "32,15"],
            vec!["--shadow-sizes", "15"],
        ),
        (vec!["cull", "--reps", "0"], vec!["--reps", "0"]),
        (vec!["serve", "--format", "raw"], vec!["--connect"]),
        (vec!["serve", "--quality", "50"], vec!["--connect"]),
    ] {
        let with_mesh = matches!(args[0], "gpu" | "kdtree-traversal" | "split-heuristic");
        let args = if with_mesh {
            [&args[..1], &mesh[..], &args[1..]].concat()
        } else {
            args
        };
        refused(&args, &needles);
    }
}

/// `experiment cull --resolutions` takes what `raykit cull --resolution`
/// takes: both refuse the values just outside the grid's range.
#[test]
fn cull_resolutions_have_the_range_of_raykit_cull() {
    let dir = tempfile::tempdir().unwrap();
    let (input, output) = (dir.path().join("in.obj"), dir.path().join("out.obj"));
    std::fs::write(&input, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let (lo, hi) = (
        raykit_cull::Grid::MIN_RESOLUTION,
        raykit_cull::Grid::MAX_RESOLUTION,
    );
    for bad in [0, lo - 1, hi + 1, 100_000] {
        let bad = bad.to_string();
        let o = raykit(&["cull", s(&input), s(&output), "--resolution", &bad]);
        assert!(!o.status.success(), "raykit cull took --resolution {bad}");
        refused(&["cull", "--resolutions", &bad], &["--resolutions", &bad]);
        refused(
            &["cull", "--resolutions", &format!("64,{bad}")],
            &["--resolutions", &bad],
        );
    }
}

/// Each part of the terrain experiment reads only its own sizes: part (b)
/// runs with a `--size` that parts (a) and (c) would refuse, and its
/// brute-force and fast masks agree.
#[test]
fn terrain_part_b_ignores_the_size_of_the_other_parts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = raykit(&[
        "experiment",
        "terrain",
        "--parts",
        "b",
        "--size",
        "15",
        "--shadow-sizes",
        "32",
        "--reps",
        "1",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let csv = std::fs::read_to_string(out.join("shadow.csv")).expect("shadow.csv");
    assert_eq!(csv.lines().count(), 2, "{csv}");
}

/// The heat maps results.md names are the ones written: the box method's
/// at τ = 16 when 16 is measured, else at the τ nearest to it.
#[test]
fn terrain_results_link_heat_maps_that_exist() {
    for (taus, boxes) in [
        ("4", "heat-boxes-tau4.png"),
        ("4,16,64", "heat-boxes-tau16.png"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let o = raykit(&[
            "experiment",
            "terrain",
            "--size",
            "32",
            "--width",
            "24",
            "--height",
            "16",
            "--taus",
            taus,
            "--parts",
            "a",
            "--reps",
            "1",
            "--out",
            s(&out),
        ]);
        let err = text(&o.stderr);
        assert!(!err.contains("panicked"), "{err}");
        let md = std::fs::read_to_string(out.join("results.md")).expect("results.md");
        let line = md
            .lines()
            .find(|l| l.starts_with("Heat maps"))
            .expect("a heat map line");
        let named: Vec<&str> = line
            .split([' ', ','])
            .map(|w| w.trim_end_matches('.'))
            .filter(|w| w.ends_with(".png"))
            .collect();
        assert!(named.contains(&boxes), "--taus {taus}: {line}");
        for name in named {
            assert!(
                out.join(name).is_file(),
                "--taus {taus}: {name} named but not written"
            );
        }
    }
}
