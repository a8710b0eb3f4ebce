//! A sub-mesh of chosen triangles: only the vertices they use (with their
//! normals and texture coordinates) and only the parts that still have
//! triangles.

use crate::mesh::{Part, TriangleMesh};

impl TriangleMesh {
    /// The triangles `t` with `keep[t]` set (entries beyond `keep` count as
    /// unset), in their order, with only the vertices they use (first use
    /// first; normals and texture coordinates follow) and only the parts that
    /// still have triangles (renumbered in order; a part index beyond
    /// `parts` becomes an unnamed part). Materials are kept as they are.
    pub fn retain_triangles(&self, keep: &[bool]) -> TriangleMesh {
        const NONE: u32 = u32::MAX;
        let kept = |t: usize| keep.get(t).copied().unwrap_or(false);
        let has_parts = !self.tri_part.is_empty() || !self.parts.is_empty();
        let n_parts = self.parts.len().max(
            (0..self.num_triangles())
                .map(|t| self.part_of(t) as usize + 1)
                .max()
                .unwrap_or(0),
        );
        let mut part_kept = vec![false; n_parts];
        for t in (0..self.num_triangles()).filter(|&t| kept(t)) {
            part_kept[self.part_of(t) as usize] = true;
        }
        let mut new_part = vec![NONE; n_parts];
        let mut parts = Vec::new();
        if has_parts {
            for (p, _) in part_kept.iter().enumerate().filter(|(_, &k)| k) {
                new_part[p] = parts.len() as u32;
                parts.push(self.parts.get(p).cloned().unwrap_or(Part {
                    name: String::new(),
                    node: None,
                }));
            }
        }
        let mut new_vertex = vec![NONE; self.positions.len()];
        let mut used = Vec::new();
        let mut indices = Vec::new();
        let mut tri_material = Vec::new();
        let mut tri_part = Vec::new();
        for t in (0..self.num_triangles()).filter(|&t| kept(t)) {
            indices.push(self.indices[t].map(|v| {
                let slot = &mut new_vertex[v as usize];
                if *slot == NONE {
                    *slot = used.len() as u32;
                    used.push(v as usize);
                }
                *slot
            }));
            if !self.tri_material.is_empty() {
                tri_material.push(self.tri_material[t]);
            }
            if has_parts {
                tri_part.push(new_part[self.part_of(t) as usize]);
            }
        }
        TriangleMesh {
            positions: used.iter().map(|&v| self.positions[v]).collect(),
            indices,
            normals: self
                .normals
                .as_ref()
                .map(|a| used.iter().map(|&v| a[v]).collect()),
            uvs: self
                .uvs
                .as_ref()
                .map(|a| used.iter().map(|&v| a[v]).collect()),
            materials: self.materials.clone(),
            tri_material,
            parts,
            tri_part,
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::mesh::{Part, TriangleMesh};
    use crate::rng::Pcg32;
    use glam::{Vec2, Vec3};

    /// A mesh of `n` triangles over shared vertices, with normals, uvs,
    /// materials and three named parts.
    fn mesh(n: usize) -> TriangleMesh {
        let mut rng = Pcg32::new(7);
        let positions: Vec<Vec3> = (0..n + 2)
            .map(|i| Vec3::new(i as f32, rng.next_f32(), rng.next_f32()))
            .collect();
        let indices = (0..n as u32).map(|t| [t, t + 1, t + 2]).collect();
        TriangleMesh {
            normals: Some(positions.iter().map(|p| p.normalize_or_zero()).collect()),
            uvs: Some(positions.iter().map(|p| Vec2::new(p.y, p.z)).collect()),
            materials: vec![Default::default(); 2],
            tri_material: (0..n as u32).map(|t| t % 2).collect(),
            parts: ["a", "b", "c"]
                .iter()
                .enumerate()
                .map(|(i, s)| Part {
                    name: s.to_string(),
                    node: Some(i as u32),
                })
                .collect(),
            tri_part: (0..n as u32).map(|t| (t / 4).min(2)).collect(),
            positions,
            indices,
        }
    }

    #[test]
    fn kept_triangles_keep_their_corners_materials_and_parts() {
        let m = mesh(12);
        let keep: Vec<bool> = (0..12)
            .map(|t| t % 3 != 0 && !(4..8).contains(&t))
            .collect();
        let sub = m.retain_triangles(&keep);
        // Brute force: the kept triangles' corners, attributes and part
        // names, read from the original mesh, in order.
        let kept: Vec<usize> = (0..12).filter(|&t| keep[t]).collect();
        assert_eq!(sub.num_triangles(), kept.len());
        for (i, &t) in kept.iter().enumerate() {
            assert_eq!(sub.triangle(i), m.triangle(t));
            for k in 0..3 {
                let (a, b) = (sub.indices[i][k] as usize, m.indices[t][k] as usize);
                assert_eq!(
                    sub.normals.as_ref().unwrap()[a],
                    m.normals.as_ref().unwrap()[b]
                );
                assert_eq!(sub.uvs.as_ref().unwrap()[a], m.uvs.as_ref().unwrap()[b]);
            }
            assert_eq!(sub.tri_material[i], m.tri_material[t]);
            let part = &sub.parts[sub.tri_part[i] as usize];
            assert_eq!(part, &m.parts[m.tri_part[t] as usize]);
        }
        // Part "b" (triangles 4..8) is gone; every vertex left is used.
        assert_eq!(
            sub.parts
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>(),
            ["a", "c"]
        );
        let mut used = vec![false; sub.positions.len()];
        sub.indices
            .iter()
            .flatten()
            .for_each(|&v| used[v as usize] = true);
        assert!(used.iter().all(|&u| u));
        assert_eq!(sub.materials, m.materials);
        assert!(sub.validate().is_ok());
    }

    #[test]
    fn keeping_nothing_or_a_short_mask_is_safe() {
        let m = mesh(5);
        assert_eq!(m.retain_triangles(&[]).num_triangles(), 0);
        let sub = m.retain_triangles(&[true, true]);
        assert_eq!(sub.num_triangles(), 2);
        assert_eq!(sub.triangle(1), m.triangle(1));
    }
}
