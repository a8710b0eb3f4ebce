//! DEM file input/output: the shared sample files load with the right
//! georeferencing (checked against independent reads of their bytes), the
//! GeoTIFF writer round-trips, and malformed input gives errors naming the
//! file and the position.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use raykit_terrain::io::{
    load_dem, read_ascii_grid, read_geotiff, read_hgt, read_png, read_raw, read_ter,
    write_dem_geotiff, write_geotiff_f32, write_geotiff_f32_with, write_geotiff_u8, DemError,
    GeoTiffLayout, LoadOptions, RawSpec, RawType, TiffCompression,
};
use raykit_terrain::{Dem, GeoRef};

/// The test data folder: `$RAYKIT_SHARED_DATA`, or
/// `<workspace>/data`. Missing data fails the test.
fn shared_data() -> PathBuf {
    if let Some(p) = std::env::var_os("RAYKIT_SHARED_DATA") {
        let p = PathBuf::from(p);
        assert!(
            p.is_dir(),
            "RAYKIT_SHARED_DATA is set to {}, which is not a directory",
            p.display()
        );
        return p;
    }
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data");
    assert!(
        p.is_dir(),
        "shared test data not found: looked in {} (CARGO_MANIFEST_DIR/../../data); \
         set RAYKIT_SHARED_DATA to its location",
        p.display()
    );
    p
}

fn terrain_file(name: &str) -> PathBuf {
    let p = shared_data().join("terrain").join(name);
    assert!(p.is_file(), "shared terrain file missing: {}", p.display());
    p
}

/// A fresh empty folder for one test, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        let p = std::env::temp_dir().join(format!("raykit-dem-io-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        TempDir(p)
    }

    fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    fn entries(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Asserts the error names the file and a position, and returns its text.
fn assert_names_file_and_position(err: &DemError, path: &Path, at: &str) -> String {
    let text = err.to_string();
    assert!(
        text.starts_with(&format!("{}: at ", path.display())),
        "error does not start with the file name: {text}"
    );
    assert!(
        err.at.contains(at),
        "expected position containing {at:?}, got: {text}"
    );
    assert!(!err.message.is_empty(), "empty message: {text}");
    text
}

/// Heights equal bit for bit (NaN equal to NaN).
fn assert_same_heights(a: &[f32], b: &[f32]) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
            "sample {i}: {x} vs {y}"
        );
    }
}

// ---------------------------------------------------------------------------
// An independent, minimal classic-TIFF IFD parser, for checking the reader.

/// One IFD entry: field type, count and the value bytes (resolved offset).
struct Entry {
    ty: u16,
    count: usize,
    bytes: Vec<u8>,
}

struct Ifd {
    le: bool,
    entries: HashMap<u16, Entry>,
}

impl Ifd {
    fn parse(data: &[u8]) -> Ifd {
        let le = match &data[..2] {
            b"II" => true,
            b"MM" => false,
            other => panic!("not a TIFF: {other:?}"),
        };
        let u16_at = |i: usize| {
            let b = [data[i], data[i + 1]];
            if le {
                u16::from_le_bytes(b)
            } else {
                u16::from_be_bytes(b)
            }
        };
        let u32_at = |i: usize| {
            let b = [data[i], data[i + 1], data[i + 2], data[i + 3]];
            if le {
                u32::from_le_bytes(b)
            } else {
                u32::from_be_bytes(b)
            }
        };
        assert_eq!(u16_at(2), 42, "classic TIFF expected");
        let ifd = u32_at(4) as usize;
        let n = u16_at(ifd) as usize;
        let mut entries = HashMap::new();
        for k in 0..n {
            let e = ifd + 2 + 12 * k;
            let (tag, ty, count) = (u16_at(e), u16_at(e + 2), u32_at(e + 4) as usize);
            let size = match ty {
                1 | 2 | 6 | 7 => 1,
                3 | 8 => 2,
                4 | 9 | 11 => 4,
                5 | 10 | 12 => 8,
                _ => panic!("unexpected field type {ty}"),
            } * count;
            let start = if size <= 4 {
                e + 8
            } else {
                u32_at(e + 8) as usize
            };
            let bytes = data[start..start + size].to_vec();
            entries.insert(tag, Entry { ty, count, bytes });
        }
        Ifd { le, entries }
    }

    fn uints(&self, tag: u16) -> Option<Vec<u64>> {
        let e = self.entries.get(&tag)?;
        let le = self.le;
        Some(match e.ty {
            3 => e
                .bytes
                .chunks_exact(2)
                .map(|b| {
                    (if le {
                        u16::from_le_bytes([b[0], b[1]])
                    } else {
                        u16::from_be_bytes([b[0], b[1]])
                    }) as u64
                })
                .collect(),
            4 => e
                .bytes
                .chunks_exact(4)
                .map(|b| {
                    let b = [b[0], b[1], b[2], b[3]];
                    (if le {
                        u32::from_le_bytes(b)
                    } else {
                        u32::from_be_bytes(b)
                    }) as u64
                })
                .collect(),
            t => panic!("tag {tag}: type {t} is not an unsigned integer"),
        })
    }

    fn doubles(&self, tag: u16) -> Option<Vec<f64>> {
        let e = self.entries.get(&tag)?;
        assert_eq!(e.ty, 12, "tag {tag} should be DOUBLE");
        assert_eq!(e.bytes.len(), 8 * e.count);
        Some(
            e.bytes
                .chunks_exact(8)
                .map(|b| {
                    let b: [u8; 8] = b.try_into().unwrap();
                    if self.le {
                        f64::from_le_bytes(b)
                    } else {
                        f64::from_be_bytes(b)
                    }
                })
                .collect(),
        )
    }

    fn ascii(&self, tag: u16) -> Option<String> {
        let e = self.entries.get(&tag)?;
        assert_eq!(e.ty, 2, "tag {tag} should be ASCII");
        let end = e
            .bytes
            .iter()
            .position(|&b| b == 0)
            .unwrap_or(e.bytes.len());
        Some(String::from_utf8(e.bytes[..end].to_vec()).unwrap())
    }
}

/// Value of an inline key in a raw GeoKeyDirectory.
fn key(keys: &[u64], id: u64) -> Option<u64> {
    keys[4..]
        .chunks_exact(4)
        .find(|e| e[0] == id && e[1] == 0)
        .map(|e| e[3])
}

// ---------------------------------------------------------------------------
// GeoTIFF

#[test]
fn lidar_geotiff_georef_matches_its_tags() {
    let path = terrain_file("lidar_dem_400.tif");
    let dem = read_geotiff(&path).unwrap();
    println!(
        "lidar_dem_400.tif: {}×{}, origin ({}, {}), pixel ({}, {}), geographic {}, nodata {:?}, \
         range {:?}, {} geokey values, geo_doubles {:?}, geo_ascii {:?}",
        dem.width,
        dem.height,
        dem.georef.origin_x,
        dem.georef.origin_y,
        dem.georef.pixel_width,
        dem.georef.pixel_height,
        dem.georef.geographic,
        dem.nodata,
        dem.range(),
        dem.georef.geo_keys.len(),
        dem.georef.geo_doubles,
        dem.georef.geo_ascii
    );

    let bytes = std::fs::read(&path).unwrap();
    let ifd = Ifd::parse(&bytes);
    let w = ifd.uints(256).unwrap()[0] as usize;
    let h = ifd.uints(257).unwrap()[0] as usize;
    assert_eq!((dem.width, dem.height), (w, h));

    let scale = ifd.doubles(33550).expect("file has ModelPixelScale");
    let tie = ifd.doubles(33922).expect("file has ModelTiepoint");
    let keys = ifd.uints(34735).expect("file has a GeoKeyDirectory");
    // PixelIsArea (or absent): the tiepoint is the pixel corner.
    let raster_type = key(&keys, 1025).unwrap_or(1);
    let half = if raster_type == 2 { 0.5 } else { 0.0 };
    let g = &dem.georef;
    assert_eq!(g.pixel_width, scale[0]);
    assert_eq!(g.pixel_height, -scale[1]);
    assert_eq!(g.origin_x, tie[3] - (tie[0] + half) * scale[0]);
    assert_eq!(g.origin_y, tie[4] + (tie[1] + half) * scale[1]);
    assert_eq!(g.geographic, key(&keys, 1024) == Some(2));
    assert_eq!(
        g.geo_keys.iter().map(|&k| k as u64).collect::<Vec<_>>(),
        keys
    );
    assert_eq!(g.geo_doubles, ifd.doubles(34736).unwrap_or_default());
    assert_eq!(g.geo_ascii, ifd.ascii(34737).unwrap_or_default());
    let nodata = ifd.ascii(42113).map(|s| s.trim().parse::<f64>().unwrap());
    assert_eq!(dem.nodata, nodata);

    // Samples: this file is uncompressed float32 in tiles; read a few by hand.
    assert_eq!(
        ifd.uints(259).unwrap()[0],
        1,
        "independent check expects no compression"
    );
    assert_eq!(ifd.uints(258).unwrap()[0], 32);
    assert_eq!(ifd.uints(339).unwrap()[0], 3);
    let tw = ifd.uints(322).expect("tiled")[0] as usize;
    let th = ifd.uints(323).unwrap()[0] as usize;
    let offsets = ifd.uints(324).unwrap();
    let across = w.div_ceil(tw);
    let sample = |col: usize, row: usize| {
        let tile = (row / th) * across + col / tw;
        let at = offsets[tile] as usize + 4 * ((row % th) * tw + col % tw);
        f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap())
    };
    let mut nan = 0;
    for (col, row) in [
        (0, 0),
        (w - 1, 0),
        (0, h - 1),
        (w - 1, h - 1),
        (127, 128),
        (200, 391),
        (399, 130),
    ] {
        let v = sample(col, row);
        let expected = if nodata.map(|n| n as f32) == Some(v) {
            f32::NAN
        } else {
            v
        };
        assert!(
            dem.at(col, row).to_bits() == expected.to_bits(),
            "({col}, {row}): read {} vs bytes {v}",
            dem.at(col, row)
        );
        nan += v.is_nan() as usize;
    }
    assert_eq!(nan, 0);
    let (lo, hi) = dem.range().unwrap();
    assert!(
        lo > 0.0 && hi < 10_000.0,
        "range {lo}..{hi} looks wrong for metres"
    );
}

#[test]
fn geotiff_round_trip_f32_keeps_data_and_georef() {
    let dir = TempDir::new("rt-f32");
    let dem = read_geotiff(terrain_file("lidar_dem_400.tif")).unwrap();
    let out = dir.join("copy.tif");
    write_dem_geotiff(&out, &dem).unwrap();
    assert_eq!(
        dir.entries(),
        vec!["copy.tif"],
        "no temporary file left behind"
    );
    let back = read_geotiff(&out).unwrap();
    assert_eq!((back.width, back.height), (dem.width, dem.height));
    assert_same_heights(&back.heights, &dem.heights);
    assert_eq!(back.georef, dem.georef);
    assert_eq!(back.nodata, dem.nodata);

    // NaN samples are written as the nodata value and read back as NaN.
    let mut holes = dem.clone();
    holes.heights[5] = f32::NAN;
    holes.heights[400 * 399 + 7] = f32::NAN;
    holes.nodata = Some(-9999.0);
    write_dem_geotiff(&out, &holes).unwrap();
    let back = read_geotiff(&out).unwrap();
    assert_same_heights(&back.heights, &holes.heights);
    assert_eq!(back.nodata, Some(-9999.0));
    let ifd = Ifd::parse(&std::fs::read(&out).unwrap());
    assert_eq!(ifd.ascii(42113).as_deref(), Some("-9999"));
}

/// Uncompressed float strips (gdalwarp's default layout) are read straight
/// into place, strip by strip in parallel: the same heights as the `tiff`
/// crate's decoding of the tiled, compressed source, no-data included, with
/// a last strip shorter than the others.
#[test]
fn geotiff_plain_float_strips_read_as_decoded() {
    let dir = TempDir::new("plain-strips");
    let src = read_geotiff(terrain_file("lidar_dem_400.tif")).unwrap();
    // The tile's rows five times over, less three: strips of about a
    // megabyte, the last one short.
    let rows = 5 * 400 - 3;
    let mut heights: Vec<f32> = src
        .heights
        .iter()
        .copied()
        .cycle()
        .take(400 * rows)
        .collect();
    heights[3] = f32::NAN;
    heights[400 * (rows - 1) + 11] = f32::NAN;
    let layout = GeoTiffLayout {
        compression: TiffCompression::None,
        tile: None,
    };
    let out = dir.join("plain.tif");
    write_geotiff_f32_with(
        &out,
        400,
        rows,
        &heights,
        &src.georef,
        Some(-9999.0),
        &layout,
    )
    .unwrap();
    let ifd = Ifd::parse(&std::fs::read(&out).unwrap());
    assert_eq!(ifd.uints(259), Some(vec![1]), "uncompressed");
    let (strips, per_strip) = (ifd.uints(273).unwrap(), ifd.uints(278).unwrap());
    assert!(strips.len() > 2, "{} strips", strips.len());
    assert!(
        rows % per_strip[0] as usize != 0,
        "the last strip should be short"
    );
    let back = read_geotiff(&out).unwrap();
    assert_eq!((back.width, back.height), (400, rows));
    assert_same_heights(&back.heights, &heights);
    assert_eq!(back.georef, src.georef);
}

/// Rewrites a classic little-endian TIFF's block tables (StripOffsets and
/// StripByteCounts, or TileOffsets and TileByteCounts, LONG values) so that
/// the blocks `absent(k)` names are stored as no bytes: offset and byte
/// count 0, as GDAL writes an all-nodata block with `SPARSE_OK=TRUE`.
/// Returns how many blocks it left out.
fn leave_out_blocks(data: &mut [u8], absent: impl Fn(usize) -> bool) -> usize {
    let ifd = Ifd::parse(data);
    assert!(ifd.le);
    let (offsets_tag, counts_tag) = if ifd.entries.contains_key(&324) {
        (324u16, 325u16)
    } else {
        (273, 279)
    };
    let u32_at = |d: &[u8], i: usize| u32::from_le_bytes(d[i..i + 4].try_into().unwrap());
    let at = u32_at(data, 4) as usize;
    let n = u16::from_le_bytes([data[at], data[at + 1]]) as usize;
    let mut left_out = 0;
    for k in 0..n {
        let e = at + 2 + 12 * k;
        let tag = u16::from_le_bytes([data[e], data[e + 1]]);
        if tag != offsets_tag && tag != counts_tag {
            continue;
        }
        assert_eq!(u16::from_le_bytes([data[e + 2], data[e + 3]]), 4, "LONG");
        let count = u32_at(data, e + 4) as usize;
        let values = if count == 1 {
            e + 8
        } else {
            u32_at(data, e + 8) as usize
        };
        for b in (0..count).filter(|&b| absent(b)) {
            data[values + 4 * b..values + 4 * b + 4].fill(0);
            left_out += usize::from(tag == offsets_tag);
        }
    }
    left_out
}

/// A striped float TIFF of `heights` by the `tiff` crate's encoder, eight
/// rows a strip, with GDAL's nodata tag when `nodata` is given.
fn write_strips_f32(
    path: &Path,
    (w, h): (usize, usize),
    heights: &[f32],
    nodata: Option<f64>,
    compression: tiff::encoder::Compression,
) {
    use tiff::encoder::{colortype::Gray32Float, TiffEncoder};
    let file = std::fs::File::create(path).unwrap();
    let mut enc = TiffEncoder::new(std::io::BufWriter::new(file))
        .unwrap()
        .with_compression(compression);
    let mut img = enc.new_image::<Gray32Float>(w as u32, h as u32).unwrap();
    img.rows_per_strip(8).unwrap();
    if let Some(nd) = nodata {
        let tag = tiff::tags::Tag::from_u16_exhaustive(42113);
        img.encoder()
            .write_tag(tag, format!("{nd}").as_str())
            .unwrap();
    }
    img.write_data(heights).unwrap();
}

/// GDAL's sparse files (`SPARSE_OK=TRUE`) store a strip or tile whose
/// samples are all nodata (all zero without a nodata value) as no bytes,
/// and read it back as such. Before, uncompressed strips read the file's
/// header as heights and compressed ones were refused as corrupt. For
/// strips (uncompressed, read straight into place; PackBits and Deflate,
/// decoded) and tiles (each compression of the writer), with and without
/// a nodata value, the file with its blank blocks left out reads as the
/// same file with them written.
#[test]
fn geotiff_blocks_stored_as_no_bytes_read_as_nodata_or_zero() {
    use tiff::encoder::{compression::DeflateLevel, Compression};
    let dir = TempDir::new("sparse");
    let src = read_geotiff(terrain_file("lidar_dem_400.tif")).unwrap();
    let (w, h) = (src.width, src.height);
    // Rows above `blank` are blank, and so are the blocks wholly above it.
    let blank = 150;
    let strips = [
        ("NONE", Compression::Uncompressed),
        ("PACKBITS", Compression::Packbits),
        ("DEFLATE", Compression::Deflate(DeflateLevel::Fast)),
    ];
    let layouts = strips
        .into_iter()
        .map(Err)
        .chain(TiffCompression::ALL.into_iter().map(|compression| {
            Ok(GeoTiffLayout {
                compression,
                tile: Some((64, 32)),
            })
        }));
    for layout in layouts {
        for nodata in [Some(-9999.0), None] {
            let mut heights = src.heights.clone();
            // Without a nodata value the blank rows are zero, and the
            // file's no-data samples are given a height.
            let fill = if nodata.is_some() { -9999.0 } else { 0.0 };
            heights
                .iter_mut()
                .filter(|x| x.is_nan())
                .for_each(|x| *x = fill);
            heights[..blank * w].fill(fill);
            let what = match &layout {
                Err((name, _)) => format!("{name}, strips of 8 rows, nodata {nodata:?}"),
                Ok(l) => format!("{}, nodata {nodata:?}", l.describe()),
            };
            let out = dir.join("dense.tif");
            match &layout {
                Err((_, c)) => write_strips_f32(&out, (w, h), &heights, nodata, *c),
                Ok(l) => {
                    write_geotiff_f32_with(&out, w, h, &heights, &src.georef, nodata, l).unwrap()
                }
            }
            let dense = read_geotiff(&out).unwrap();
            let mut bytes = std::fs::read(&out).unwrap();
            let ifd = Ifd::parse(&bytes);
            let absent = |k: usize| match &layout {
                Err(_) => (k + 1) * ifd.uints(278).unwrap()[0] as usize <= blank,
                Ok(l) => {
                    let (tw, th) = l.tile.unwrap();
                    (k / w.div_ceil(tw as usize) + 1) * th as usize <= blank
                }
            };
            let left_out = leave_out_blocks(&mut bytes, absent);
            assert!(left_out >= 4, "{what}: {left_out} blocks left out");
            let sparse = dir.join("sparse.tif");
            std::fs::write(&sparse, &bytes).unwrap();
            let back = read_geotiff(&sparse).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_same_heights(&back.heights, &dense.heights);
            assert_eq!(back.nodata, dense.nodata, "{what}");
            let blank_height = if nodata.is_some() { f32::NAN } else { 0.0 };
            assert_same_heights(&back.heights[..blank * w], &vec![blank_height; blank * w]);
        }
    }
}

/// Esri ASCII grids: the `…center` keywords, GDAL's `dx`/`dy`, no-data,
/// rows wrapped over several lines, upper-case keywords and CRLF line
/// ends read to the heights and corner written here; a `.prj` with a
/// geographic WKT marks degrees; malformed files are errors naming the
/// line.
#[test]
fn esri_ascii_grids_read_with_their_corner_and_errors_name_the_line() {
    let dir = TempDir::new("ascii-grid");
    let (w, h) = (7usize, 5usize);
    let want: Vec<f32> = (0..w * h)
        .map(|i| {
            if i == 9 {
                f32::NAN
            } else {
                100.0 + i as f32 * 0.25 - (i % 3) as f32
            }
        })
        .collect();
    let token = |x: f32| {
        if x.is_nan() {
            "-9999".to_string()
        } else {
            format!("{x}")
        }
    };
    // One row per line (read in parallel), with the lower-left centre.
    let rows: Vec<String> = want
        .chunks(w)
        .map(|r| r.iter().map(|&x| token(x)).collect::<Vec<_>>().join(" "))
        .collect();
    let text = format!(
        "ncols {w}\nnrows {h}\nxllcenter 1000.5\nyllcenter 2000.5\ncellsize 1\nNODATA_value -9999\n{}\n",
        rows.join("\n")
    );
    let a = dir.join("centre.asc");
    std::fs::write(&a, &text).unwrap();
    let dem = read_ascii_grid(&a).unwrap();
    assert_eq!((dem.width, dem.height), (w, h));
    assert_same_heights(&dem.heights, &want);
    let g = &dem.georef;
    assert_eq!((g.origin_x, g.origin_y), (1000.0, 2000.0 + h as f64));
    assert_eq!(
        (g.pixel_width, g.pixel_height, g.geographic),
        (1.0, -1.0, false)
    );
    assert_eq!(dem.nodata, Some(-9999.0));
    // Wrapped rows, dx/dy, upper-case keys, CRLF, a geographic .prj.
    let tokens: Vec<String> = want.iter().map(|&x| token(x)).collect();
    let wrapped: Vec<String> = tokens.chunks(4).map(|c| c.join("\t")).collect();
    let text = format!(
        "NCOLS {w}\r\nNROWS {h}\r\nXLLCORNER -10\r\nYLLCORNER 50\r\nDX 0.25\r\nDY 0.125\r\n\
         NODATA_VALUE -9999\r\n{}\r\n",
        wrapped.join("\r\n")
    );
    let b = dir.join("wrapped.asc");
    std::fs::write(&b, &text).unwrap();
    std::fs::write(
        dir.join("wrapped.prj"),
        "GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\"]]",
    )
    .unwrap();
    let dem = load_dem(&b, &LoadOptions::default()).unwrap();
    assert_same_heights(&dem.heights, &want);
    let g = &dem.georef;
    assert_eq!((g.origin_x, g.origin_y), (-10.0, 50.0 + h as f64 * 0.125));
    assert_eq!(
        (g.pixel_width, g.pixel_height, g.geographic),
        (0.25, -0.125, true)
    );
    // NaN written as GDAL writes it in float grids without a nodata value,
    // first on the first row too: a sample, not a header keyword.
    let mut with_nan = want.clone();
    with_nan[0] = f32::NAN;
    let nan_rows: Vec<String> = with_nan
        .chunks(w)
        .map(|r| {
            r.iter()
                .map(|&x| {
                    if x.is_nan() {
                        "nan".to_string()
                    } else {
                        format!("{x}")
                    }
                })
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect();
    let c = dir.join("nan.asc");
    std::fs::write(
        &c,
        format!(
            "ncols {w}\nnrows {h}\nxllcorner 0\nyllcorner 0\ncellsize 1\n{}\n",
            nan_rows.join("\n")
        ),
    )
    .unwrap();
    let dem = read_ascii_grid(&c).unwrap_or_else(|e| panic!("{e}"));
    assert_same_heights(&dem.heights, &with_nan);
    // Malformed: each error names the line (or the header) and the problem.
    let header = format!("ncols {w}\nnrows {h}\nxllcorner 0\nyllcorner 0\ncellsize 2\n");
    let body = rows.join("\n").replace("-9999", "0");
    let bad = [
        (
            format!("nrows {h}\nxllcorner 0\nyllcorner 0\ncellsize 2\n{body}"),
            "header",
            "no ncols",
        ),
        (
            format!("{header}{}", body.replacen("100", "1x0", 1)),
            "line 6",
            "not a number",
        ),
        (
            format!("{header}{}", &body[..body.rfind(' ').unwrap()]),
            "line 10",
            "ends after 34 values",
        ),
        (format!("{header}{body} 5"), "line 10", "beyond"),
        (
            format!("{header}cellsize 3\n{body}"),
            "line 6",
            "given twice",
        ),
        (
            format!("ncols 0\nnrows {h}\nxllcorner 0\nyllcorner 0\ncellsize 2\n{body}"),
            "line 1",
            "at least 1",
        ),
        (
            format!("{}{body}", header.replace("cellsize 2", "cellsize -2")),
            "header",
            "positive",
        ),
        (
            format!("{}{body}", header.replace("xllcorner", "xllcentre")),
            "line 3",
            "unknown header keyword",
        ),
    ];
    for (k, (text, at, needle)) in bad.iter().enumerate() {
        let p = dir.join(&format!("bad{k}.asc"));
        std::fs::write(&p, text).unwrap();
        let e = read_ascii_grid(&p).unwrap_err();
        assert_eq!(e.path, p);
        assert_eq!(&e.at, at, "case {k}: {e}");
        assert!(e.message.contains(needle), "case {k}: {e}");
    }
}

#[test]
fn geotiff_round_trip_u8_and_geographic() {
    let dir = TempDir::new("rt-u8");
    let (w, h) = (37, 23);
    let data: Vec<u8> = (0..w * h).map(|i| (i * 7 % 256) as u8).collect();
    let georef = GeoRef {
        origin_x: 11.5,
        origin_y: 58.25,
        pixel_width: 1.0 / 1200.0,
        pixel_height: -1.0 / 1200.0,
        geographic: true,
        geo_keys: vec![1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326],
        geo_doubles: vec![0.5, 6378137.0],
        geo_ascii: "WGS 84|".to_string(),
        crs_wkt: None,
    };
    let out = dir.join("bytes.tif");
    write_geotiff_u8(&out, w, h, &data, &georef, Some(255.0)).unwrap();
    let back = read_geotiff(&out).unwrap();
    assert_eq!(back.georef, georef);
    assert_eq!(back.nodata, Some(255.0));
    for (i, (&d, &b)) in data.iter().zip(&back.heights).enumerate() {
        if d == 255 {
            assert!(b.is_nan(), "sample {i}");
        } else {
            assert_eq!(b, d as f32, "sample {i}");
        }
    }

    // An SRTM tile written as GeoTIFF keeps its geographic georef.
    let hgt = read_hgt(terrain_file("N57E011.hgt")).unwrap();
    let out = dir.join("srtm.tif");
    write_dem_geotiff(&out, &hgt).unwrap();
    let back = read_geotiff(&out).unwrap();
    assert_eq!(back.georef, hgt.georef);
    assert_eq!(back.nodata, hgt.nodata);
    assert_same_heights(&back.heights, &hgt.heights);

    // Empty geokeys become a minimal directory; the rest round-trips.
    let plain = Dem::from_heights(3, 2, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    let out = dir.join("plain.tif");
    write_dem_geotiff(&out, &plain).unwrap();
    let back = read_geotiff(&out).unwrap();
    assert_eq!(back.heights, plain.heights);
    assert_eq!(
        back.georef.geo_keys,
        vec![1, 1, 0, 2, 1024, 0, 1, 1, 1025, 0, 1, 1]
    );
    assert_eq!(
        GeoRef {
            geo_keys: vec![],
            ..back.georef
        },
        plain.georef
    );
}

/// A coordinate system known only as WKT (an ASCII grid's `.prj`) goes
/// into the GeoTIFF's `.aux.xml` and comes back with the raster, geographic
/// or projected, through a second write; a raster whose GeoKeys declare a
/// coordinate system ignores a sidecar, and writing it removes the stale
/// one.
#[test]
fn a_coordinate_system_in_the_sidecar_round_trips() {
    let dir = TempDir::new("crs-sidecar");
    let projected = r#"PROJCS["NAD_1983_UTM_Zone_15N",GEOGCS["GCS_North_American_1983",DATUM["D_North_American_1983",SPHEROID["GRS_1980",6378137.0,298.257222101]]],PROJECTION["Transverse_Mercator"],UNIT["Meter",1.0]]"#;
    let geographic = r#"GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,298.257223563]],UNIT["Degree",0.0174532925199433]]"#;
    for (k, wkt) in [projected, geographic].into_iter().enumerate() {
        let mut dem = Dem::from_heights(3, 2, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        dem.georef.crs_wkt = Some(wkt.to_string());
        dem.georef.geographic = k == 1;
        let first = dir.join(&format!("first{k}.tif"));
        write_dem_geotiff(&first, &dem).unwrap();
        let back = read_geotiff(&first).unwrap();
        assert_eq!(back.georef.crs_wkt.as_deref(), Some(wkt), "case {k}");
        assert_eq!(back.georef.geographic, k == 1, "case {k}");
        // Written again from what was read: the GeoKeys are now the
        // minimal directory, which still declares no coordinate system.
        let second = dir.join(&format!("second{k}.tif"));
        write_dem_geotiff(&second, &back).unwrap();
        let again = read_geotiff(&second).unwrap();
        assert_eq!(again.georef, back.georef, "case {k}");
    }

    // A GeoTIFF with no GeoKeys at all, as other writers make it, takes
    // its sidecar's coordinate system, and is geographic by its WKT.
    // A 2×2 raster placed by pixel scale and tie point, with `keys` added.
    let placed = |path: &Path, keys: Vec<(u16, TagValue)>| {
        let mut tags = vec![
            (33550, TagValue::Doubles(vec![0.5, 0.5, 0.0])),
            (
                33922,
                TagValue::Doubles(vec![0.0, 0.0, 0.0, 10.0, 50.0, 0.0]),
            ),
        ];
        tags.extend(keys);
        write_custom_tiff(path, &[1, 2, 3, 4], 2, 2, &tags);
    };
    let bare = dir.join("bare.tif");
    placed(&bare, Vec::new());
    assert!(!read_geotiff(&bare).unwrap().georef.geographic);
    raykit_terrain::io::write_crs_sidecar(&bare, geographic).unwrap();
    let back = read_geotiff(&bare).unwrap();
    assert!(back.georef.geo_keys.is_empty());
    assert_eq!(back.georef.crs_wkt.as_deref(), Some(geographic));
    assert!(back.georef.geographic);
    // A citation alone (GTCitationGeoKey, PCSCitationGeoKey) declares no
    // coordinate system either.
    let cited = dir.join("cited.tif");
    placed(
        &cited,
        vec![
            (
                34735,
                TagValue::Shorts(vec![1, 1, 0, 2, 1024, 0, 1, 1, 3073, 34737, 12, 0]),
            ),
            (34737, TagValue::Ascii("raykit test|".to_string())),
        ],
    );
    raykit_terrain::io::write_crs_sidecar(&cited, projected).unwrap();
    let back = read_geotiff(&cited).unwrap();
    assert_eq!(back.georef.crs_wkt.as_deref(), Some(projected));
    assert!(!back.georef.geographic);

    // GeoKeys that declare a coordinate system (EPSG:4326) win over a
    // sidecar, and a write removes the sidecar left at its path.
    let mut dem = Dem::from_heights(2, 2, vec![1.0, 2.0, 3.0, 4.0]);
    dem.georef.geographic = true;
    dem.georef.geo_keys = vec![1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326];
    let out = dir.join("declared.tif");
    write_dem_geotiff(&out, &dem).unwrap();
    raykit_terrain::io::write_crs_sidecar(&out, projected).unwrap();
    assert_eq!(read_geotiff(&out).unwrap().georef.crs_wkt, None);
    write_dem_geotiff(&out, &dem).unwrap();
    assert!(!raykit_terrain::io::crs_sidecar_path(&out).exists());
}

/// Writes a small GeoTIFF with the `tiff` encoder directly, with whatever
/// georeferencing tags the test wants.
fn write_custom_tiff(path: &Path, data: &[i16], w: u32, h: u32, tags: &[(u16, TagValue)]) {
    use tiff::encoder::{colortype::GrayI16, TiffEncoder};
    let file = std::fs::File::create(path).unwrap();
    let mut enc = TiffEncoder::new(std::io::BufWriter::new(file)).unwrap();
    let mut img = enc.new_image::<GrayI16>(w, h).unwrap();
    for (tag, v) in tags {
        let t = tiff::tags::Tag::from_u16_exhaustive(*tag);
        match v {
            TagValue::Doubles(d) => img.encoder().write_tag(t, &d[..]).unwrap(),
            TagValue::Shorts(s) => img.encoder().write_tag(t, &s[..]).unwrap(),
            TagValue::Ascii(s) => img.encoder().write_tag(t, s.as_str()).unwrap(),
        }
    }
    img.write_data(data).unwrap();
}

enum TagValue {
    Doubles(Vec<f64>),
    Shorts(Vec<u16>),
    Ascii(String),
}

#[test]
fn geotiff_pixel_is_point_transformation_and_int_nodata() {
    let dir = TempDir::new("custom");
    let data: Vec<i16> = vec![-9999, 10, 20, 30, 40, -9999];
    // PixelIsPoint: the tiepoint (1000, 2000) is the centre of pixel (0, 0).
    let point = dir.join("point.tif");
    write_custom_tiff(
        &point,
        &data,
        3,
        2,
        &[
            (33550, TagValue::Doubles(vec![10.0, 5.0, 0.0])),
            (
                33922,
                TagValue::Doubles(vec![0.0, 0.0, 0.0, 1000.0, 2000.0, 0.0]),
            ),
            (
                34735,
                TagValue::Shorts(vec![1, 1, 0, 2, 1024, 0, 1, 1, 1025, 0, 1, 2]),
            ),
            (42113, TagValue::Ascii("-9999".into())),
        ],
    );
    let dem = read_geotiff(&point).unwrap();
    assert_eq!((dem.georef.origin_x, dem.georef.origin_y), (995.0, 2002.5));
    assert_eq!(
        (dem.georef.pixel_width, dem.georef.pixel_height),
        (10.0, -5.0)
    );
    assert!(!dem.georef.geographic);
    assert!(dem.heights[0].is_nan() && dem.heights[5].is_nan());
    assert_eq!(&dem.heights[1..5], &[10.0, 20.0, 30.0, 40.0]);
    // Written back as PixelIsArea with the corner origin: same georef
    // except the raster type key.
    let out = dir.join("point-out.tif");
    write_dem_geotiff(&out, &dem).unwrap();
    let back = read_geotiff(&out).unwrap();
    assert_eq!(
        back.georef.geo_keys,
        vec![1, 1, 0, 2, 1024, 0, 1, 1, 1025, 0, 1, 1]
    );
    assert_eq!(
        (back.georef.origin_x, back.georef.origin_y),
        (995.0, 2002.5)
    );
    assert_same_heights(&back.heights, &dem.heights);

    // ModelTransformation instead of scale + tiepoint, tiepoint at a
    // non-zero raster position.
    let tr = dir.join("transform.tif");
    #[rustfmt::skip]
    let m = vec![
        2.0, 0.0, 0.0, 500.0,
        0.0, -3.0, 0.0, 900.0,
        0.0, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    ];
    write_custom_tiff(&tr, &data, 3, 2, &[(34264, TagValue::Doubles(m))]);
    let dem = read_geotiff(&tr).unwrap();
    let g = &dem.georef;
    assert_eq!(
        (g.origin_x, g.origin_y, g.pixel_width, g.pixel_height),
        (500.0, 900.0, 2.0, -3.0)
    );
    assert_eq!(dem.nodata, None);
    assert_eq!(dem.heights[0], -9999.0);

    let tp = dir.join("tiepoint.tif");
    write_custom_tiff(
        &tp,
        &data,
        3,
        2,
        &[
            (33550, TagValue::Doubles(vec![10.0, 10.0, 0.0])),
            (
                33922,
                TagValue::Doubles(vec![2.0, 1.0, 0.0, 1000.0, 2000.0, 0.0]),
            ),
        ],
    );
    let g = read_geotiff(&tp).unwrap().georef;
    assert_eq!((g.origin_x, g.origin_y), (980.0, 2010.0));

    // Rotation is refused, naming the tag.
    let rot = dir.join("rotated.tif");
    #[rustfmt::skip]
    let m = vec![
        2.0, 0.5, 0.0, 500.0,
        0.0, -3.0, 0.0, 900.0,
        0.0, 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    ];
    write_custom_tiff(&rot, &data, 3, 2, &[(34264, TagValue::Doubles(m))]);
    let err = read_geotiff(&rot).unwrap_err();
    assert_names_file_and_position(&err, &rot, "tag 34264");
}

/// A tiled GeoTIFF whose TileWidth is not a multiple of 16 (TIFF 6.0) is
/// refused at the tag, not decoded into a wrong picture.
#[test]
fn geotiff_tiles_of_a_side_not_a_multiple_of_16_are_refused() {
    let dir = TempDir::new("tiles");
    let mut data = std::fs::read(terrain_file("lidar_dem_400.tif")).unwrap();
    assert!(Ifd::parse(&data).le, "fixture layout changed");
    let ifd = u32::from_le_bytes(data[4..8].try_into().unwrap()) as usize;
    let n = u16::from_le_bytes(data[ifd..ifd + 2].try_into().unwrap()) as usize;
    let entry = (0..n)
        .map(|k| ifd + 2 + 12 * k)
        .find(|&e| u16::from_le_bytes(data[e..e + 2].try_into().unwrap()) == 322)
        .expect("a tiled fixture");
    let ty = u16::from_le_bytes(data[entry + 2..entry + 4].try_into().unwrap());
    let value = entry + 8;
    if ty == 3 {
        data[value..value + 2].copy_from_slice(&100u16.to_le_bytes());
    } else {
        data[value..value + 4].copy_from_slice(&100u32.to_le_bytes());
    }
    let path = dir.join("odd_tiles.tif");
    std::fs::write(&path, &data).unwrap();
    let err = read_geotiff(&path).unwrap_err();
    let text = assert_names_file_and_position(&err, &path, "tag 322");
    assert!(text.contains("multiple of 16"), "{text}");
}

#[test]
fn geotiff_unsupported_samples_and_garbage_are_errors() {
    use tiff::encoder::{colortype, TiffEncoder};
    let dir = TempDir::new("bad-tiff");

    let rgb = dir.join("rgb.tif");
    {
        let f = std::fs::File::create(&rgb).unwrap();
        let mut enc = TiffEncoder::new(f).unwrap();
        enc.write_image::<colortype::RGB8>(2, 2, &[0u8; 12])
            .unwrap();
    }
    let err = read_geotiff(&rgb).unwrap_err();
    let text = assert_names_file_and_position(&err, &rgb, "tag 277");
    assert!(text.contains("single band"), "{text}");

    let u64s = dir.join("u64.tif");
    {
        let f = std::fs::File::create(&u64s).unwrap();
        let mut enc = TiffEncoder::new(f).unwrap();
        enc.write_image::<colortype::Gray64>(2, 2, &[0u64; 4])
            .unwrap();
    }
    let err = read_geotiff(&u64s).unwrap_err();
    let text = assert_names_file_and_position(&err, &u64s, "tag 339");
    assert!(text.contains("64-bit unsigned"), "{text}");

    let garbage = dir.join("garbage.tif");
    std::fs::write(&garbage, b"this is not a tiff file at all, just text").unwrap();
    let err = read_geotiff(&garbage).unwrap_err();
    let text = assert_names_file_and_position(&err, &garbage, "byte 0");
    assert!(text.contains("\"II\" or \"MM\""), "{text}");

    let empty = dir.join("empty.tif");
    std::fs::write(&empty, b"").unwrap();
    let err = read_geotiff(&empty).unwrap_err();
    assert_names_file_and_position(&err, &empty, "byte 0");

    // A TIFF header pointing to an IFD past the end.
    let bad_ifd = dir.join("bad-ifd.tif");
    std::fs::write(&bad_ifd, b"II*\0\xff\xff\x00\x00garbage").unwrap();
    let err = read_geotiff(&bad_ifd).unwrap_err();
    assert_names_file_and_position(&err, &bad_ifd, "byte 65535");

    // The real file cut short: the header and IFD survive, the tiles do not.
    let bytes = std::fs::read(terrain_file("lidar_dem_400.tif")).unwrap();
    let cut = dir.join("cut.tif");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let err = read_geotiff(&cut).unwrap_err();
    assert_names_file_and_position(&err, &cut, "image data");

    // Random bytes after a valid header never panic.
    let mut state = 0x1234_5678_u64;
    for i in 0..200 {
        let mut b = bytes[..2048].to_vec();
        for _ in 0..8 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let at = 8 + (state >> 33) as usize % (b.len() - 8);
            b[at] = (state >> 20) as u8;
        }
        let p = dir.join("fuzz.tif");
        std::fs::write(&p, &b).unwrap();
        if let Err(e) = read_geotiff(&p) {
            assert!(
                e.to_string().starts_with(&p.display().to_string()),
                "case {i}: {e}"
            );
        }
    }
}

#[test]
fn geotiff_writer_refuses_bad_arguments() {
    let dir = TempDir::new("bad-write");
    let g = Dem::from_heights(1, 1, vec![0.0]).georef;
    let out = dir.join("x.tif");
    let err = write_geotiff_f32(&out, 3, 3, &[0.0; 8], &g, None).unwrap_err();
    assert_names_file_and_position(&err, &out, "arguments");
    let err = write_geotiff_u8(&out, 1, 1, &[0], &g, Some(-9999.0)).unwrap_err();
    assert_names_file_and_position(&err, &out, "tag 42113");
    let err = write_geotiff_f32(&out, 1, 1, &[0.0], &GeoRef::default(), None).unwrap_err();
    assert_names_file_and_position(&err, &out, "tag 33550");
    assert!(
        dir.entries().is_empty(),
        "nothing written: {:?}",
        dir.entries()
    );
}

// ---------------------------------------------------------------------------
// SRTM .hgt

#[test]
fn srtm_hgt_loads_with_georef_from_its_name() {
    let path = terrain_file("N57E011.hgt");
    let dem = read_hgt(&path).unwrap();
    let g = &dem.georef;
    println!(
        "N57E011.hgt: {}×{}, origin ({}, {}), pixel ({}, {}), geographic {}, range {:?}",
        dem.width,
        dem.height,
        g.origin_x,
        g.origin_y,
        g.pixel_width,
        g.pixel_height,
        g.geographic,
        dem.range()
    );
    let bytes = std::fs::read(&path).unwrap();
    let n = 1201;
    assert_eq!(bytes.len(), 2 * n * n);
    assert_eq!((dem.width, dem.height), (n, n));
    let raw = |col: usize, row: usize| {
        let i = 2 * (row * n + col);
        i16::from_be_bytes([bytes[i], bytes[i + 1]])
    };
    for (col, row) in [
        (0, 0),
        (n - 1, 0),
        (0, n - 1),
        (n - 1, n - 1),
        (600, 600),
        (17, 1003),
    ] {
        let v = raw(col, row);
        assert_ne!(v, -32768);
        assert_eq!(dem.at(col, row), v as f32, "({col}, {row})");
    }
    let (lo, hi) = (0..n * n)
        .map(|i| raw(i % n, i / n))
        .filter(|&v| v != -32768)
        .fold((i16::MAX, i16::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    assert_eq!(dem.range(), Some((lo as f32, hi as f32)));
    // SW corner 57 N 11 E, samples on whole degrees at the edges.
    let px = 1.0 / 1200.0;
    assert!(g.geographic);
    assert_eq!((g.pixel_width, g.pixel_height), (px, -px));
    assert!(
        (g.origin_x - (11.0 - px / 2.0)).abs() < 1e-12,
        "{}",
        g.origin_x
    );
    assert!(
        (g.origin_y - (58.0 + px / 2.0)).abs() < 1e-12,
        "{}",
        g.origin_y
    );
    assert_eq!(dem.nodata, Some(-32768.0));
}

#[test]
fn srtm_hgt_names_voids_and_bad_files() {
    let dir = TempDir::new("hgt");
    // Southern/western tile of 3×3 with a void.
    let samples: [i16; 9] = [1, 2, 3, 4, -32768, 6, 7, 8, -9];
    let bytes: Vec<u8> = samples.iter().flat_map(|s| s.to_be_bytes()).collect();
    let p = dir.join("s09W080.hgt");
    std::fs::write(&p, &bytes).unwrap();
    let dem = read_hgt(&p).unwrap();
    assert_eq!((dem.width, dem.height), (3, 3));
    assert!(dem.heights[4].is_nan());
    assert_eq!(dem.at(2, 2), -9.0);
    assert_eq!(dem.georef.origin_x, -80.25);
    assert_eq!(dem.georef.origin_y, -8.0 + 0.25);

    // Truncated tile.
    let real = std::fs::read(terrain_file("N57E011.hgt")).unwrap();
    let cut = dir.join("N57E011.hgt");
    std::fs::write(&cut, &real[..real.len() - 2]).unwrap();
    let err = read_hgt(&cut).unwrap_err();
    let text = assert_names_file_and_position(&err, &cut, &format!("byte {}", real.len() - 2));
    assert!(text.contains("2884802"), "{text}");

    // Odd size.
    std::fs::write(&cut, &real[..1001]).unwrap();
    assert_names_file_and_position(&read_hgt(&cut).unwrap_err(), &cut, "byte 1001");

    // Name that does not locate a tile.
    let bad = dir.join("tile57.hgt");
    std::fs::write(&bad, &bytes).unwrap();
    let err = read_hgt(&bad).unwrap_err();
    let text = assert_names_file_and_position(&err, &bad, "file name");
    assert!(text.contains("N57E011"), "{text}");
}

// ---------------------------------------------------------------------------
// Terragen .ter

/// Finds a 4-byte chunk marker after the 16-byte magic (test's own scan).
fn chunk(bytes: &[u8], id: &[u8; 4]) -> Option<usize> {
    bytes[16..].windows(4).position(|w| w == id).map(|p| p + 16)
}

#[test]
fn terragen_loads_flipped_with_scaled_heights() {
    let path = terrain_file("RealisticTerrain_Large.ter");
    let dem = read_ter(&path).unwrap();
    let g = &dem.georef;
    println!(
        "RealisticTerrain_Large.ter: {}×{}, origin ({}, {}), pixel ({}, {}), range {:?}",
        dem.width,
        dem.height,
        g.origin_x,
        g.origin_y,
        g.pixel_width,
        g.pixel_height,
        dem.range()
    );
    let b = std::fs::read(&path).unwrap();
    let le16 = |i: usize| i16::from_le_bytes([b[i], b[i + 1]]);
    let lef32 = |i: usize| f32::from_le_bytes(b[i..i + 4].try_into().unwrap());
    let size = le16(chunk(&b, b"SIZE").unwrap() + 4) as usize + 1;
    let x = chunk(&b, b"XPTS").map_or(size, |i| le16(i + 4) as usize);
    let y = chunk(&b, b"YPTS").map_or(size, |i| le16(i + 4) as usize);
    let scal =
        chunk(&b, b"SCAL").map_or([30.0; 3], |i| [lef32(i + 4), lef32(i + 8), lef32(i + 12)]);
    let altw = chunk(&b, b"ALTW").unwrap();
    let (hs, base) = (le16(altw + 4) as f64, le16(altw + 6) as f64);
    let data = altw + 8;
    assert_eq!((dem.width, dem.height), (x, y));
    assert_eq!((x, y), (513, 513));
    let metres = |col: usize, file_row: usize| {
        let e = le16(data + 2 * (file_row * x + col)) as f64;
        ((base + e * hs / 65536.0) * scal[2] as f64) as f32
    };
    for (col, file_row) in [
        (0, 0),
        (x - 1, 0),
        (0, y - 1),
        (x - 1, y - 1),
        (100, 300),
        (256, 7),
    ] {
        assert_eq!(
            dem.at(col, y - 1 - file_row),
            metres(col, file_row),
            "({col}, {file_row})"
        );
    }
    assert_eq!(
        (g.pixel_width, g.pixel_height),
        (scal[0] as f64, -(scal[1] as f64))
    );
    assert_eq!((g.origin_x, g.origin_y), (0.0, y as f64 * scal[1] as f64));
    assert!(!g.geographic);
    assert!(dem.heights.iter().all(|h| h.is_finite()));
}

/// A small valid .ter file: SIZE 2 (3×3), SCAL 10, ALTW, data, EOF.
fn small_ter() -> Vec<u8> {
    let mut b = b"TERRAGENTERRAIN ".to_vec();
    b.extend(b"SIZE");
    b.extend(2u16.to_le_bytes());
    b.extend([0, 0]);
    b.extend(b"SCAL");
    for _ in 0..3 {
        b.extend(10f32.to_le_bytes());
    }
    b.extend(b"ALTW");
    b.extend(i16::MIN.to_le_bytes()); // HeightScale -32768: × -0.5
    b.extend(100i16.to_le_bytes());
    for e in [0i16, 2, 4, 6, 8, 10, 12, 14, 16] {
        b.extend(e.to_le_bytes());
    }
    b.extend(b"EOF ");
    b
}

#[test]
fn terragen_small_and_malformed() {
    let dir = TempDir::new("ter");
    let p = dir.join("small.ter");
    std::fs::write(&p, small_ter()).unwrap();
    let dem = read_ter(&p).unwrap();
    assert_eq!((dem.width, dem.height), (3, 3));
    // Top row is the last file row: elevations 12, 14, 16 → (100 − e/2) × 10.
    assert_eq!(&dem.heights[..3], &[940.0, 930.0, 920.0]);
    assert_eq!(&dem.heights[6..], &[1000.0, 990.0, 980.0]);

    let mut bad = small_ter();
    bad[3] = b'X';
    std::fs::write(&p, &bad).unwrap();
    let text = assert_names_file_and_position(&read_ter(&p).unwrap_err(), &p, "byte 0");
    assert!(text.contains("TERRAGENTERRAIN"), "{text}");

    // Header chunks and then EOF, no ALTW.
    let good = small_ter();
    let altw = chunk(&good, b"ALTW").unwrap();
    let mut no_altw = good[..altw].to_vec();
    no_altw.extend(b"EOF ");
    std::fs::write(&p, &no_altw).unwrap();
    let text =
        assert_names_file_and_position(&read_ter(&p).unwrap_err(), &p, &format!("byte {altw}"));
    assert!(text.contains("ALTW"), "{text}");
    // ... or the file simply ends.
    std::fs::write(&p, &good[..altw]).unwrap();
    let text =
        assert_names_file_and_position(&read_ter(&p).unwrap_err(), &p, &format!("byte {altw}"));
    assert!(text.contains("chunk marker"), "{text}");

    // Unknown chunk.
    let mut unknown = good.clone();
    unknown[altw..altw + 4].copy_from_slice(b"QQQQ");
    std::fs::write(&p, &unknown).unwrap();
    let text =
        assert_names_file_and_position(&read_ter(&p).unwrap_err(), &p, &format!("byte {altw}"));
    assert!(text.contains("unknown chunk"), "{text}");

    // Truncated elevations.
    std::fs::write(&p, &good[..altw + 8 + 10]).unwrap();
    let text = assert_names_file_and_position(
        &read_ter(&p).unwrap_err(),
        &p,
        &format!("byte {}", altw + 18),
    );
    assert!(text.contains("18 bytes"), "{text}");

    // The real file truncated.
    let real = std::fs::read(terrain_file("RealisticTerrain_Large.ter")).unwrap();
    std::fs::write(&p, &real[..real.len() / 3]).unwrap();
    assert_names_file_and_position(&read_ter(&p).unwrap_err(), &p, "byte");
}

// ---------------------------------------------------------------------------
// PNG, raw, load_dem

#[test]
fn png_16_and_8_bit_heights() {
    let dir = TempDir::new("png");
    let (w, h) = (5u32, 4u32);
    let img =
        image::ImageBuffer::from_fn(w, h, |x, y| image::Luma([(x * 1000 + y * 13000) as u16]));
    let p16 = dir.join("h16.png");
    img.save(&p16).unwrap();
    let dem = read_png(&p16, 0.1, -100.0).unwrap();
    assert_eq!((dem.width, dem.height), (5, 4));
    for y in 0..h {
        for x in 0..w {
            let s = (x * 1000 + y * 13000) as f64;
            assert_eq!(dem.at(x as usize, y as usize), (s * 0.1 - 100.0) as f32);
        }
    }
    let img8 = image::ImageBuffer::from_fn(3, 2, |x, y| image::Luma([(x * 50 + y * 100) as u8]));
    let p8 = dir.join("h8.png");
    img8.save(&p8).unwrap();
    let dem = load_dem(
        &p8,
        &LoadOptions {
            png_scale: 2.0,
            ..LoadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(dem.heights, vec![0.0, 100.0, 200.0, 200.0, 300.0, 400.0]);

    let rgb = image::ImageBuffer::from_fn(2, 2, |_, _| image::Rgb([1u8, 2, 3]));
    let prgb = dir.join("rgb.png");
    rgb.save(&prgb).unwrap();
    let text = assert_names_file_and_position(
        &read_png(&prgb, 1.0, 0.0).unwrap_err(),
        &prgb,
        "PNG header",
    );
    assert!(text.contains("grayscale"), "{text}");

    let junk = dir.join("junk.png");
    std::fs::write(&junk, b"\x89PNG\r\n\x1a\nnot really").unwrap();
    assert_names_file_and_position(&read_png(&junk, 1.0, 0.0).unwrap_err(), &junk, "PNG");
}

#[test]
fn raw_all_types_and_wrong_size() {
    let dir = TempDir::new("raw");
    let values = [0.0f32, 1.0, 2.0, 250.0, 100.0, 7.0];
    type Encode = fn(f32) -> Vec<u8>;
    let cases: [(RawType, Encode); 7] = [
        (RawType::U8, |v| vec![v as u8]),
        (RawType::I16Le, |v| (-(v as i16)).to_le_bytes().to_vec()),
        (RawType::I16Be, |v| (-(v as i16)).to_be_bytes().to_vec()),
        (RawType::U16Le, |v| (v as u16 * 200).to_le_bytes().to_vec()),
        (RawType::U16Be, |v| (v as u16 * 200).to_be_bytes().to_vec()),
        (RawType::F32Le, |v| (v * 0.25).to_le_bytes().to_vec()),
        (RawType::F32Be, |v| (v * 0.25).to_be_bytes().to_vec()),
    ];
    for (ty, enc) in cases {
        let p = dir.join(&format!("g.{}", ty.name()));
        let bytes: Vec<u8> = values.iter().flat_map(|&v| enc(v)).collect();
        std::fs::write(&p, &bytes).unwrap();
        let dem = read_raw(&p, 3, 2, ty).unwrap();
        let expected: Vec<f32> = values
            .iter()
            .map(|&v| match ty {
                RawType::U8 => v,
                RawType::I16Le | RawType::I16Be => -v,
                RawType::U16Le | RawType::U16Be => v * 200.0,
                RawType::F32Le | RawType::F32Be => v * 0.25,
            })
            .collect();
        assert_eq!(dem.heights, expected, "{ty:?}");
        assert_eq!(RawType::parse(&ty.name().to_uppercase()), Some(ty));

        let err = read_raw(&p, 4, 2, ty).unwrap_err();
        let text = assert_names_file_and_position(&err, &p, "byte");
        let need = 8 * ty.bytes();
        assert!(text.contains(&format!("{} bytes", bytes.len())), "{text}");
        assert!(text.contains(&format!("{need} bytes")), "{text}");
    }
    let p = dir.join("huge.raw");
    std::fs::write(&p, [0u8; 4]).unwrap();
    let err = read_raw(&p, 70_000, 2, RawType::U8).unwrap_err();
    assert!(err.to_string().contains("65536"), "{err}");
    let err = read_raw(&p, 65_536, 65_536, RawType::U8).unwrap_err();
    assert!(err.to_string().contains("2147483648"), "{err}");
}

#[test]
fn load_dem_dispatches_on_extension() {
    let dir = TempDir::new("load");
    let o = LoadOptions::default();
    assert_eq!(
        load_dem(terrain_file("lidar_dem_400.tif"), &o)
            .unwrap()
            .width,
        400
    );
    assert_eq!(
        load_dem(terrain_file("N57E011.hgt"), &o).unwrap().width,
        1201
    );
    assert_eq!(
        load_dem(terrain_file("RealisticTerrain_Large.ter"), &o)
            .unwrap()
            .width,
        513
    );

    let r16 = dir.join("square.R16");
    let bytes: Vec<u8> = (0u16..16).flat_map(|v| (v * 100).to_le_bytes()).collect();
    std::fs::write(&r16, &bytes).unwrap();
    let dem = load_dem(&r16, &o).unwrap();
    assert_eq!((dem.width, dem.height, dem.at(3, 3)), (4, 4, 1500.0));

    let raw = dir.join("grid.raw");
    std::fs::write(&raw, &bytes).unwrap();
    let err = load_dem(&raw, &o).unwrap_err();
    assert!(
        err.to_string().contains(".r16") && err.to_string().contains("LoadOptions::raw"),
        "{err}"
    );
    let spec = RawSpec {
        width: 8,
        height: 2,
        sample: RawType::U16Le,
    };
    let dem = load_dem(
        &raw,
        &LoadOptions {
            raw: Some(spec),
            ..o.clone()
        },
    )
    .unwrap();
    assert_eq!((dem.width, dem.height, dem.at(7, 1)), (8, 2, 1500.0));

    let odd = dir.join("odd.r32");
    std::fs::write(&odd, [0u8; 12]).unwrap();
    assert_names_file_and_position(&load_dem(&odd, &o).unwrap_err(), &odd, "byte 12");

    // An infinite height is refused at its cell; NaN is no data.
    for (at, bad) in [
        (6usize, f32::INFINITY),
        (13, f32::NEG_INFINITY),
        (7, 3e38),
        (9, -3e38),
    ] {
        let mut heights: Vec<f32> = (0..16).map(|v| v as f32).collect();
        heights[2] = f32::NAN;
        heights[at] = bad;
        let path = dir.join("inf.r32");
        std::fs::write(
            &path,
            heights
                .iter()
                .flat_map(|h| h.to_le_bytes())
                .collect::<Vec<u8>>(),
        )
        .unwrap();
        let err = load_dem(&path, &o).unwrap_err();
        let place = format!("row {}, column {}", at / 4, at % 4);
        let text = assert_names_file_and_position(&err, &path, &place);
        let why = if bad.is_infinite() {
            "not finite"
        } else {
            "beyond"
        };
        assert!(text.contains(why), "{text}");
    }

    let unknown = dir.join("terrain.xyz");
    std::fs::write(&unknown, b"1 2 3").unwrap();
    let err = load_dem(&unknown, &o).unwrap_err();
    let text = assert_names_file_and_position(&err, &unknown, "file name");
    for ext in [".tif", ".hgt", ".ter", ".png", ".raw", ".r16", ".r32"] {
        assert!(text.contains(ext), "{text}");
    }
    let missing = dir.join("missing.tif");
    assert_names_file_and_position(&load_dem(&missing, &o).unwrap_err(), &missing, "open");
}
