//! Unit icospheres: a regular icosahedron whose faces are split in four
//! `subdivisions` times, the new vertices pushed out onto the sphere.

use glam::Vec3;
use std::collections::HashMap;

/// A closed unit sphere made of `20·4^s` triangles over `10·4^s + 2` shared
/// vertices (`s` subdivisions), counter-clockwise seen from outside. The
/// position of each vertex is also its outward unit normal.
#[derive(Clone, Debug, PartialEq)]
pub struct Icosphere {
    /// Vertex positions on the unit sphere.
    pub positions: Vec<Vec3>,
    /// Triangles, counter-clockwise seen from outside.
    pub indices: Vec<[u32; 3]>,
}

impl Icosphere {
    /// The icosphere with `subdivisions` levels of 4-to-1 splitting.
    pub fn new(subdivisions: u32) -> Self {
        let t = (1.0 + 5f32.sqrt()) / 2.0;
        let mut positions: Vec<Vec3> = [
            (-1.0, t, 0.0),
            (1.0, t, 0.0),
            (-1.0, -t, 0.0),
            (1.0, -t, 0.0),
            (0.0, -1.0, t),
            (0.0, 1.0, t),
            (0.0, -1.0, -t),
            (0.0, 1.0, -t),
            (t, 0.0, -1.0),
            (t, 0.0, 1.0),
            (-t, 0.0, -1.0),
            (-t, 0.0, 1.0),
        ]
        .iter()
        .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
        .collect();
        let mut indices: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..subdivisions {
            let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
            let mut mid = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
                *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let p = (positions[a as usize] + positions[b as usize]).normalize();
                    positions.push(p);
                    (positions.len() - 1) as u32
                })
            };
            let mut next = Vec::with_capacity(indices.len() * 4);
            for [a, b, c] in indices {
                let ab = mid(a, b, &mut positions);
                let bc = mid(b, c, &mut positions);
                let ca = mid(c, a, &mut positions);
                next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            indices = next;
        }
        Icosphere { positions, indices }
    }
}
