//! The visibility buffer: nearest triangle per pixel by rasterization, with
//! the exact hit of each candidate pixel's ray.

use super::bins::Bins;
use super::setup::EdgeSetup;
use super::view::RasterView;
use raykit_core::tri::{TestKind, TriangleTest};
use raykit_core::{with_test, Camera, Hit, Ray, TriangleMesh};
use rayon::prelude::*;

/// Rows per band: the unit of parallel work.
const BAND_HEIGHT: u32 = 8;

/// Paper 001's rasterized primary visibility: the nearest hit of the camera
/// ray of every pixel of a `width` × `height` image (row-major), through the
/// pixel centres, as [`visibility`] computes it.
pub fn primary_visibility(
    mesh: &TriangleMesh,
    test: TestKind,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Vec<Option<Hit>> {
    let rays = camera.rays(width, height);
    visibility(mesh, test, camera, width, height, &|x, y| rays.pixel(x, y))
}

/// Visibility buffer by rasterization (paper 001's hybrid renderer: the first
/// hit per pixel is rasterized with the ray camera's projection, rays are
/// traced only from there on).
///
/// `sample(x, y)` gives the ray of pixel (`x`, `y`) (`x < width`,
/// `y < height`); it must start at the camera's eye and pass through that
/// pixel of `camera`'s image (the pixel centre, or a jittered position
/// inside it, as `Camera::rays(width, height).ray(fx, fy)` gives). The
/// result, row-major, is per pixel the hit that tracing the same ray
/// through an accelerator built with the triangle test `test` reports
/// (`Accel::intersect`), except where two triangles are hit at the same
/// distance (shared edges, coplanar overlap), where either may be kept.
///
/// Every triangle is set up once (edge functions of its projection,
/// conservatively expanded, and a screen box), binned into bands of rows,
/// and every band is rasterized in parallel: each candidate pixel of each
/// triangle gets the exact hit of its own ray with that triangle (the same
/// test and precomputed data as the accelerators use), and a depth test on
/// `t` keeps the nearest. A zero-size image gives an empty buffer.
pub fn visibility(
    mesh: &TriangleMesh,
    test: TestKind,
    camera: &Camera,
    width: u32,
    height: u32,
    sample: &(dyn Fn(u32, u32) -> Ray + Sync),
) -> Vec<Option<Hit>> {
    let view = RasterView::camera(camera, width, height);
    rasterize(mesh, test, &view, width, height, sample)
}

/// [`visibility`] for any [`RasterView`] (perspective or orthographic), as
/// paper 001's shadow maps render depth from a light: `sample(x, y)` must be
/// a ray of `view` through pixel (`x`, `y`).
pub fn rasterize(
    mesh: &TriangleMesh,
    test: TestKind,
    view: &RasterView,
    width: u32,
    height: u32,
    sample: &(dyn Fn(u32, u32) -> Ray + Sync),
) -> Vec<Option<Hit>> {
    with_test!(test, T => rasterize_with::<T>(mesh, view, width, height, sample))
}

/// One set-up triangle: edge functions, box, the test's precomputed data.
struct Prepared<T: TriangleTest> {
    edges: EdgeSetup,
    tri: T::Tri,
    prim: u32,
}

fn rasterize_with<T: TriangleTest>(
    mesh: &TriangleMesh,
    view: &RasterView,
    width: u32,
    height: u32,
    sample: &(dyn Fn(u32, u32) -> Ray + Sync),
) -> Vec<Option<Hit>> {
    let pixels = width as usize * height as usize;
    if pixels == 0 {
        return Vec::new();
    }
    // Setup, in parallel, keeping mesh order.
    let prepared: Vec<Prepared<T>> = (0..mesh.num_triangles())
        .into_par_iter()
        .with_min_len(1024)
        .filter_map(|p| {
            let corners = mesh.triangle(p);
            let edges = EdgeSetup::new(view, corners, width, height)?;
            let [a, b, c] = corners;
            Some(Prepared {
                edges,
                tri: T::precompute(a, b, c),
                prim: p as u32,
            })
        })
        .collect();
    let bands = height.div_ceil(BAND_HEIGHT) as usize;
    let rows: Vec<(u32, u32)> = prepared
        .par_iter()
        .map(|t| (t.edges.y0, t.edges.y1))
        .collect();
    let bins = Bins::new(&rows, BAND_HEIGHT, bands);
    let mut out: Vec<Option<Hit>> = vec![None; pixels];

    let w = width as usize;
    out.par_chunks_mut(w * BAND_HEIGHT as usize)
        .enumerate()
        .for_each_init(Vec::new, |rays, (band, hits)| {
            let y_first = band as u32 * BAND_HEIGHT;
            let rows = (hits.len() / w) as u32;
            // The band's rays and per-ray data, made when a pixel first
            // becomes a candidate (background pixels never need one).
            rays.clear();
            rays.resize(hits.len(), None);
            for index in bins.band(band) {
                let t = &prepared[index as usize];
                let e = &t.edges;
                let y0 = e.y0.max(y_first);
                let y1 = e.y1.min(y_first + rows - 1);
                for y in y0..=y1 {
                    let row = (y - y_first) as usize * w;
                    for x in e.x0..=e.x1 {
                        if !e.covers(x, y) {
                            continue;
                        }
                        let slot = row + x as usize;
                        let (ray, rd) = rays[slot].get_or_insert_with(|| {
                            let ray = sample(x, y);
                            (ray, T::prepare(&ray))
                        });
                        let best = &mut hits[slot];
                        let tfar = best.map_or(ray.tfar, |b| b.t);
                        if let Some(h) = T::intersect(&t.tri, ray, rd, tfar) {
                            if best.is_none_or(|b| h.t < b.t) {
                                *best = Some(Hit {
                                    t: h.t,
                                    u: h.u,
                                    v: h.v,
                                    prim: t.prim,
                                });
                            }
                        }
                    }
                }
            }
        });
    out
}
