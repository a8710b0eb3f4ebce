//! The ground truth's labels as a JSON file (`raykit cull --save-truth`,
//! read back by `--truth`): the visible triangles' ids and the figures of
//! the run that found them, so that a slow evaluation is done once.

use crate::evaluate::GroundTruth;
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
}

/// Why saved labels do not fit the mesh they are read for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SavedTruthMismatch {
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
    /// The labels of `truth`, found on `input` with `min_opening`.
    pub fn new(input: &str, truth: &GroundTruth, min_opening: f32) -> SavedTruth {
        SavedTruth {
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

    /// The ground truth for a mesh of `triangles` triangles, or why the
    /// labels do not fit it.
    pub fn to_truth(&self, triangles: usize) -> Result<GroundTruth, SavedTruthMismatch> {
        if self.triangles != triangles {
            return Err(SavedTruthMismatch::Triangles {
                saved: self.triangles,
                mesh: triangles,
            });
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
        let saved = SavedTruth::new("m.obj", &truth, 1e-4);
        let text = serde_json::to_string(&saved).unwrap();
        let back: SavedTruth = serde_json::from_str(&text).unwrap();
        let again = back.to_truth(5).unwrap();
        assert_eq!(again.visible, visible);
        assert_eq!(again.visible_count, 3);
        assert_eq!((again.rounds, again.rays), (4, 99));
        assert_eq!(
            back.to_truth(6).unwrap_err(),
            SavedTruthMismatch::Triangles { saved: 5, mesh: 6 }
        );
        let mut bad = back.clone();
        bad.visible_ids.push(9);
        assert_eq!(
            bad.to_truth(5).unwrap_err(),
            SavedTruthMismatch::IdBeyond {
                index: 3,
                id: 9,
                mesh: 5
            }
        );
    }
}
