//! A first program with raykit's core: a sphere from vertex and index
//! arrays, an 8-wide BVH over it, one batch of rays, and the sphere drawn
//! as text. Run with `cargo run -p raykit-core --example first_rays`.

use raykit_core::prelude::*;
use raykit_core::Icosphere;

fn main() -> Result<(), MeshError> {
    // Any vertex and index arrays will do; here, a subdivided icosahedron.
    let sphere = Icosphere::new(3);
    let positions: Vec<[f32; 3]> = sphere.positions.iter().map(|p| p.to_array()).collect();
    let mesh = TriangleMesh::from_arrays(&positions, &sphere.indices)?;
    let bvh = Bvh8::<Moller>::build(&mesh, &BuildOptions::best());
    let stats = bvh.stats();
    println!(
        "{} triangles; {} nodes, depth {}, SAH cost {:.1}",
        mesh.num_triangles(),
        stats.nodes,
        stats.depth,
        stats.sah_cost
    );

    // Parallel rays through a 48 × 24 grid (a character is twice as tall
    // as wide), looking down -z.
    let (w, h) = (48, 24);
    let rays: Vec<Ray> = (0..w * h)
        .map(|i| {
            let x = 2.4 * ((i % w) as f32 + 0.5) / w as f32 - 1.2;
            let y = 1.2 - 2.4 * ((i / w) as f32 + 0.5) / h as f32;
            Ray::new(Vec3::new(x, y, 5.0), Vec3::new(0.0, 0.0, -1.0))
        })
        .collect();
    let mut hits = vec![None; rays.len()];
    bvh.intersect_batch(&rays, &mut hits);

    // Shade by the hit's depth: nearer is darker.
    for row in hits.chunks(w) {
        let line: String = row
            .iter()
            .map(|hit| match hit {
                None => ' ',
                Some(h) if h.t < 4.3 => '#',
                Some(h) if h.t < 4.7 => '+',
                Some(_) => '.',
            })
            .collect();
        println!("{line}");
    }
    Ok(())
}
