//! Huge declared counts in tiny files must fail without allocating memory in
//! proportion to the count: pre-allocation is capped by the file size.
//!
//! The cases run in a child process (this same test binary) whose address
//! space is limited with `ulimit -v`, so any attempt to reserve gigabytes
//! fails there and fails the test; the child first checks that the limit is
//! effective by trying to reserve 1 GiB itself.

mod common;

use common::assert_located;
use raykit_io::parse_mesh;
use std::path::Path;
use std::process::Command;

const CHILD_ENV: &str = "RAYKIT_IO_HUGE_COUNTS_CHILD";
const TEST_NAME: &str = "huge_counts_in_tiny_files_fail_without_big_allocations";
/// Address-space limit of the child, KiB.
const LIMIT_KIB: u64 = 768 * 1024;

#[test]
#[cfg(target_os = "linux")]
fn huge_counts_in_tiny_files_fail_without_big_allocations() {
    if std::env::var_os(CHILD_ENV).is_some() {
        run_cases();
        return;
    }
    let exe = std::env::current_exe().unwrap();
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {LIMIT_KIB} && exec \"$0\" --exact {TEST_NAME} --test-threads=1 --nocapture"
        ))
        .arg(&exe)
        .env(CHILD_ENV, "1")
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "child failed:\n{text}");
    assert!(
        text.contains("1 passed"),
        "child did not run the cases:\n{text}"
    );
}

fn run_cases() {
    // The limit must be in force, or this test proves nothing.
    let mut probe: Vec<u8> = Vec::new();
    assert!(
        probe.try_reserve_exact(1 << 30).is_err(),
        "ulimit -v did not limit the address space"
    );
    let ply_header = |fmt: &str, nv: u64, nf: u64| {
        format!(
            "ply\nformat {fmt} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\n\
property float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let mut cases: Vec<(&str, Vec<u8>)> = Vec::new();
    for fmt in ["ascii", "binary_little_endian", "binary_big_endian"] {
        cases.push(("h.ply", ply_header(fmt, 4_000_000_000, 1).into_bytes()));
        cases.push(("h.ply", ply_header(fmt, 3_000_000_000, 10).into_bytes()));
        let mut small = ply_header(fmt, 3, 4_000_000_000).into_bytes();
        if fmt == "ascii" {
            small.extend(b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        } else {
            small.extend([0u8; 36]);
            small.push(3);
            for i in 0i32..3 {
                if fmt == "binary_big_endian" {
                    small.extend(i.to_be_bytes());
                } else {
                    small.extend(i.to_le_bytes());
                }
            }
        }
        cases.push(("h.ply", small));
    }
    cases.push(("h.off", b"OFF\n4000000000 4000000000 0\n0 0 0\n".to_vec()));
    cases.push((
        "h.off",
        b"OFF\n3 4000000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n".to_vec(),
    ));
    cases.push(("h.off", b"OFF\n3000000000 1 0\n0 0 0\n".to_vec()));
    let mut stl = vec![b' '; 80];
    stl.extend(4_000_000_000u32.to_le_bytes());
    stl.extend([0u8; 100]);
    cases.push(("h.stl", stl));
    let gltf = |acc: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"accessors":[{acc}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}}]}}"#
        )
        .into_bytes()
    };
    cases.push((
        "h.gltf",
        gltf(r#"{"bufferView":0,"componentType":5126,"count":1000000000,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}"#),
    ));
    cases.push((
        "h.gltf",
        gltf(r#"{"componentType":5126,"count":1000000000,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}"#),
    ));
    cases.push((
        "h.gltf",
        gltf(
            r#"{"componentType":5126,"count":1000000000,"type":"VEC3","min":[0,0,0],"max":[1,1,0],
"sparse":{"count":1,"indices":{"bufferView":0,"componentType":5125},"values":{"bufferView":0}}}"#,
        ),
    ));
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend(4_000_000_000u32.to_le_bytes());
    glb.extend([0u8; 40]);
    cases.push(("h.glb", glb));
    // A gzip bomb: 1,024 members of 1 MiB of zeros each, 1 GiB in about 1 MB.
    let member = {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        e.write_all(&vec![0u8; 1 << 20]).unwrap();
        e.finish().unwrap()
    };
    cases.push(("h.ply.gz", member.repeat(1024)));
    for (name, bytes) in &cases {
        let e = match parse_mesh(Path::new(name), bytes) {
            Err(e) => e,
            Ok(_) => panic!(
                "{name}: expected an error for {:?}",
                String::from_utf8_lossy(bytes)
            ),
        };
        eprintln!("{e}");
        assert_located(&e, name);
        if name.ends_with(".gz") {
            assert!(
                e.to_string().contains("outgrew the memory available"),
                "{e}"
            );
        }
    }
}
