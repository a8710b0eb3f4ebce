//! The ground truth's labels as a JSON file (`raykit cull --save-truth`,
//! read back by `--truth`): the visible triangles' ids and the figures of
//! the run that found them, so that a slow evaluation is done once.

use crate::evaluate::GroundTruth;
use raykit_core::TriangleMesh;
use serde::{Deserialize, Serialize};

/// The saved labels and figures of a [`GroundTruth`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SavedTruth {
    /// The input mesh the truth was found on, as named on the command line.
    pub input: String,
    /// Triangles of that mesh.
    pub triangles: usize,
    /// Rounds run.
    pub rounds: usize,
    /// True when the last rounds changed nothing.
    pub converged: bool,
    /// Triangles newly found visible by the last round.
    pub last_change: usize,
    /// Rays cast.
    pub rays: u64,
    /// Seconds the evaluation took.
    pub seconds: f64,
    /// Narrowest opening seen through, as a fraction of the diagonal.
    pub min_opening: f32,
    /// Ids of the visible triangles, ascending.
    pub visible_ids: Vec<usize>,
    /// [`mesh_digest`] of the mesh, so that labels are not read for another
    /// mesh with as many triangles (absent in files saved before it was
    /// kept: those are checked by their triangle count only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_digest: Option<String>,
}

/// A digest of `mesh`'s triangles: 64-bit FNV-1a (Fowler, Noll and Vo) over
/// the bits of each triangle's corners in order, as 16 hex digits. Two
/// meshes with the same triangles at the same positions share it; a moved
/// corner, another order or another winding changes it.
pub fn mesh_digest(mesh: &TriangleMesh) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for t in 0..mesh.num_triangles() {
        for corner in mesh.triangle(t) {
            for c in corner.to_array() {
                for b in c.to_bits().to_le_bytes() {
                    h ^= b as u64;
                    h = h.wrapping_mul(0x0000_0100_0000_01b3);
                }
            }
        }
    }
    format!("{h:016x}")
}

/// Why saved labels do not fit the mesh they are read for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SavedTruthMismatch {
    /// The file was saved for another mesh with as many triangles.
    Mesh {
        /// The digest in the file.
        saved: String,
        /// The mesh's digest.
        mesh: String,
    },
    /// The file was saved for a mesh with another number of triangles.
    Triangles {
        /// Triangles in the file.
        saved: usize,
        /// Triangles of the mesh.
        mesh: usize,
    },
    /// `visible_ids[index]` names a triangle beyond the mesh.
    IdBeyond {
        /// Position in `visible_ids`.
        index: usize,
        /// The id found there.
        id: usize,
        /// Triangles of the mesh.
        mesh: usize,
    },
}

impl SavedTruth {
    /// The labels of `truth`, found on `mesh` (read from `input`) with
    /// `min_opening`.
    pub fn new(
        input: &str,
        mesh: &TriangleMesh,
        truth: &GroundTruth,
        min_opening: f32,
    ) -> SavedTruth {
        SavedTruth {
            mesh_digest: Some(mesh_digest(mesh)),
            input: input.to_string(),
            triangles: truth.visible.len(),
            rounds: truth.rounds,
            converged: truth.converged,
            last_change: truth.last_change,
            rays: truth.rays,
            seconds: truth.seconds,
            min_opening,
            visible_ids: (0..truth.visible.len())
                .filter(|&t| truth.visible[t])
                .collect(),
        }
    }

    /// The ground truth for `mesh`, or why the labels do not fit it.
    pub fn to_truth(&self, mesh: &TriangleMesh) -> Result<GroundTruth, SavedTruthMismatch> {
        let triangles = mesh.num_triangles();
        if self.triangles != triangles {
            return Err(SavedTruthMismatch::Triangles {
                saved: self.triangles,
                mesh: triangles,
            });
        }
        if let Some(saved) = &self.mesh_digest {
            let digest = mesh_digest(mesh);
            if *saved != digest {
                return Err(SavedTruthMismatch::Mesh {
                    saved: saved.clone(),
                    mesh: digest,
                });
            }
        }
        let mut visible = vec![false; triangles];
        for (index, &id) in self.visible_ids.iter().enumerate() {
            match visible.get_mut(id) {
                Some(v) => *v = true,
                None => {
                    return Err(SavedTruthMismatch::IdBeyond {
                        index,
                        id,
                        mesh: triangles,
                    })
                }
            }
        }
        Ok(GroundTruth {
            visible_count: self.visible_ids.len(),
            visible,
            rounds: self.rounds,
            last_change: self.last_change,
            converged: self.converged,
            rays: self.rays,
            seconds: self.seconds,
            ..Default::default()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` triangles along x, the last moved by `shift` (a mesh for the
    /// labels to belong to).
    fn strip(n: usize, shift: f32) -> TriangleMesh {
        use raykit_core::Vec3;
        let mut m = TriangleMesh::default();
        for i in 0..n {
            let x = i as f32 + if i + 1 == n { shift } else { 0.0 };
            let b = m.positions.len() as u32;
            m.positions.extend([
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 1.0, 0.0, 0.0),
                Vec3::new(x, 1.0, 0.0),
            ]);
            m.indices.push([b, b + 1, b + 2]);
        }
        m
    }

    #[test]
    fn labels_survive_the_json_round_trip() {
        let visible = vec![true, false, false, true, true];
        let truth = GroundTruth {
            visible_count: 3,
            visible: visible.clone(),
            rounds: 4,
            rays: 99,
            ..Default::default()
        };
        let mesh = strip(5, 0.0);
        let saved = SavedTruth::new("m.obj", &mesh, &truth, 1e-4);
        let text = serde_json::to_string(&saved).unwrap();
        let back: SavedTruth = serde_json::from_str(&text).unwrap();
        let again = back.to_truth(&mesh).unwrap();
        assert_eq!(again.visible, visible);
        assert_eq!(again.visible_count, 3);
        assert_eq!((again.rounds, again.rays), (4, 99));
        assert_eq!(
            back.to_truth(&strip(6, 0.0)).unwrap_err(),
            SavedTruthMismatch::Triangles { saved: 5, mesh: 6 }
        );
        // As many triangles, one of them moved: another mesh.
        assert!(matches!(
            back.to_truth(&strip(5, 1e-3)).unwrap_err(),
            SavedTruthMismatch::Mesh { .. }
        ));
        // A file saved without the digest is checked by its count alone.
        let mut old = back.clone();
        old.mesh_digest = None;
        let text = serde_json::to_string(&old).unwrap();
        assert!(!text.contains("mesh_digest"));
        let old: SavedTruth = serde_json::from_str(&text).unwrap();
        assert_eq!(old.to_truth(&strip(5, 1e-3)).unwrap().visible, visible);
        let mut bad = back.clone();
        bad.visible_ids.push(9);
        assert_eq!(
            bad.to_truth(&mesh).unwrap_err(),
            SavedTruthMismatch::IdBeyond {
                index: 3,
                id: 9,
                mesh: 5
            }
        );
    }
}
