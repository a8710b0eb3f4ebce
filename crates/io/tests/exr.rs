//! The OpenEXR writers, read back through the `exr` crate's own reader.

use exr::prelude::{read_first_flat_layer_from_file, FlatSamples};
use raykit_io::{write_exr_channels, write_exr_rgb};
use std::path::Path;

/// Named f32 channels as read back.
type Channels = Vec<(String, Vec<f32>)>;
/// Width, height and the channels passed to the writer.
type Case<'a> = (u32, u32, Vec<(&'a str, &'a [f32])>);

/// Channel name → f32 samples of the first layer, and the layer size.
fn read_channels(path: &Path) -> ((usize, usize), Channels) {
    let image = read_first_flat_layer_from_file(path).unwrap();
    let layer = image.layer_data;
    let channels = layer
        .channel_data
        .list
        .iter()
        .map(|c| match &c.sample_data {
            FlatSamples::F32(v) => (c.name.to_string(), v.clone()),
            other => panic!("channel {} is not f32: {other:?}", c.name),
        })
        .collect();
    ((layer.size.0, layer.size.1), channels)
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Deterministic test values covering signs, magnitudes and specials.
fn values(n: usize, seed: u32) -> Vec<f32> {
    let specials = [
        0.0,
        -0.0,
        f32::INFINITY,
        f32::NAN,
        f32::MIN_POSITIVE,
        1e-40,
        -3.3e38,
    ];
    (0..n)
        .map(|i| {
            let k = (i as u32).wrapping_mul(2654435761).wrapping_add(seed);
            if k.is_multiple_of(17) {
                specials[(k / 17) as usize % specials.len()]
            } else {
                f32::from_bits(k % 0x7f00_0000) * if k & 1 == 0 { 1.0 } else { -1.0 }
            }
        })
        .collect()
}

#[test]
fn rgb_round_trips_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("render.exr");
    let (w, h) = (33u32, 17u32);
    let v = values((w * h * 3) as usize, 1);
    let rgb: Vec<[f32; 3]> = v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    write_exr_rgb(&path, w, h, &rgb).unwrap();
    let (size, channels) = read_channels(&path);
    assert_eq!(size, (w as usize, h as usize));
    let names: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["B", "G", "R"]);
    for (name, samples) in &channels {
        let k = ["R", "G", "B"].iter().position(|n| n == name).unwrap();
        let want: Vec<f32> = rgb.iter().map(|p| p[k]).collect();
        assert_eq!(bits(samples), bits(&want), "channel {name}");
    }
    // The convenience reader sees the same top row first.
    let first = exr::prelude::read_first_rgba_layer_from_file(
        &path,
        |_, _| Vec::new(),
        |px: &mut Vec<(usize, usize, f32)>, pos, (r, _g, _b, _a): (f32, f32, f32, f32)| {
            px.push((pos.0, pos.1, r))
        },
    )
    .unwrap();
    for (x, y, r) in first.layer_data.channel_data.pixels {
        assert_eq!(r.to_bits(), rgb[y * w as usize + x][0].to_bits());
    }
}

#[test]
fn arbitrary_channels_round_trip_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("aovs.exr");
    let (w, h) = (100u32, 7u32);
    let n = (w * h) as usize;
    let depth = values(n, 2);
    let nx = values(n, 3);
    let id: Vec<f32> = (0..n).map(|i| (i % 13) as f32).collect();
    let input: [(&str, &[f32]); 3] = [("Z", &depth), ("N.X", &nx), ("id", &id)];
    write_exr_channels(&path, w, h, &input).unwrap();
    let (size, channels) = read_channels(&path);
    assert_eq!(size, (w as usize, h as usize));
    assert_eq!(channels.len(), 3);
    for (name, samples) in &input {
        let got = &channels.iter().find(|(n, _)| n == name).unwrap().1;
        assert_eq!(bits(got), bits(samples), "channel {name}");
    }
    // A single channel of a single pixel.
    write_exr_channels(&path, 1, 1, &[("Y", &[0.25])]).unwrap();
    let (size, channels) = read_channels(&path);
    assert_eq!(
        (size, channels),
        ((1, 1), vec![("Y".to_string(), vec![0.25])])
    );
}

#[test]
fn bad_arguments_are_errors_naming_the_file_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.exr");
    let four = [0.0f32; 4];
    let cases: Vec<Case> = vec![
        (0, 0, vec![("Z", &[])]),
        (2, 2, vec![]),
        (2, 2, vec![("Z", &four[..3])]),
        (2, 2, vec![("Z", &four), ("Z", &four)]),
        (2, 2, vec![("", &four)]),
        (2, 2, vec![("tiefe€", &four)]),
        (2, 2, vec![("a\nb", &four)]),
    ];
    for (w, h, channels) in cases {
        let e = write_exr_channels(&path, w, h, &channels).unwrap_err();
        assert!(e.to_string().contains("bad.exr"), "{e}");
        assert!(!path.exists());
    }
    let e = write_exr_rgb(&path, 3, 3, &[[0.0; 3]; 8]).unwrap_err();
    assert!(e.to_string().contains("bad.exr"), "{e}");
    let missing = dir.path().join("no/such/dir/out.exr");
    let e = write_exr_rgb(&missing, 1, 1, &[[1.0; 3]]).unwrap_err();
    assert!(e.to_string().contains("out.exr"), "{e}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn an_existing_file_is_replaced_whole() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.exr");
    std::fs::write(&path, b"old").unwrap();
    write_exr_rgb(&path, 2, 1, &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]).unwrap();
    let (size, channels) = read_channels(&path);
    assert_eq!(size, (2, 1));
    assert_eq!(channels[2], ("R".to_string(), vec![1.0, 4.0]));
    let e = write_exr_rgb(&path, 2, 2, &[[0.0; 3]; 3]).unwrap_err();
    assert!(e.to_string().contains("out.exr"));
    assert_eq!(read_channels(&path).0, (2, 1));
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["out.exr"]);
}
