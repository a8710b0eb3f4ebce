//! Timing the engines in turn: each cell's runs interleaved round by
//! round, and the trace calls of each engine and API.

use super::report::{api_name, label, Cell};
use crate::measure::{median_min_max, timed};
use crate::one_ray;
use raykit_core::accel::AccelKind;
use raykit_core::raysets::RayKind;
use raykit_core::tri::TestKind;
use raykit_core::{Accel, Ray};
use raykit_embree::{Embree4Scene, QueryApi};

/// Rays per `rtcIntersect1M` call of the Embree 3 stream cell.
pub(super) const STREAM_PACKET: usize = 256;

/// One timed thing of a cell: an engine's build or trace.
pub(super) type Run<'a> = Box<dyn FnMut() + 'a>;

/// Median seconds and spread (max−min)/median of each of `runs`, timed in
/// turn: each of `reps` rounds times every run once, in order, after one
/// untimed round where `warm_up` is set. Host noise comes in bursts of a
/// second or more; timed one engine after the other, a burst could fall on
/// all of one engine's samples and move its median alone; in turn, a burst
/// falls on both engines' samples alike. The warm-up round is for the trace
/// cells, whose first runs after the builds spread far more than the later
/// ones: the medians are the steady state, as a renderer tracing frame
/// after frame sees it.
pub(super) fn time_in_turn(reps: usize, warm_up: bool, runs: &mut [Run]) -> Vec<(f64, f64)> {
    if warm_up {
        runs.iter_mut().for_each(|f| f());
    }
    let mut samples = vec![Vec::new(); runs.len()];
    for _ in 0..reps.max(1) {
        for (f, t) in runs.iter_mut().zip(&mut samples) {
            t.push(timed(&mut *f).1);
        }
    }
    samples
        .iter()
        .map(|t| {
            let (m, lo, hi) = median_min_max(t);
            (m, if m > 0.0 { (hi - lo) / m } else { 0.0 })
        })
        .collect()
}

/// Our batch API over the set.
pub(super) fn trace(accel: &dyn Accel, rays: &[Ray], shadow: bool) {
    if shadow {
        let mut o = vec![false; rays.len()];
        accel.occluded_batch(rays, &mut o);
    } else {
        let mut h = vec![None; rays.len()];
        accel.intersect_batch(rays, &mut h);
    }
}

/// Our one-ray API over the set.
pub(super) fn trace_one_ray(accel: &dyn Accel, rays: &[Ray], shadow: bool) {
    if shadow {
        let mut o = vec![false; rays.len()];
        one_ray::occluded_each(accel, rays, &mut o);
    } else {
        let mut h = vec![None; rays.len()];
        one_ray::intersect_each(accel, rays, &mut h);
    }
}

/// Embree 4 through `api`; primaries and shadow rays (which leave from
/// the primaries' hit points in pixel order) carry the coherent hint.
pub(super) fn trace4(em: &Embree4Scene, api: QueryApi, rays: &[Ray], set: RayKind) {
    let coherent = set != RayKind::Incoherent;
    if set == RayKind::Shadow {
        let mut o = vec![false; rays.len()];
        em.occluded_with(api, rays, &mut o, coherent);
    } else {
        let mut h = vec![None; rays.len()];
        em.intersect_with(api, rays, &mut h, coherent);
    }
}

/// Medians and spreads of one cell's runs, in the order pushed: ours
/// first (one per structure), then Embree 4's APIs, then Embree 3.
pub(super) struct CellTimes {
    ours: Vec<(f64, f64)>,
    embree4: Vec<(QueryApi, f64, f64)>,
    embree3: Option<(f64, f64)>,
}

impl CellTimes {
    /// Split `times` (from `time_in_turn`) as the runs were pushed.
    pub(super) fn split(mut times: Vec<(f64, f64)>, apis: &[QueryApi], embree3: bool) -> CellTimes {
        let embree3 = if embree3 { times.pop() } else { None };
        let e4 = times.split_off(times.len() - apis.len());
        CellTimes {
            ours: times,
            embree4: apis
                .iter()
                .zip(e4)
                .map(|(&a, (t, sp))| (a, t, sp))
                .collect(),
            embree3,
        }
    }

    /// Cells of `what`: each of ours against Embree 4's fastest API and
    /// Embree 3. `rate` turns seconds into the figure shown (ms or
    /// Mrays/s), `ratio` two times into ours' advantage.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn cells(
        &self,
        what: &str,
        threads: usize,
        ours: &[(AccelKind, TestKind)],
        shadow: bool,
        rate: impl Fn(f64) -> f64,
        out: &mut Vec<Cell>,
    ) {
        let best4 = self
            .embree4
            .iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .copied();
        for (&(kind, test), &(t, sp)) in ours.iter().zip(&self.ours) {
            let t = t.max(1e-12);
            out.push(Cell {
                what: what.to_string(),
                structure: label(kind, test),
                threads,
                ours: rate(t),
                embree4: best4.map(|b| rate(b.1)),
                embree4_api: best4
                    .filter(|_| self.embree4.len() > 1 || !what.starts_with("build"))
                    .map(|b| api_name(b.0, shadow)),
                ratio4: best4.map(|b| b.1 / t),
                embree3: self.embree3.map(|e| rate(e.0)),
                ratio3: self.embree3.map(|e| e.0 / t),
                spread: best4
                    .map(|b| b.2)
                    .into_iter()
                    .chain(self.embree3.map(|e| e.1))
                    .fold(sp, f64::max),
            });
        }
    }
}
