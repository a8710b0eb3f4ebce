//! Huge declared counts in tiny files must fail without allocating memory in
//! proportion to the count: pre-allocation is capped by the file size. A
//! counting global allocator measures the peak while each file is parsed.
//! (This binary holds a single test so no other test allocates meanwhile.)

mod common;

use common::assert_located;
use raykit_io::parse_mesh;
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let now = CURRENT.fetch_add(layout.size(), Ordering::SeqCst) + layout.size();
        PEAK.fetch_max(now, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        CURRENT.fetch_sub(layout.size(), Ordering::SeqCst);
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

fn peak_while(f: impl FnOnce()) -> usize {
    let base = CURRENT.load(Ordering::SeqCst);
    PEAK.store(base, Ordering::SeqCst);
    f();
    PEAK.load(Ordering::SeqCst) - base
}

#[test]
fn huge_counts_in_tiny_files_fail_without_big_allocations() {
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
    for (name, bytes) in &cases {
        let mut result = None;
        let peak = peak_while(|| result = Some(parse_mesh(Path::new(name), bytes)));
        let e = match result {
            Some(Err(e)) => e,
            _ => panic!(
                "{name}: expected an error for {:?}",
                String::from_utf8_lossy(bytes)
            ),
        };
        eprintln!("{e} (peak {peak} bytes)");
        assert_located(&e, name);
        assert!(
            peak < 1 << 20,
            "{name}: parsing a {}-byte file allocated {peak} bytes ({e})",
            bytes.len()
        );
    }
}
