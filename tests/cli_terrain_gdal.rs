//! `raykit terrain shadow` with gdal_viewshed's conventions, read back by
//! GDAL's own tools (gdalinfo, gdal_translate from Debian's gdal-bin, which
//! scripts/test installs): the values of visible, invisible, out-of-range
//! and no-data cells, the target height, the maximum distance, the
//! compression and tiling (`--co`) as GDAL sees them, every cell against the
//! library's brute force; and the mask against gdal_viewshed's own on the
//! same DEM and observer, flat and with the earth's curvature; GeoTIFFs in
//! GDAL's layouts, nodata, band scaling, south-up rows and units read as
//! GDAL reads them.

#[path = "support/cli.rs"]
mod cli;

use cli::{raykit, s, text};
use raykit_terrain::curvature::curvature_corrected;
use raykit_terrain::io::{load_dem, LoadOptions};
use raykit_terrain::shadow::{shadow_mask_for_targets, Light, ShadowMethod};
use raykit_terrain::{Dem, HeightField};
use std::path::{Path, PathBuf};
use std::process::Command;

fn data(rel: &str) -> PathBuf {
    let root = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data"));
    let p = root.join(rel);
    assert!(p.is_file(), "{} is missing (test data)", p.display());
    p
}

/// Run a GDAL tool; a missing tool fails with the package to install.
fn gdal(tool: &str, args: &[&str]) -> String {
    let o = Command::new(tool).args(args).output().unwrap_or_else(|e| {
        panic!("{tool} does not run ({e}): apt-get install gdal-bin (scripts/test installs it)")
    });
    assert!(
        o.status.success(),
        "{tool} {args:?} failed: {}",
        text(&o.stderr)
    );
    text(&o.stdout)
}

fn gdalinfo(path: &Path) -> serde_json::Value {
    serde_json::from_str(&gdal("gdalinfo", &["-json", s(path)])).expect("gdalinfo -json")
}

/// The samples of band 1 as GDAL decodes them: gdal_translate to a raw
/// ENVI file, read back as bytes.
fn gdal_bytes(path: &Path, dir: &Path, name: &str) -> Vec<u8> {
    let raw = dir.join(format!("{name}.raw"));
    gdal("gdal_translate", &["-q", "-of", "ENVI", s(path), s(&raw)]);
    std::fs::read(&raw).unwrap()
}

/// Light `h` metres above the ground at grid point (`col`, `row`): map
/// coordinates for the command line, and the library's light.
fn light_at(dem: &Dem, field: &HeightField, col: usize, row: usize, h: f64) -> (String, Light) {
    let (mx, my) = dem.grid_to_map(col as f64, row as f64);
    let ground = field.at(col, row) as f64;
    (
        format!("{mx},{my},{h}"),
        Light::Point([col as f64 * field.sx, -(row as f64) * field.sy, ground + h]),
    )
}

#[test]
fn gdal_style_values_tiles_and_compression_read_back_in_gdal() {
    let dir = tempfile::tempdir().unwrap();
    let dem_path = data("terrain/lidar_dem_400.tif");
    let dem = load_dem(&dem_path, &LoadOptions::default()).unwrap();
    let field = HeightField::new(&dem).unwrap();
    let (arg, light) = light_at(&dem, &field, 200, 170, 3.0);
    let (tz, md) = (1.5, 120.0);
    let (vv, iv, ov, nv) = (255u8, 10u8, 128u8, 200u8);
    // The reference, computed here: brute force for the targets 1.5 m above
    // the ground, then gdal_viewshed's classes by distance and no-data.
    let lit = shadow_mask_for_targets(&field, None, &light, ShadowMethod::BruteForce, tz, &|_| {});
    let want: Vec<u8> = (0..lit.len())
        .map(|i| {
            let (c, r) = ((i % dem.width) as f64, (i / dem.width) as f64);
            let d = ((c - 200.0) * field.sx).hypot((r - 170.0) * field.sy);
            if dem.heights[i].is_nan() {
                nv
            } else if d > md {
                ov
            } else if lit[i] == 1 {
                vv
            } else {
                iv
            }
        })
        .collect();
    for v in [vv, iv, ov] {
        assert!(want.contains(&v), "the view should have value {v}");
    }
    let tz_s = tz.to_string();
    let md_s = md.to_string();
    let common = [
        "terrain",
        "shadow",
        s(&dem_path),
        "--light",
        &arg,
        "--tz",
        &tz_s,
        "--md",
        &md_s,
        "--vv",
        "255",
        "--iv",
        "10",
        "--ov",
        "128",
        "--nodata-value",
        "200",
    ];
    // Layouts: DEFLATE strips by default, then each --co choice; GDAL's
    // COMPRESSION metadata and block size for each.
    type Layout<'a> = (&'a str, &'a [&'a str], Option<&'a str>, Option<[u64; 2]>);
    let layouts: [Layout; 5] = [
        ("default", &[], Some("DEFLATE"), None),
        (
            "tiled",
            &[
                "--co",
                "TILED=YES",
                "--co",
                "BLOCKXSIZE=64",
                "--co",
                "BLOCKYSIZE=48",
            ],
            Some("DEFLATE"),
            Some([64, 48]),
        ),
        ("lzw", &["--co", "COMPRESS=LZW"], Some("LZW"), None),
        (
            "packbits-tiled",
            &["--co", "COMPRESS=PACKBITS", "--co", "TILED=YES"],
            Some("PACKBITS"),
            Some([256, 256]),
        ),
        ("none", &["--co", "COMPRESS=NONE"], None, None),
    ];
    let dem_info = gdalinfo(&dem_path);
    for (name, co, compression, block) in layouts {
        let out = dir.path().join(format!("{name}.tif"));
        let mut a = common.to_vec();
        a.extend_from_slice(co);
        a.extend(["--out", s(&out)]);
        let o = raykit(&a);
        assert!(o.status.success(), "{name}: {}", text(&o.stderr));
        let info = gdalinfo(&out);
        assert_eq!(info["size"], serde_json::json!([400, 400]), "{name}");
        assert_eq!(info["geoTransform"], dem_info["geoTransform"], "{name}");
        let band = &info["bands"][0];
        assert_eq!(band["type"], "Byte", "{name}");
        assert_eq!(band["noDataValue"].as_f64(), Some(nv as f64), "{name}");
        assert_eq!(
            info["metadata"]["IMAGE_STRUCTURE"]["COMPRESSION"].as_str(),
            compression,
            "{name}: {}",
            info["metadata"]
        );
        if let Some(b) = block {
            assert_eq!(band["block"], serde_json::json!(b), "{name}");
        } else {
            assert_eq!(band["block"][0], 400, "{name}: strips span the row");
        }
        let got = gdal_bytes(&out, dir.path(), name);
        assert_eq!(got.len(), want.len(), "{name}");
        let differ = got.iter().zip(&want).filter(|(a, b)| a != b).count();
        assert_eq!(
            differ, 0,
            "{name}: {differ} cells differ from the reference"
        );
    }
    // The default output is much smaller than the raw mask.
    let size = std::fs::metadata(dir.path().join("default.tif"))
        .unwrap()
        .len();
    let plain = std::fs::metadata(dir.path().join("none.tif"))
        .unwrap()
        .len();
    assert!(
        size * 4 < plain,
        "DEFLATE {size} bytes vs uncompressed {plain}"
    );
}

#[test]
fn sun_hours_tiled_lzw_read_back_in_gdal() {
    let dir = tempfile::tempdir().unwrap();
    // A flat 16-bit PNG DEM: every cell gets the whole day's sun.
    let png = dir.path().join("flat.png");
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_pixel(40, 33, image::Luma([100u16]))
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
        "--co",
        "COMPRESS=LZW",
        "--co",
        "TILED=YES",
        "--co",
        "BLOCKXSIZE=32",
        "--co",
        "BLOCKYSIZE=16",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let info = gdalinfo(&out);
    assert_eq!(info["bands"][0]["type"], "Float32");
    assert_eq!(info["bands"][0]["block"], serde_json::json!([32, 16]));
    assert_eq!(info["metadata"]["IMAGE_STRUCTURE"]["COMPRESSION"], "LZW");
    let bytes = gdal_bytes(&out, dir.path(), "hours");
    let hours: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    assert_eq!(hours.len(), 40 * 33);
    // Independent count: 10-minute steps (at their midpoints) with the sun up.
    let up = (0..144)
        .filter(|k| {
            raykit_terrain::sun::sun_position(172, (*k as f64 + 0.5) / 6.0, 59.3, 18.0).1 > 0.0
        })
        .count() as f32;
    for &h in &hours {
        assert!((h - up / 6.0).abs() < 1e-3, "{h} vs {}", up / 6.0);
    }
}

/// An ASCII grid as gdal_translate exports it, with a `.prj` in Esri's WKT
/// (no EPSG code): the shadow mask and the hours of sun computed from it
/// are in the grid's coordinate system as GDAL reads both, through the
/// `.aux.xml` written beside them, and a GeoTIFF DEM's masks get none (its
/// GeoKeys carry the coordinate system).
#[test]
fn rasters_from_ascii_grids_keep_the_prj_coordinate_system() {
    let dir = tempfile::tempdir().unwrap();
    let tif = data("terrain/lidar_dem_400.tif");
    let asc = dir.path().join("lidar.asc");
    let window = ["-srcwin", "0", "0", "120", "90"];
    gdal(
        "gdal_translate",
        &[&["-q", "-of", "AAIGrid"][..], &window, &[s(&tif), s(&asc)]].concat(),
    );
    assert!(
        dir.path().join("lidar.prj").is_file(),
        "gdal_translate wrote no .prj"
    );
    let crs = |p: &Path| {
        gdalinfo(p)["coordinateSystem"]["wkt"]
            .as_str()
            .unwrap_or("")
            .to_string()
    };
    let want = crs(&asc);
    assert!(
        want.contains("UTM"),
        "the grid's coordinate system as GDAL reads it: {want}"
    );
    for (name, light) in [
        ("mask.tif", ["--sun", "135,30"]),
        ("hours.tif", ["--sun-path", "2026-06-21,45.0,-93.0"]),
    ] {
        let out = dir.path().join(name);
        let o = raykit(
            &[
                &["terrain", "shadow", s(&asc), "--out", s(&out)][..],
                &light,
            ]
            .concat(),
        );
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert_eq!(crs(&out), want, "{name}");
    }
    // A GeoTIFF whose coordinate system is only in its sidecar (the mask
    // above), taken as a DEM, passes it on.
    let again = dir.path().join("again.tif");
    let mask = dir.path().join("mask.tif");
    let o = raykit(&[
        "terrain",
        "shadow",
        s(&mask),
        "--out",
        s(&again),
        "--sun",
        "135,30",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(crs(&again), want, "a mask computed from the mask");
    let out = dir.path().join("from_tif.tif");
    // A sidecar left at the output's path from an earlier file goes.
    std::fs::copy(
        raykit_terrain::io::crs_sidecar_path(&mask),
        raykit_terrain::io::crs_sidecar_path(&out),
    )
    .unwrap();
    let o = raykit(&[
        "terrain",
        "shadow",
        s(&tif),
        "--out",
        s(&out),
        "--sun",
        "135,30",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(!raykit_terrain::io::crs_sidecar_path(&out).exists());
    assert_eq!(crs(&out), crs(&tif));
}

/// Cells where two masks (visible 255, else 0) disagree, among the cells
/// valid in `dem`, as a percentage.
fn percent_differing(a: &[u8], b: &[u8], dem: &Dem) -> f64 {
    let valid: Vec<usize> = (0..a.len()).filter(|&i| !dem.heights[i].is_nan()).collect();
    let differ = valid
        .iter()
        .filter(|&&i| (a[i] == 255) != (b[i] == 255))
        .count();
    100.0 * differ as f64 / valid.len() as f64
}

/// Our mask and gdal_viewshed's for the same DEM, observer and options.
fn ours_and_gdal(dir: &Path, dem_path: &Path, light: &str, extra: &[&str]) -> (Vec<u8>, Vec<u8>) {
    let ours = dir.join("ours.tif");
    let mut a = vec![
        "terrain",
        "shadow",
        s(dem_path),
        "--light",
        light,
        "--vv",
        "255",
        "--iv",
        "0",
        "--nodata-value",
        "254",
        "--out",
        s(&ours),
    ];
    for pair in extra.chunks(2) {
        a.extend([pair[0], pair[1]]);
    }
    let o = raykit(&a);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let xyz: Vec<&str> = light.split(',').collect();
    let theirs = dir.join("gdal.tif");
    let _ = std::fs::remove_file(&theirs);
    let mut g = vec![
        "-q", "-ox", xyz[0], "-oy", xyz[1], "-oz", xyz[2], "-vv", "255", "-iv", "0", "-ov", "0",
    ];
    for pair in extra.chunks(2) {
        g.extend([pair[0].trim_start_matches('-'), pair[1]]);
    }
    let g: Vec<String> = g
        .iter()
        .map(|a| match *a {
            "tz" | "cc" => format!("-{a}"),
            _ => a.to_string(),
        })
        .collect();
    let mut args: Vec<&str> = g.iter().map(String::as_str).collect();
    args.extend([s(dem_path), s(&theirs)]);
    gdal("gdal_viewshed", &args);
    (
        gdal_bytes(&ours, dir, "ours"),
        gdal_bytes(&theirs, dir, "gdal"),
    )
}

#[test]
fn agrees_with_gdal_viewshed_on_a_lidar_dem() {
    let dir = tempfile::tempdir().unwrap();
    let dem_path = data("terrain/lidar_dem_400.tif");
    let dem = load_dem(&dem_path, &LoadOptions::default()).unwrap();
    let (mx, my) = dem.grid_to_map(200.0, 170.0);
    let light = format!("{mx},{my},3");
    let (ours, theirs) =
        ours_and_gdal(dir.path(), &dem_path, &light, &["--tz", "1.5", "--cc", "0"]);
    assert_eq!(ours.len(), theirs.len());
    let pct = percent_differing(&ours, &theirs, &dem);
    let lit = ours.iter().filter(|&&v| v == 255).count();
    eprintln!("lidar 400x400, observer 3 m, targets 1.5 m: {pct:.2}% of the cells differ from gdal_viewshed ({lit} lit)");
    assert!(lit > 1000 && lit < 159_000, "lit {lit}");
    // gdal_viewshed decides each cell from two neighbours nearer the
    // observer (Wang et al. 2000), an approximation of the exact answer.
    assert!(
        pct < 3.0,
        "{pct:.2}% of the cells differ from gdal_viewshed"
    );
}

#[test]
fn agrees_with_gdal_viewshed_over_the_curved_earth() {
    let dir = tempfile::tempdir().unwrap();
    // The SRTM tile in UTM zone 32 (180 m cells, about 60 km across), where
    // the earth's curvature hides tens of metres at the far side.
    let utm = dir.path().join("utm.tif");
    gdal(
        "gdalwarp",
        &[
            "-q",
            "-t_srs",
            "EPSG:32632",
            "-tr",
            "180",
            "180",
            "-r",
            "bilinear",
            "-dstnodata",
            "-32768",
            s(&data("terrain/N57E011.hgt")),
            s(&utm),
        ],
    );
    let dem = load_dem(&utm, &LoadOptions::default()).unwrap();
    let (col, row) = (dem.width / 2, dem.height / 2);
    assert!(!dem.at(col, row).is_nan());
    let (mx, my) = dem.grid_to_map(col as f64, row as f64);
    let light = format!("{mx},{my},60");
    let (flat, flat_gdal) = ours_and_gdal(dir.path(), &utm, &light, &["--tz", "2", "--cc", "0"]);
    let (curved, curved_gdal) =
        ours_and_gdal(dir.path(), &utm, &light, &["--tz", "2", "--cc", "0.85714"]);
    let flat_pct = percent_differing(&flat, &flat_gdal, &dem);
    let curved_pct = percent_differing(&curved, &curved_gdal, &dem);
    let effect = percent_differing(&flat, &curved, &dem);
    eprintln!(
        "SRTM N57E011 in UTM 32N ({}x{}), observer 60 m, targets 2 m: differing from gdal_viewshed \
         {flat_pct:.2}% flat (-cc 0), {curved_pct:.2}% curved (-cc 0.85714); the curvature changes {effect:.2}%",
        dem.width, dem.height
    );
    // The warp leaves no data round the tile; there, and only there, both
    // masks hold --nodata-value.
    let missing = dem.heights.iter().filter(|h| h.is_nan()).count();
    assert!(missing > 0, "the warped tile should have no-data cells");
    for (i, h) in dem.heights.iter().enumerate() {
        assert_eq!(flat[i] == 254, h.is_nan(), "flat mask, cell {i}");
        assert_eq!(curved[i] == 254, h.is_nan(), "curved mask, cell {i}");
    }
    // The curvature matters here, and both tools apply it alike.
    assert!(effect > 1.0, "the curvature changed only {effect:.2}%");
    assert!(flat_pct < 3.0, "{flat_pct:.2}%");
    assert!(curved_pct < 3.0, "{curved_pct:.2}%");
    // Our curved mask is the exact mask of the corrected heights.
    let corrected = curvature_corrected(&dem, col as f64, row as f64, 0.85714);
    let field = HeightField::new(&corrected).unwrap();
    let ground = field.at(col, row) as f64;
    let lit = shadow_mask_for_targets(
        &field,
        None,
        &Light::Point([
            col as f64 * field.sx,
            -(row as f64) * field.sy,
            ground + 60.0,
        ]),
        ShadowMethod::BruteForce,
        2.0,
        &|_| {},
    );
    for (i, (&l, &c)) in lit.iter().zip(&curved).enumerate() {
        if !dem.heights[i].is_nan() {
            assert_eq!(l == 1, c == 255, "cell {i}");
        }
    }
}

/// GeoTIFFs as GDAL writes them read as GDAL reads them: the lidar DEM,
/// its first 150 rows made no-data, converted by gdal_translate with the
/// creation options people use for DEMs (ZSTD, the floating-point and
/// integer predictors, BigTIFF, COG, blocks of no data left out with
/// `SPARSE_OK`, separate planes) and as an Esri ASCII grid, read by the
/// library and compared sample for sample with GDAL's own decoding of the
/// same file.
#[test]
fn geotiffs_as_gdal_writes_them_read_as_gdal_reads_them() {
    let dir = tempfile::tempdir().unwrap();
    let dem = load_dem(data("terrain/lidar_dem_400.tif"), &LoadOptions::default()).unwrap();
    let mut heights = dem.heights.clone();
    heights[..150 * dem.width].fill(f32::NAN);
    let src = dir.path().join("src.tif");
    raykit_terrain::io::write_geotiff_f32(
        &src,
        dem.width,
        dem.height,
        &heights,
        &dem.georef,
        Some(-9999.0),
    )
    .unwrap();
    // gdal_translate options, one layout each.
    let cases: [&str; 18] = [
        "-co COMPRESS=ZSTD",
        "-co COMPRESS=ZSTD -co PREDICTOR=3 -co TILED=YES",
        "-co COMPRESS=DEFLATE -co PREDICTOR=3",
        "-ot Int16 -co COMPRESS=LZW -co PREDICTOR=2",
        "-co BIGTIFF=YES -co TILED=YES -co BLOCKXSIZE=128",
        "-of COG -co COMPRESS=DEFLATE",
        "-co SPARSE_OK=TRUE",
        "-co SPARSE_OK=TRUE -co COMPRESS=DEFLATE -co PREDICTOR=3",
        "-co SPARSE_OK=TRUE -co TILED=YES -co BLOCKYSIZE=64 -co BLOCKXSIZE=64",
        "-co INTERLEAVE=BAND -co COMPRESS=PACKBITS",
        "-of AAIGrid",
        // LZW tiles whose edge tiles the `tiff` crate fails to decode, and
        // each predictor and sample width through the same decoder.
        "-ot Int16 -co COMPRESS=LZW -co TILED=YES -co BLOCKXSIZE=48 -co BLOCKYSIZE=48",
        "-ot Int16 -co COMPRESS=LZW -co PREDICTOR=2 -co TILED=YES -co BLOCKXSIZE=48 -co BLOCKYSIZE=32",
        "-ot Int32 -co COMPRESS=LZW -co PREDICTOR=2 -co TILED=YES -co BLOCKXSIZE=48 -co BLOCKYSIZE=48",
        "-ot Float64 -co COMPRESS=LZW -co TILED=YES -co BLOCKXSIZE=48 -co BLOCKYSIZE=48",
        "-co COMPRESS=LZW -co PREDICTOR=3 -co TILED=YES -co BLOCKXSIZE=48 -co BLOCKYSIZE=48",
        "-ot Float64 -co COMPRESS=LZW -co PREDICTOR=3 -co TILED=YES -co BLOCKXSIZE=64 -co BLOCKYSIZE=48",
        "-co SPARSE_OK=TRUE -co COMPRESS=LZW -co TILED=YES -co BLOCKXSIZE=48 -co BLOCKYSIZE=48",
    ];
    for (k, options) in cases.iter().enumerate() {
        let ext = if options.contains("AAIGrid") {
            "asc"
        } else {
            "tif"
        };
        let tif = dir.path().join(format!("case{k}.{ext}"));
        let mut args = vec!["-q"];
        args.extend(options.split_whitespace());
        args.extend_from_slice(&[s(&src), s(&tif)]);
        gdal("gdal_translate", &args);
        // GDAL's decoding, as 32-bit floats in this machine's byte order.
        let raw = dir.path().join(format!("case{k}.raw"));
        gdal(
            "gdal_translate",
            &["-q", "-of", "ENVI", "-ot", "Float32", s(&tif), s(&raw)],
        );
        let want: Vec<f32> = std::fs::read(&raw)
            .unwrap()
            .chunks_exact(4)
            .map(|b| f32::from_ne_bytes(b.try_into().unwrap()))
            .map(|x| if x == -9999.0 { f32::NAN } else { x })
            .collect();
        let got =
            load_dem(&tif, &LoadOptions::default()).unwrap_or_else(|e| panic!("{options:?}: {e}"));
        assert_eq!(got.heights.len(), want.len(), "{options:?}");
        let differ = got
            .heights
            .iter()
            .zip(&want)
            .filter(|(a, b)| a.to_bits() != b.to_bits() && !(a.is_nan() && b.is_nan()))
            .count();
        assert_eq!(differ, 0, "{options:?}: samples differing from GDAL's");
        assert!(got.heights[..150 * dem.width].iter().all(|h| h.is_nan()));
        // GDAL rewrites the GeoKeys; the grid's place stays.
        let place = |g: &raykit_terrain::GeoRef| {
            (
                g.origin_x,
                g.origin_y,
                g.pixel_width,
                g.pixel_height,
                g.geographic,
            )
        };
        assert_eq!(place(&got.georef), place(&dem.georef), "{options:?}");
    }
    // An LZW tile the file ends inside is an error at that tile's bytes.
    let lzw = dir.path().join("case11.tif");
    let mut bytes = std::fs::read(&lzw).unwrap();
    bytes.truncate(bytes.len() * 3 / 5);
    let cut = dir.path().join("cut.tif");
    std::fs::write(&cut, &bytes).unwrap();
    let text = load_dem(&cut, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        text.contains("cut.tif") && text.contains("byte ") && text.contains("tile "),
        "{text}"
    );
    // A compression the decoder lacks is refused by name, with the way out.
    let lerc = dir.path().join("lerc.tif");
    gdal(
        "gdal_translate",
        &["-q", "-co", "COMPRESS=LERC", s(&src), s(&lerc)],
    );
    let err = load_dem(&lerc, &LoadOptions::default()).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("LERC") && text.contains("tag 259") && text.contains("gdal_translate"),
        "{text}"
    );
}

#[test]
fn gdal_float_max_nodata_marks_the_cells_gdal_fills() {
    let dir = tempfile::tempdir().unwrap();
    // GDAL's -FLT_MAX nodata ("-3.4028229999999999e+038" in the shared
    // lidar DEM's tag): the cells GDAL pads with it hold that text rounded
    // to float32, one step inside -FLT_MAX, and are no data.
    let padded = dir.path().join("padded.tif");
    gdal(
        "gdal_translate",
        &[
            "-q",
            "-srcwin",
            "-10",
            "-10",
            "420",
            "420",
            s(&data("terrain/lidar_dem_400.tif")),
            s(&padded),
        ],
    );
    let raw = dir.path().join("padded.raw");
    gdal(
        "gdal_translate",
        &["-q", "-of", "ENVI", s(&padded), s(&raw)],
    );
    let fill = "-3.4028229999999999e+038".parse::<f64>().unwrap() as f32;
    let want: Vec<f32> = std::fs::read(&raw)
        .unwrap()
        .chunks_exact(4)
        .map(|b| f32::from_ne_bytes(b.try_into().unwrap()))
        .map(|x| if x == fill { f32::NAN } else { x })
        .collect();
    let got = load_dem(&padded, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        want.iter().filter(|x| x.is_nan()).count(),
        420 * 420 - 400 * 400
    );
    assert_eq!(got.heights.len(), want.len());
    assert!(got
        .heights
        .iter()
        .zip(&want)
        .all(|(a, b)| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())));
}

#[test]
fn south_up_and_scaled_rasters_read_as_gdal_warps_and_unscales_them() {
    let dir = tempfile::tempdir().unwrap();
    // A south-up raster (GDAL writes Terragen files so, pixel height +19.5)
    // reads as the north-up raster gdalwarp makes of it: rows reversed,
    // origin at the north edge, every sample where GDAL puts it; and the
    // shadow mask written from it is north-up too.
    let south = dir.path().join("south.tif");
    let north = dir.path().join("north.tif");
    gdal(
        "gdal_translate",
        &[
            "-q",
            "-ot",
            "Float32",
            "-unscale",
            s(&data("terrain/RealisticTerrain_Large.ter")),
            s(&south),
        ],
    );
    gdal("gdalwarp", &["-q", "-r", "near", s(&south), s(&north)]);
    let (a, b) = (
        load_dem(&south, &LoadOptions::default()).unwrap(),
        load_dem(&north, &LoadOptions::default()).unwrap(),
    );
    let place =
        |g: &raykit_terrain::GeoRef| (g.origin_x, g.origin_y, g.pixel_width, g.pixel_height);
    assert_eq!(place(&a.georef), place(&b.georef));
    assert!(a.georef.pixel_height < 0.0);
    assert_eq!((a.width, a.height), (b.width, b.height));
    assert!(a
        .heights
        .iter()
        .zip(&b.heights)
        .all(|(x, y)| x.to_bits() == y.to_bits()));
    // Stored as Terragen's raw integers with GDAL's band scale and offset,
    // the heights are the unscaled ones.
    let south_raw = dir.path().join("south_raw.tif");
    gdal(
        "gdal_translate",
        &[
            "-q",
            s(&data("terrain/RealisticTerrain_Large.ter")),
            s(&south_raw),
        ],
    );
    assert!(gdalinfo(&south_raw)["bands"][0]["scale"].as_f64() != Some(1.0));
    let c = load_dem(&south_raw, &LoadOptions::default()).unwrap();
    assert!(c
        .heights
        .iter()
        .zip(&a.heights)
        .all(|(x, y)| x.to_bits() == y.to_bits()));
    let mask = dir.path().join("south_mask.tif");
    let out = raykit(&[
        "terrain",
        "shadow",
        s(&south),
        "--sun",
        "30,20",
        "--out",
        s(&mask),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let gt = gdalinfo(&mask)["geoTransform"].clone();
    assert_eq!(gt[3].as_f64(), Some(b.georef.origin_y), "{gt}");
    assert_eq!(gt[5].as_f64(), Some(b.georef.pixel_height), "{gt}");
}

#[test]
fn a_projected_system_in_feet_is_named() {
    let dir = tempfile::tempdir().unwrap();
    // A projected system in US survey feet is named, with what follows.
    let feet = dir.path().join("feet.tif");
    gdal(
        "gdal_translate",
        &[
            "-q",
            "-a_srs",
            "EPSG:2263",
            s(&data("terrain/lidar_dem_400.tif")),
            s(&feet),
        ],
    );
    let out = raykit(&[
        "terrain",
        "shadow",
        s(&feet),
        "--sun",
        "100,20",
        "--out",
        s(&dir.path().join("feet_mask.tif")),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let said = text(&out.stderr);
    assert!(
        said.contains("cells 1.00 x 1.00 US survey feet") && said.contains("--md are read in them"),
        "{said}"
    );
}

#[test]
fn cells_outside_gdals_mask_are_no_data_as_gdalwarp_reads_them() {
    // A window of the SRTM tile half sea (height 0), with band 1 as its own
    // mask, so the sea is masked out: GDAL's mask beside the file (.msk,
    // 8-bit), inside it (1-bit, DEFLATE strips; LZW 16² tiles; BigTIFF with
    // ZSTD). gdalwarp honours the mask and writes -9999 there; we must read
    // NaN at exactly those cells and GDAL's heights elsewhere.
    let dir = tempfile::tempdir().unwrap();
    let window = dir.path().join("window.tif");
    gdal(
        "gdal_translate",
        &[
            "-q",
            "-srcwin",
            "600",
            "0",
            "64",
            "48",
            s(&data("terrain/N57E011.hgt")),
            s(&window),
        ],
    );
    let cases: [(&str, &str, &[&str]); 4] = [
        ("sidecar", "NO", &[]),
        ("internal", "YES", &[]),
        (
            "tiled_lzw",
            "YES",
            &[
                "-co",
                "TILED=YES",
                "-co",
                "BLOCKXSIZE=16",
                "-co",
                "BLOCKYSIZE=16",
                "-co",
                "COMPRESS=LZW",
            ],
        ),
        (
            "bigtiff_zstd",
            "YES",
            &["-co", "BIGTIFF=YES", "-co", "COMPRESS=ZSTD"],
        ),
    ];
    for (name, internal, options) in cases {
        let masked = dir.path().join(format!("{name}.tif"));
        let mut args = vec![
            "-q",
            "--config",
            "GDAL_TIFF_INTERNAL_MASK",
            internal,
            "-b",
            "1",
            "-mask",
            "1",
        ];
        args.extend_from_slice(options);
        args.extend([s(&window), s(&masked)]);
        gdal("gdal_translate", &args);
        assert_eq!(
            dir.path().join(format!("{name}.tif.msk")).is_file(),
            internal == "NO",
            "{name}: GDAL put its mask elsewhere than this case tests"
        );
        let warped = dir.path().join(format!("{name}_warped.tif"));
        gdal(
            "gdalwarp",
            &[
                "-q",
                "-ot",
                "Float32",
                "-dstnodata",
                "-9999",
                s(&masked),
                s(&warped),
            ],
        );
        let want: Vec<f32> = gdal_bytes(&warped, dir.path(), &format!("{name}_warped"))
            .chunks_exact(4)
            .map(|b| f32::from_ne_bytes(b.try_into().unwrap()))
            .map(|x| if x == -9999.0 { f32::NAN } else { x })
            .collect();
        let masked_cells = want.iter().filter(|x| x.is_nan()).count();
        assert!(
            (64 * 48 / 4..64 * 48 * 3 / 4).contains(&masked_cells),
            "{name}: GDAL masked {masked_cells} cells; the window should be about half sea"
        );
        let got = load_dem(&masked, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(got.heights.len(), want.len(), "{name}");
        let differing = got
            .heights
            .iter()
            .zip(&want)
            .filter(|(a, b)| a.to_bits() != b.to_bits() && !(a.is_nan() && b.is_nan()))
            .count();
        assert_eq!(differing, 0, "{name}: cells read otherwise than gdalwarp");
    }
}
