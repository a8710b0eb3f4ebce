//! The answers of every engine and API on every ray set, checked against
//! ours ray by ray (edge grazes told apart in f64).

use super::report::{api_name, label, Agreement};
use super::timing::STREAM_PACKET;
use crate::one_ray;
use raykit_core::accel::AccelKind;
use raykit_core::raysets::RayKind;
use raykit_core::tri::TestKind;
use raykit_core::verify::{compare_hits, compare_occlusion, edge_grazes, occlusion_grazes};
use raykit_core::{Accel, Hit, Ray, TriangleMesh};
use raykit_embree::{Embree3Scene, Embree4Scene, QueryApi};

/// Answers of one engine and API on a set.
pub(super) enum Answers {
    Hits(Vec<Option<Hit>>),
    Occluded(Vec<bool>),
}

/// An engine's nearest hits of some rays, into a slice.
pub(super) type HitsInto<'a> = dyn Fn(&[Ray], &mut [Option<Hit>]) + 'a;
/// An engine's occlusion answers of some rays, into a slice.
pub(super) type OcclusionInto<'a> = dyn Fn(&[Ray], &mut [bool]) + 'a;

/// An engine's nearest hits of some rays.
pub(super) type NearestHits<'a> = Box<dyn Fn(&[Ray]) -> Vec<Option<Hit>> + 'a>;

/// Every ray of every set: ours (batch and one-ray) against Embree 3's
/// single rays and stream, and against each Embree 4 API.
pub(super) fn agreement(
    mesh: &TriangleMesh,
    sets: &[Vec<Ray>; 3],
    embree3: Option<&Embree3Scene>,
    embree4: Option<&Embree4Scene>,
    ours: &[Box<dyn Accel>],
    names: &[(AccelKind, TestKind)],
) -> Vec<Agreement> {
    let mut out = Vec::new();
    for (si, set) in RayKind::ALL.into_iter().enumerate() {
        let rays = &sets[si];
        let shadow = set == RayKind::Shadow;
        let coherent = set != RayKind::Incoherent;
        // (engine label, its answers, and a nearest-hit oracle of the same
        // engine for telling edge grazes apart on shadow rays)
        let mut theirs: Vec<(String, Answers, NearestHits)> = Vec::new();
        let answers = |f: &HitsInto, g: &OcclusionInto| {
            if shadow {
                let mut o = vec![false; rays.len()];
                g(rays, &mut o);
                Answers::Occluded(o)
            } else {
                let mut h = vec![None; rays.len()];
                f(rays, &mut h);
                Answers::Hits(h)
            }
        };
        if let Some(em) = embree3 {
            theirs.push((
                format!(
                    "Embree 3 {}",
                    if shadow {
                        "rtcOccluded1"
                    } else {
                        "rtcIntersect1"
                    }
                ),
                answers(&|r, h| em.intersect_batch(r, h), &|r, o| {
                    em.occluded_batch(r, o)
                }),
                Box::new(move |r: &[Ray]| {
                    let mut h = vec![None; r.len()];
                    em.intersect_batch(r, &mut h);
                    h
                }),
            ));
            if set == RayKind::Primary {
                let mut h = vec![None; rays.len()];
                em.intersect_stream(rays, &mut h, STREAM_PACKET);
                theirs.push((
                    "Embree 3 rtcIntersect1M".to_string(),
                    Answers::Hits(h),
                    Box::new(|_: &[Ray]| Vec::new()),
                ));
            }
        }
        if let Some(em) = embree4 {
            for api in QueryApi::ALL {
                theirs.push((
                    format!("Embree 4 {}", api_name(api, shadow)),
                    answers(&|r, h| em.intersect_with(api, r, h, coherent), &|r, o| {
                        em.occluded_with(api, r, o, coherent)
                    }),
                    Box::new(move |r: &[Ray]| {
                        let mut h = vec![None; r.len()];
                        em.intersect_with(api, r, &mut h, coherent);
                        h
                    }),
                ));
            }
        }
        for (o, &(kind, test)) in ours.iter().zip(names) {
            for one_ray_api in [false, true] {
                let mine = answers(
                    &|r, h| {
                        if one_ray_api {
                            one_ray::intersect_each(o.as_ref(), r, h)
                        } else {
                            o.intersect_batch(r, h)
                        }
                    },
                    &|r, v| {
                        if one_ray_api {
                            one_ray::occluded_each(o.as_ref(), r, v)
                        } else {
                            o.occluded_batch(r, v)
                        }
                    },
                );
                let structure = format!(
                    "{}{}",
                    label(kind, test),
                    if one_ray_api { ", one ray" } else { "" }
                );
                for (engine, theirs, nearest) in &theirs {
                    // The one-ray answers against the single-ray calls only.
                    if one_ray_api && !engine.ends_with('1') {
                        continue;
                    }
                    let verdict = match (theirs, &mine) {
                        (Answers::Hits(a), Answers::Hits(b)) => {
                            let mut v = compare_hits(a, b);
                            v.edge_grazes = edge_grazes(mesh, rays, a, b);
                            v
                        }
                        (Answers::Occluded(a), Answers::Occluded(b)) => {
                            let mut v = compare_occlusion(a, b);
                            (v.edge_grazes, _) = occlusion_grazes(mesh, rays, a, b, |r| {
                                let mut hb = vec![None; r.len()];
                                o.intersect_batch(r, &mut hb);
                                (nearest(r), hb)
                            });
                            v
                        }
                        _ => unreachable!("both answer the same kind of query"),
                    };
                    out.push(Agreement {
                        set: set.name(),
                        structure: structure.clone(),
                        engine: engine.clone(),
                        verdict,
                    });
                }
            }
        }
    }
    out
}
