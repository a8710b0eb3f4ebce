//! `raykit terrain shadow` end to end: the GeoTIFF mask carries the DEM's
//! georeferencing and equals the library's brute-force mask, and its
//! preview shows each cell's class in its colour; `--compare`
//! finds no difference; `--sun-path` on a flat DEM gives every cell the
//! day's full daylight (counted independently from the solar formula);
//! bad arguments name the flag; the default no-data value steps aside for
//! the mask values.

#[path = "support/cli.rs"]
mod cli;

use cli::{raykit, s, text};
use raykit_terrain::io::{load_dem, read_geotiff, LoadOptions};
use raykit_terrain::mask_cells::MaskCell;
use raykit_terrain::shadow::{shadow_mask, Light, ShadowMethod};
use raykit_terrain::{HeightField, MaxMipmap};
use std::path::{Path, PathBuf};

fn ter() -> PathBuf {
    let root = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data"));
    let p = root.join("terrain/lidar_dem_400.tif");
    assert!(
        p.is_file(),
        "{} is missing: the tests need the test data folder",
        p.display()
    );
    p
}

#[test]
fn point_light_mask_keeps_the_georeferencing_and_equals_brute_force() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mask.tif");
    let dem = load_dem(ter(), &LoadOptions::default()).unwrap();
    // A light 3 m above the ground at the centre of the DEM, in map units.
    let (mx, my) = dem.grid_to_map(200.0, 200.0);
    let light = format!("{mx},{my},3");
    let o = raykit(&[
        "terrain",
        "shadow",
        s(&ter()),
        "--light",
        &light,
        "--out",
        s(&out),
        "--compare",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("cells that differ: 0 of 160000"),
        "{}",
        text(&o.stderr)
    );
    let mask = read_geotiff(&out).unwrap();
    // The preview shows each cell's class in its colour.
    let preview = image::open(dir.path().join("mask.png")).unwrap().to_rgb8();
    assert_eq!(preview.dimensions(), (dem.width as u32, dem.height as u32));
    for (p, &v) in preview.pixels().zip(&mask.heights) {
        let class = match v as u8 {
            1 => MaskCell::Lit,
            0 => MaskCell::Shadow,
            255 => MaskCell::NoData,
            other => panic!("mask value {other}"),
        };
        assert_eq!(p.0, class.preview(), "value {v}");
    }
    assert_eq!((mask.width, mask.height), (dem.width, dem.height));
    assert_eq!(mask.georef.origin_x, dem.georef.origin_x);
    assert_eq!(mask.georef.origin_y, dem.georef.origin_y);
    assert_eq!(mask.georef.pixel_width, dem.georef.pixel_width);
    assert_eq!(mask.georef.pixel_height, dem.georef.pixel_height);
    assert_eq!(mask.georef.geo_keys, dem.georef.geo_keys);
    // The same light through the library's brute force.
    let field = HeightField::new(&dem).unwrap();
    let pyramid = MaxMipmap::new(&field);
    let ground = field.height_at(200.0, 200.0);
    let reference = shadow_mask(
        &field,
        &pyramid,
        &Light::Point([200.0 * field.sx, -200.0 * field.sy, ground + 3.0]),
        ShadowMethod::BruteForce,
    );
    let got: Vec<u8> = mask.heights.iter().map(|&v| v as u8).collect();
    assert_eq!(got, reference);
    let lit = reference.iter().filter(|&&m| m == 1).count();
    assert!(lit > 1000 && lit < 159_000, "lit {lit}");
}

#[test]
fn sun_path_on_a_flat_dem_gives_every_cell_the_whole_day() {
    let dir = tempfile::tempdir().unwrap();
    // A flat 16-bit PNG DEM: no shadows anywhere.
    let png = dir.path().join("flat.png");
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_pixel(20, 20, image::Luma([100u16]))
        .save(&png)
        .unwrap();
    let out = dir.path().join("hours.tif");
    let o = raykit(&[
        "terrain",
        "shadow",
        s(&png),
        "--sun-path",
        "2026-06-21,59.3,18.0",
        "--step-minutes",
        "10",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let hours = read_geotiff(&out).unwrap();
    // Independent count: 10-minute steps (at their midpoints) with the sun up.
    let up = (0..144)
        .filter(|k| {
            raykit_terrain::sun::sun_position(172, (*k as f64 + 0.5) / 6.0, 59.3, 18.0).1 > 0.0
        })
        .count() as f32;
    let want = up / 6.0;
    assert!(
        want > 17.0 && want < 19.5,
        "Stockholm midsummer daylight {want} h"
    );
    for &h in &hours.heights {
        assert!((h - want).abs() < 1e-3, "{h} vs {want}");
    }
}

#[test]
fn bad_arguments_name_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.tif");
    let dem = ter();
    // The command fails, naming `needle`.
    let refused = |args: &[&str], needle: &str| {
        let mut a = vec!["terrain", "shadow"];
        a.extend(args);
        let o = raykit(&a);
        assert!(
            !o.status.success() && text(&o.stderr).contains(needle),
            "{args:?}: {}",
            text(&o.stderr)
        );
    };
    for (args, needle) in [
        (vec!["--light", "1,2"], "--light"),
        (vec!["--light", "0,0,5"], "outside the DEM"),
        (vec!["--sun", "135,120"], "--sun"),
        (vec!["--sun", "135,20", "--light", "1,2,3"], "exactly one"),
        (vec!["--sun-path", "2026-02-30,10,10"], "not a date"),
        (
            vec!["--light-elevation", "--sun", "10,10"],
            "--light-elevation",
        ),
        // The mask's options do not apply to the hours of sun.
        (
            vec!["--sun-path", "2026-06-21,45,0", "--iv", "9"],
            "--invisible-value",
        ),
        (
            vec!["--sun-path", "2026-06-21,45,0", "--compare"],
            "--compare",
        ),
        (
            vec!["--sun-path", "2026-06-21,45,0", "--nodata-value", "7"],
            "--nodata-value",
        ),
        (
            vec!["--sun", "135,20", "--step-minutes", "5"],
            "--step-minutes",
        ),
        (
            vec!["--light", "429452,5150685,10", "--cc", "1e30"],
            "lowered by --curvature-coefficient 1e30",
        ),
    ] {
        let mut a = vec![s(&dem)];
        a.extend(args.iter().copied());
        a.extend(["--out", s(&out)]);
        refused(&a, needle);
    }
    let (dem, out) = (s(&dem), s(&out));
    refused(
        &["/no/such/dem.tif", "--sun", "1,1", "--out", out],
        "/no/such/dem.tif",
    );
    // The output never replaces the input.
    refused(&[dem, "--sun", "1,1", "--out", dem], "also an input");
    // Outputs are named for their format: the mask is a GeoTIFF (`--out
    // m.png` would also have put the preview at m.png), the preview a PNG.
    let png_out = dir.path().join("m.png");
    refused(
        &[dem, "--sun", "135,20", "--out", s(&png_out)],
        "must end in .tif",
    );
    assert!(!png_out.exists());
    let jpg = dir.path().join("p.jpg");
    refused(
        &[dem, "--sun", "135,20", "--out", out, "--preview", s(&jpg)],
        "--preview (a PNG) must end in .png",
    );
    assert!(!jpg.exists() && !Path::new(out).exists());
    // A preview that cannot be written stops the command before the GeoTIFF
    // is written.
    refused(
        &[
            dem,
            "--sun",
            "135,20",
            "--out",
            out,
            "--preview",
            "/no/such/folder/m.png",
        ],
        "/no/such/folder",
    );
    assert!(!Path::new(out).exists());
}

/// A point light over a cell without data has no ground to stand on: its
/// height above the ground is refused, naming the sample, by the mask and
/// the render alike, and nothing is written; an absolute elevation works.
#[test]
fn a_light_over_no_data_needs_its_elevation() {
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("g.asc");
    std::fs::write(
        &dem,
        "ncols 4\nnrows 4\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n\
         1 2 3 4\n4 -9999 6 7\n7 8 9 10\n1 1 1 1\n",
    )
    .unwrap();
    let (mask, picture) = (dir.path().join("m.tif"), dir.path().join("r.png"));
    // The grid points lie at cell centres: (1.5, 2.5) is row 1, column 1.
    for args in [
        vec!["shadow", s(&dem), "--light", "1.5,2.5,2", "--out", s(&mask)],
        vec!["shadow", s(&dem), "--light", "2,2,2", "--out", s(&mask)],
        vec![
            "render",
            s(&dem),
            "--light",
            "1.5,2.5,2",
            "--out",
            s(&picture),
        ],
    ] {
        let mut a = vec!["terrain"];
        a.extend(&args);
        let o = raykit(&a);
        assert!(
            !o.status.success() && text(&o.stderr).contains("no height at row 1, column 1"),
            "{args:?}: {}",
            text(&o.stderr)
        );
        assert!(!mask.exists() && !picture.exists(), "{args:?}");
    }
    // Beside the hole, on the edge between two valid samples, the ground is known.
    for light in ["2.5,3.5,2", "1.5,2.5,2"] {
        let mut a = vec!["terrain", "shadow", s(&dem), "--light", light];
        if light == "1.5,2.5,2" {
            a.push("--light-elevation");
        }
        a.extend(["--out", s(&mask)]);
        let o = raykit(&a);
        assert!(o.status.success(), "{light}: {}", text(&o.stderr));
        // The share lit counts the grid points with data only.
        let written = read_geotiff(&mask).unwrap();
        let lit = written.heights.iter().filter(|&&v| v == 1.0).count();
        let with_data = written
            .heights
            .iter()
            .filter(|&&v| v == 0.0 || v == 1.0)
            .count();
        assert_eq!(with_data, 15, "{light}");
        let line = format!(
            "{:.1}% of the grid points with data lit",
            100.0 * lit as f64 / with_data as f64
        );
        assert!(
            text(&o.stderr).contains(&line),
            "{light}: {}",
            text(&o.stderr)
        );
    }
}

#[test]
fn the_default_nodata_value_steps_aside_for_the_mask_values() {
    // gdal_viewshed's -vv 255: the no-data value moves to 254, unless given.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.tif");
    let dem = ter();
    for (extra, nodata) in [
        (vec![], 255.0),
        (vec!["--vv", "255"], 254.0),
        (vec!["--vv", "255", "--iv", "254"], 253.0),
        (vec!["--vv", "255", "--nodata-value", "7"], 7.0),
    ] {
        let mut a = vec!["terrain", "shadow", s(&dem), "--sun", "135,20"];
        a.extend(extra.iter().copied());
        a.extend(["--out", s(&out)]);
        let o = raykit(&a);
        assert!(o.status.success(), "{extra:?}: {}", text(&o.stderr));
        assert_eq!(
            read_geotiff(&out).unwrap().nodata,
            Some(nodata),
            "{extra:?}"
        );
    }
    let o = raykit(&[
        "terrain",
        "shadow",
        s(&dem),
        "--sun",
        "135,20",
        "--vv",
        "255",
        "--nodata-value",
        "255",
        "--out",
        s(&out),
    ]);
    assert!(
        !o.status.success() && text(&o.stderr).contains("--nodata-value 255"),
        "{}",
        text(&o.stderr)
    );
}

/// A DEM too large for the memory the process may use is an error naming
/// its size, not an abort: a sparse 32768² float file (4 GiB of heights)
/// under a 2 GiB address-space limit.
#[cfg(target_os = "linux")]
#[test]
fn a_dem_larger_than_memory_allows_is_an_error_not_an_abort() {
    refused_under_limit(32768, 2097152);
}

/// Heights that fit in memory while the pyramid built over them would not
/// are refused at load, naming the size: a sparse 16384² float file (1 GiB
/// of heights, 2.7 GiB of max-mipmap pyramid) under a 3 GiB limit, where
/// the pyramid's allocation used to abort the process.
#[cfg(target_os = "linux")]
#[test]
fn a_dem_whose_pyramid_would_not_fit_is_an_error_not_an_abort() {
    refused_under_limit(16384, 3145728);
}

/// `terrain shadow` on a sparse `side`² float file under `ulimit -v
/// limit_kib` ends with status 1, naming the file and its size, and writes
/// nothing.
#[cfg(target_os = "linux")]
fn refused_under_limit(side: u64, limit_kib: u64) {
    let dir = tempfile::tempdir().unwrap();
    let dem = dir.path().join("big.r32");
    let file = std::fs::File::create(&dem).unwrap();
    file.set_len(side * side * 4).unwrap();
    let out = dir.path().join("m.tif");
    let script = format!(
        "ulimit -v {limit_kib}; exec {} terrain shadow {} --sun 135,30 --out {}",
        env!("CARGO_BIN_EXE_raykit"),
        s(&dem),
        s(&out)
    );
    let o = std::process::Command::new("bash")
        .args(["-c", &script])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    let size = format!("{side}×{side}");
    assert!(
        e.contains("big.r32") && e.contains(&size) && e.contains("cannot be allocated"),
        "{e}"
    );
    assert!(!out.exists());
}
