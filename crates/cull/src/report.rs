//! The report of a culling run as `raykit cull` writes it: what was
//! removed and how, the figures of the run, and the evaluation against the
//! ground truth; as JSON (serde) or as a summary in words.

use crate::evaluate::{EvalReport, GroundTruth};
use crate::{CullResult, CullStats};
use raykit_core::TriangleMesh;
use serde::Serialize;
use std::path::Path;

/// What is removed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Removal {
    /// Each hidden triangle.
    Triangle,
    /// Whole parts with no visible triangle.
    Part,
}

/// How visibility is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CullMode {
    /// Ray tracing ([`crate::cull_by_rays`]).
    Rays,
    /// Min's (2008) grid with the conservative additions.
    Conservative,
    /// Min's (2008) rule alone.
    Paper,
}

impl CullResult {
    /// Per triangle of `mesh`: true when kept by `removal` (a triangle of a
    /// part with any kept triangle is kept under [`Removal::Part`]).
    pub fn keep(&self, mesh: &TriangleMesh, removal: Removal) -> Vec<bool> {
        match removal {
            Removal::Triangle => self.visible.clone(),
            Removal::Part => (0..mesh.num_triangles())
                .map(|t| self.part_visible[mesh.part_of(t) as usize])
                .collect(),
        }
    }
}

/// A glTF assembly written with its instancing: the nodes placing meshes
/// and the meshes they place, read and written.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Instancing {
    /// Nodes placing a mesh in the input (one per copy of a node with
    /// `EXT_mesh_gpu_instancing`).
    pub nodes_in: usize,
    /// Meshes those nodes place.
    pub meshes_in: usize,
    /// Nodes written (those that keep any triangle).
    pub nodes_out: usize,
    /// Meshes written: one per mesh and set of kept triangles.
    pub meshes_out: usize,
    /// Whether every node of a mesh was made to keep what any of them
    /// keeps, so that each mesh is written once.
    pub shared: bool,
}

/// The report of one run: the run's figures and the library's statistics.
#[derive(Clone, Debug, Serialize)]
pub struct CullReport {
    /// The input mesh, as named.
    pub input: String,
    /// The output mesh, as named.
    pub output: String,
    /// What was removed.
    pub by: Removal,
    /// How visibility was found.
    pub mode: CullMode,
    /// Whether every remaining candidate was confirmed by rays.
    pub confirm: bool,
    /// Grid points along the longest axis (grid modes).
    pub resolution: u32,
    /// Narrowest opening of the rays mode, a fraction of the diagonal.
    pub min_opening: f32,
    /// Triangles read.
    pub triangles_in: usize,
    /// Triangles written.
    pub triangles_out: usize,
    /// Triangles removed.
    pub triangles_removed: usize,
    /// Parts read.
    pub parts_in: usize,
    /// Parts written.
    pub parts_out: usize,
    /// Parts removed.
    pub parts_removed: usize,
    /// Seconds to read the input.
    pub load_s: f64,
    /// Seconds to cull.
    pub cull_s: f64,
    /// Seconds to write the output.
    pub save_s: f64,
    /// The library's figures.
    pub stats: CullStats,
    /// How a glTF input's instancing was written, when it was.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub instancing: Option<Instancing>,
    /// The ground truth, when evaluated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground_truth: Option<GroundTruth>,
    /// The comparison with the ground truth, when evaluated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub evaluation: Option<EvalReport>,
}

impl CullReport {
    /// The report in words, one line per topic, ending with the files
    /// written (`output`, and `report` when the JSON went to a file).
    pub fn summary(&self, output: &Path, report: Option<&Path>) -> String {
        let r = self;
        let s = &r.stats;
        let mut out = String::new();
        // One line of the summary.
        macro_rules! say {
            ($($arg:tt)*) => {{
                out.push_str(&format!($($arg)*));
                out.push('\n');
            }};
        }
        match &s.rays {
            Some(x) => say!(
                "{}: {} triangles, {} parts; visible = {}",
                r.input,
                r.triangles_in,
                r.parts_in,
                if x.beam > 0.0 {
                    format!(
                        "an escaping beam {:.4e} wide ({} of the diagonal) from either face",
                        x.beam, r.min_opening
                    )
                } else {
                    "any escaping ray from either face".to_string()
                }
            ),
            None => say!(
                "{}: {} triangles, {} parts; grid {}x{}x{} (spacing {}), {} of {} points outside",
                r.input,
                r.triangles_in,
                r.parts_in,
                s.grid[0],
                s.grid[1],
                s.grid[2],
                // Four decimals, or four digits where those would show
                // none (a model micrometres across).
                if s.spacing >= 1e-3 || s.spacing == 0.0 {
                    format!("{:.4}", s.spacing)
                } else {
                    format!("{:.3e}", s.spacing)
                },
                s.outside_points,
                s.points
            ),
        }
        let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
        say!(
            "triangles: {} -> {} ({} removed, {:.1}%)",
            r.triangles_in,
            r.triangles_out,
            r.triangles_removed,
            pct(r.triangles_removed, r.triangles_in)
        );
        say!(
            "parts: {} -> {} ({} removed, {:.1}%)",
            r.parts_in,
            r.parts_out,
            r.parts_removed,
            pct(r.parts_removed, r.parts_in)
        );
        if let Some(i) = &r.instancing {
            say!(
                "instancing: {} nodes placing {} meshes -> {} nodes placing {} meshes{}",
                i.nodes_in,
                i.meshes_in,
                i.nodes_out,
                i.meshes_out,
                if i.shared {
                    " (each mesh keeps what any of its nodes sees)"
                } else {
                    " (nodes that keep the same triangles of a mesh share it)"
                }
            );
        }
        if let Some(x) = &s.rays {
            say!(
                "rays: {} seen by {} views of {}x{}, {} by escape rays and shared directions in {} rounds \
                 ({}; last round added {}); {} rays, {:.0} per triangle; {}; {} zero-area triangles {}",
                x.by_views,
                x.viewpoints,
                x.image,
                x.image,
                x.by_escape_rays,
                x.rounds,
                if x.converged {
                    "converged: the last two found nothing"
                } else {
                    "not converged"
                },
                x.last_round_added,
                x.rays,
                x.rays_per_triangle,
                x.escape_fraction_95.map_or(
                    "no triangle of positive area removed".to_string(),
                    |f| format!(
                        "every removed triangle survived at least {} escape rays of its own (one \
                         escaping through {f:.1e} of its point and direction samples would have been \
                         found with 95% probability)",
                        x.rays_per_removed
                    )
                ),
                x.degenerate,
                if r.by == Removal::Part {
                    "counted hidden (removed only with their parts)"
                } else {
                    "removed"
                }
            );
        }
        if r.mode == CullMode::Conservative {
            say!(
                "conservative mode kept {} triangles by dilation, {} by contact with outside cells, {} by \
                 escaping rays at the frontier{}{}",
                s.kept_by_dilation,
                s.kept_by_contact,
                s.kept_by_frontier,
                if s.frontier_cut_short {
                    " (ray budget reached: a finer --resolution or --confirm searches more)"
                } else {
                    ""
                },
                if r.confirm {
                    format!(", {} by escaping rays elsewhere", s.kept_by_rays)
                } else {
                    String::new()
                }
            );
        }
        if s.rays.is_some() {
            say!(
                "time: load {:.1} ms, BVH {:.1} ms, rays {:.1} ms, save {:.1} ms",
                r.load_s * 1e3,
                s.accel_seconds * 1e3,
                s.visible_seconds * 1e3,
                r.save_s * 1e3
            );
        } else {
            say!(
                "time: load {:.1} ms, BVH {:.1} ms, distance field {:.1} ms, propagation {:.1} ms, \
                 visible set {:.1} ms, save {:.1} ms",
                r.load_s * 1e3,
                s.accel_seconds * 1e3,
                s.distance_field_seconds * 1e3,
                s.propagation_seconds * 1e3,
                s.visible_seconds * 1e3,
                r.save_s * 1e3
            );
        }
        if let (Some(g), Some(e)) = (&r.ground_truth, &r.evaluation) {
            say!(
                "ground truth: {} of {} triangles visible ({} rounds, last added {}{}; {} points x {} \
                 directions per face, {} viewpoints of {}x{}; {} rays, {:.1} s)",
                g.visible_count,
                r.triangles_in,
                g.rounds,
                g.last_change,
                if g.converged { "" } else { ", not converged" },
                g.points,
                g.directions,
                g.viewpoints,
                g.image,
                g.image,
                g.rays,
                g.seconds
            );
            say!(
                "evaluation: removed {:.1}% of triangles, {:.1}% of area, {:.1}% of parts; \
                 false removals {} (area {:.4e}{}), missed removals {} ({:.1}% of {} truly hidden)",
                100.0 * e.removed_fraction_triangles,
                100.0 * e.removed_fraction_area,
                100.0 * e.removed_fraction_parts,
                e.false_removals,
                e.false_removal_area,
                if e.false_removal_ids.is_empty() {
                    String::new()
                } else {
                    format!(", first ids {:?}", e.false_removal_ids)
                },
                e.missed_removals,
                100.0 * e.missed_fraction,
                e.truly_hidden
            );
        }
        say!("wrote {}", output.display());
        if let Some(p) = report {
            say!("wrote the report to {}", p.display());
        }
        out
    }
}
