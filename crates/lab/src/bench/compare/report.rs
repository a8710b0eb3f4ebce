//! What a comparison reports: the cells (ours beside each Embree), the
//! agreement of the answers, and the figures of our builds.

use raykit_core::accel::AccelKind;
use raykit_core::tri::TestKind;
use raykit_core::verify::Verdict;
use raykit_embree::{Quality, QueryApi};
use serde::Serialize;

/// One cell: our figure beside each Embree's. Builds in ms (a ratio above
/// 1 means our build is faster), traces in Mrays/s (ours ÷ Embree).
#[derive(Serialize)]
pub(crate) struct Cell {
    pub what: String,
    /// Our structure × test of this cell.
    pub structure: String,
    pub threads: usize,
    pub ours: f64,
    /// Embree 4's figure: its fastest API on trace cells.
    pub embree4: Option<f64>,
    /// The Embree 4 API that gave it (`rtcIntersect16`, …).
    pub embree4_api: Option<String>,
    pub ratio4: Option<f64>,
    pub embree3: Option<f64>,
    pub ratio3: Option<f64>,
    /// Largest (max−min)/median of the samples behind the figures.
    pub spread: f64,
}

#[derive(Serialize)]
pub(crate) struct Agreement {
    pub set: &'static str,
    /// Our structure × test compared, and its API (batch or one-ray).
    pub structure: String,
    /// The Embree and API whose answers ours are compared with.
    pub engine: String,
    /// Every ray of the set; `edge_grazes` counts the disagreements where
    /// the nearer answer's triangle is met within the edge band (f64): the
    /// ray grazes an edge, one engine catches it where the other slips past.
    pub verdict: Verdict,
}

/// Our build's size and quality, shown beside its build time.
#[derive(Serialize)]
pub(crate) struct BuiltFigures {
    pub structure: String,
    pub sah_cost: f64,
    pub bytes: usize,
    pub nodes: usize,
}

#[derive(Serialize)]
pub(crate) struct Comparison {
    pub mesh: String,
    pub triangles: usize,
    /// The builder of the structures traced (`--bvh-build`).
    pub traced_build: String,
    /// The Embree versions compared (`4.4.0 (path)`, `3`).
    pub embree4: Option<String>,
    pub embree3: bool,
    pub ours: Vec<BuiltFigures>,
    pub builds_ms: Vec<Cell>,
    pub mrays: Vec<Cell>,
    pub agreement: Vec<Agreement>,
}

/// The build Embree traces: HIGH (with spatial splits), or MEDIUM where
/// RAYKIT_EMBREE_TRACE_MEDIUM is set (an experiment: on the scatter both
/// trace at the same speed, so the splits are not what Embree's lead on
/// shadow and incoherent rays comes from).
pub(crate) fn trace_quality() -> Quality {
    match std::env::var_os("RAYKIT_EMBREE_TRACE_MEDIUM") {
        Some(_) => Quality::Medium,
        None => Quality::High,
    }
}

/// `structure × test`, as the cells name our structures.
pub(crate) fn label(kind: AccelKind, test: TestKind) -> String {
    format!("{} × {}", kind.name(), test.name())
}

/// The Embree 4 call of `api` for a set.
pub(crate) fn api_name(api: QueryApi, shadow: bool) -> String {
    let call = if shadow {
        "rtcOccluded"
    } else {
        "rtcIntersect"
    };
    format!("{call}{}", api.width())
}
