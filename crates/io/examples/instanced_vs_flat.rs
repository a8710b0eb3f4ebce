//! A glTF file traced as an instanced scene (its instancing kept: one
//! geometry per mesh, one instance per node, two-level BVH) and flattened
//! (one mesh, one `Bvh8`): memory, build time and nearest-hit rates on the
//! standard primary and incoherent ray sets (the sets of `raykit rays`,
//! 1024² each), every ray's answer compared between the two. Set
//! `RAYON_NUM_THREADS` for the thread count.
//!
//! `cargo run --release -p raykit-io --example instanced_vs_flat -- data/meshes/2CylinderEngine.glb`

use raykit_core::accel::{Accel, BuildOptions, Bvh8};
use raykit_core::instancing::{SceneBuilder, MASK_ALL};
use raykit_core::raysets::{incoherent, primary, standard_camera};
use raykit_core::tri::Moller;
use raykit_core::{Ray, Vec3};
use std::time::Instant;

/// Median of `runs` timings of `f`, in seconds.
fn median(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[runs / 2]
}

fn main() {
    let path = std::env::args().nth(1).expect("a glTF file");
    let path = std::path::Path::new(&path);
    let inst = raykit_io::load_gltf_instances(path).unwrap_or_else(|e| panic!("{e}"));
    let flat = raykit_io::load_mesh(path).unwrap_or_else(|e| panic!("{e}"));
    let opts = BuildOptions::default();
    let threads = rayon::current_num_threads();

    let s = Instant::now();
    let mut b = SceneBuilder::new();
    inst.add_to(&mut b).unwrap_or_else(|e| panic!("{e}"));
    let scene = b.build(&opts);
    let build_i = s.elapsed().as_secs_f64();
    let s = Instant::now();
    let bvh = Bvh8::<Moller>::build(&flat, &opts);
    let build_f = s.elapsed().as_secs_f64();

    let st = scene.stats();
    let flat_bytes = bvh.stats().bytes
        + flat.positions.len() * std::mem::size_of::<Vec3>()
        + flat.indices.len() * 12;
    println!("file: {}  threads: {threads}", path.display());
    println!(
        "instanced: {} geometries, {} instances, {} triangles stored, {:.2} MB, build {:.1} ms",
        st.geometries,
        st.instances,
        st.stored_triangles,
        st.bytes as f64 / 1e6,
        build_i * 1e3
    );
    println!(
        "flattened: {} triangles, {:.2} MB, build {:.1} ms",
        flat.num_triangles(),
        flat_bytes as f64 / 1e6,
        build_f * 1e3
    );

    let bounds = flat.bounds();
    let sets: [(&str, Vec<Ray>); 2] = [
        ("primary", primary(&standard_camera(&flat), 1024)),
        ("incoherent", incoherent(&bounds, 1024 * 1024, 7)),
    ];
    println!("| rays | instanced Mrays/s | flattened Mrays/s | flattened single-ray Mrays/s | instanced/flattened | answers differing |");
    for (name, rays) in &sets {
        let n = rays.len();
        let mut hi = vec![None; n];
        let mut hf = vec![None; n];
        let ti = median(5, || scene.intersect_batch(rays, MASK_ALL, &mut hi));
        let tf = median(5, || bvh.intersect_batch(rays, &mut hf));
        // The flattened tree's single-ray path (no packets), the one the
        // instanced scene uses per instance.
        let ts = median(5, || {
            use rayon::prelude::*;
            rays.par_iter()
                .zip(hf.par_iter_mut())
                .with_min_len(256)
                .for_each(|(r, h)| *h = bvh.intersect(r));
        });
        let differ = hi
            .iter()
            .zip(&hf)
            .filter(|(a, b)| match (a, b) {
                (None, None) => false,
                (Some(a), Some(b)) => (a.t - b.t).abs() > 1e-4 * b.t,
                _ => true,
            })
            .count();
        let m = |t: f64| n as f64 / t / 1e6;
        println!(
            "| {name} | {:.2} | {:.2} | {:.2} | {:.2} | {differ} of {n} |",
            m(ti),
            m(tf),
            m(ts),
            tf / ti
        );
    }
}
