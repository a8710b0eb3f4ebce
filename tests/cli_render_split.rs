//! `raykit render` split over processes as a batch scheduler runs it:
//! bands rendered by separate `--tile I/N` processes and assembled by
//! `raykit merge-tiles` equal the one-process render pixel for pixel, frame
//! ranges of `--orbit` equal the frames of a whole-range run, and bad sets
//! of parts (overlapping, missing, of another size or of another picture:
//! scene, sampling, environment or materials) are refused with errors
//! naming the file.

use std::path::{Path, PathBuf};

#[path = "support/cli.rs"]
mod cli;
use cli::{raykit, s, text};

fn ok(o: &std::process::Output) {
    assert!(o.status.success(), "{}", text(&o.stderr));
}

fn pixels(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

fn render(extra: &[&str], out: &Path) {
    let mut args = vec!["render", "--width", "90", "--height", "61"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", s(out)]);
    ok(&raykit(&args));
}

#[test]
fn merged_bands_equal_the_one_process_render() {
    let dir = tempfile::tempdir().unwrap();
    for (name, opts) in [
        ("jittered", &["--spp", "3"][..]),
        (
            "wavefront-raster-maps",
            &[
                "--integrator",
                "wavefront",
                "--primary",
                "raster",
                "--shadows",
                "maps",
            ][..],
        ),
    ] {
        let whole = dir.path().join(format!("{name}.png"));
        render(opts, &whole);
        let n = 4;
        let parts: Vec<PathBuf> = (0..n)
            .map(|i| {
                let p = dir.path().join(format!("{name}-part{i}.png"));
                let tile = format!("{i}/{n}");
                let mut a = opts.to_vec();
                a.extend_from_slice(&["--tile", &tile, "--threads", "1"]);
                render(&a, &p);
                // A band is a band of the image: full width, a quarter of the rows.
                let (w, h) = pixels(&p).dimensions();
                assert!(
                    w == 90 && (15..=16).contains(&h),
                    "{name} band {i}: {w}x{h}"
                );
                p
            })
            .collect();
        let merged = dir.path().join(format!("{name}-merged.png"));
        // Parts in any order.
        let order = [2, 0, 3, 1];
        let mut args = vec!["merge-tiles", s(&merged)];
        args.extend(order.iter().map(|&i| s(&parts[i])));
        // A name that promises another format is refused, and nothing is written.
        let jpg = dir.path().join(format!("{name}-merged.jpg"));
        let mut wrong = args.clone();
        wrong[1] = s(&jpg);
        let o = raykit(&wrong);
        assert!(!o.status.success() && !jpg.exists());
        assert!(String::from_utf8_lossy(&o.stderr).contains(".png"));
        ok(&raykit(&args));
        let (a, b) = (pixels(&whole), pixels(&merged));
        assert_eq!(a.dimensions(), b.dimensions());
        assert!(
            a.as_raw() == b.as_raw(),
            "{name}: merged bands differ from the one-process render"
        );
    }
}

#[test]
fn frame_ranges_equal_the_whole_range_run() {
    let dir = tempfile::tempdir().unwrap();
    let (all, split) = (dir.path().join("all"), dir.path().join("split"));
    std::fs::create_dir_all(&all).unwrap();
    std::fs::create_dir_all(&split).unwrap();
    render(&["--orbit", "6"], &all.join("f.png"));
    for range in ["0..2", "2..=3", "4..6"] {
        render(&["--orbit", "6", "--frames", range], &split.join("f.png"));
    }
    let mut names: Vec<String> = std::fs::read_dir(&split)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let expected: Vec<String> = (0..6).map(|k| format!("f.{k:04}.png")).collect();
    assert_eq!(names, expected);
    for name in &names {
        let (a, b) = (pixels(&all.join(name)), pixels(&split.join(name)));
        assert!(
            a.as_raw() == b.as_raw(),
            "{name}: the split run's frame differs"
        );
    }
    // Frame 0 is the scene camera's own view; the others turn around it.
    let still = dir.path().join("still.png");
    render(&[], &still);
    assert!(pixels(&still).as_raw() == pixels(&all.join("f.0000.png")).as_raw());
    assert!(pixels(&all.join("f.0000.png")).as_raw() != pixels(&all.join("f.0003.png")).as_raw());
}

#[test]
fn bad_sets_of_parts_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let part = |i: u32, n: u32, h: &str| {
        let p = dir.path().join(format!("p{i}of{n}h{h}.png"));
        let tile = format!("{i}/{n}");
        ok(&raykit(&[
            "render",
            "--width",
            "40",
            "--height",
            h,
            "--tile",
            &tile,
            "--out",
            s(&p),
        ]));
        p
    };
    let (p0, p1, p2) = (part(0, 3, "30"), part(1, 3, "30"), part(2, 3, "30"));
    let out = dir.path().join("merged.png");
    let fails = |parts: &[&Path], needles: &[&str]| {
        let mut args = vec!["merge-tiles", s(&out)];
        args.extend(parts.iter().map(|p| s(p)));
        let o = raykit(&args);
        let err = text(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        for n in needles {
            assert!(err.contains(n), "{args:?}: '{n}' not in: {err}");
        }
        assert!(!out.exists(), "{args:?} wrote its output");
    };
    // A band given twice overlaps itself.
    fails(&[&p0, &p1, &p1, &p2], &["p1of3h30.png", "overlaps"]);
    // A missing band leaves rows uncovered (band 1: rows 10 to 19).
    fails(&[&p0, &p2], &["uncovered", "row 10"]);
    // Bands of another image size.
    let other = part(1, 3, "33");
    fails(&[&p0, &other, &p2], &["p1of3h33.png", "40×33", "40×30"]);
    // A band of another picture of the same size: another scene, more
    // samples per pixel, another environment or other materials.
    for (i, other) in [
        ["--scene", "builtin:cornell"],
        ["--spp", "2"],
        ["--env", "black"],
        ["--env", "0.2,0.3,0.4"],
        ["--material", "glass"],
    ]
    .iter()
    .enumerate()
    {
        let p = dir.path().join(format!("other{i}.png"));
        let mut args = vec!["render", "--width", "40", "--height", "30", "--tile", "1/3"];
        args.extend_from_slice(other);
        args.extend_from_slice(&["--out", s(&p)]);
        ok(&raykit(&args));
        fails(
            &[&p0, &p, &p2],
            &[&format!("other{i}.png"), "another picture"],
        );
    }
    // Bands of another split overlap.
    let half = part(0, 2, "30");
    fails(&[&p0, &half], &["p0of2h30.png", "overlaps"]);
    // A plain PNG is no part.
    let plain = dir.path().join("plain.png");
    ok(&raykit(&[
        "render",
        "--width",
        "40",
        "--height",
        "30",
        "--out",
        s(&plain),
    ]));
    fails(&[&plain], &["plain.png", "raykit-part"]);
    // Not a PNG at all.
    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"not a png").unwrap();
    fails(&[&p0, &junk], &["junk.png"]);
    ok(&raykit(&["merge-tiles", s(&out), s(&p2), s(&p0), s(&p1)]));
    assert_eq!(pixels(&out).as_raw(), pixels(&plain).as_raw());

    let never = dir.path().join("never.png");
    let never_exr = dir.path().join("never.exr");
    for (args, needle) in [
        (&["--tile", "3/3", "--out", s(&never)][..], "--tile"),
        (&["--tile", "0/3", "--out", s(&never_exr)][..], ".png"),
        (&["--tile", "0/31", "--out", s(&never)][..], "at most 30"),
        (&["--frames", "0..2", "--out", s(&never)][..], "--orbit"),
        (
            &["--orbit", "4", "--frames", "2..6", "--out", s(&never)][..],
            "past the 4 frames",
        ),
    ] {
        let mut a = vec!["render", "--width", "40", "--height", "30"];
        a.extend_from_slice(args);
        let o = raykit(&a);
        assert!(!o.status.success(), "{a:?} succeeded");
        assert!(
            text(&o.stderr).contains(needle),
            "{a:?}: {}",
            text(&o.stderr)
        );
    }
    assert!(!never.exists() && !never_exr.exists());
}
