//! The visibility buffer: nearest triangle per pixel by rasterization, with
//! the exact hit of each candidate pixel's ray.

use super::bins::Bins;
use super::samples::Samples;
use super::screen::Screen;
use super::setup::EdgeSetup;
use super::tight::{Tight, TightSetup};
use super::view::RasterView;
use raykit_core::tri::{TestKind, TriangleTest};
use raykit_core::{with_test, Camera, Hit, Ray, TriangleMesh};
use rayon::prelude::*;

/// Rows per band: the unit of parallel work.
const BAND_HEIGHT: u32 = 8;

/// The Purcell-style stream tracer's rasterized primary visibility: the nearest hit of the camera
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

/// Visibility buffer by rasterization (the Purcell-style stream tracer's hybrid renderer: the first
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
/// Each pixel's sample position is computed once; every triangle is set up
/// once (edge functions of its projection, widened by a bound on rounding
/// and tested at the sample positions, [`super::tight`]; triangles near the
/// eye plane or in degenerate views get the conservative whole-pixel setup,
/// [`super::setup`]), triangles whose box holds no covered sample are
/// dropped, the rest binned into bands of rows, and every band is
/// rasterized in parallel: each candidate pixel of each triangle gets the
/// exact hit of its own ray with that triangle (the same test and
/// precomputed data as the accelerators use) unless the pixel's nearest hit
/// so far is nearer than the triangle can be, and a depth test on `t` keeps
/// the nearest. A zero-size image gives an empty buffer.
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
/// the Purcell-style stream tracer's shadow maps render depth from a light: `sample(x, y)` must be
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

/// Below `pixels / FEW_TRIANGLES_RATIO` triangles the rasterizer skips the
/// per-pixel sample pass and the tight setup (measured: on the 1.3k-triangle
/// Cornell box at 512² the sample pass alone costs more than the tight
/// coverage saves).
const FEW_TRIANGLES_RATIO: usize = 16;

/// How a set-up triangle's candidate pixels are found.
enum Edges {
    /// At the pixels' sample positions, tight ([`TightSetup`]).
    Tight(TightSetup),
    /// At pixel centres, widened by half a pixel ([`EdgeSetup`]).
    Wide(EdgeSetup),
}

impl Edges {
    /// Inclusive pixel box `(x0, x1, y0, y1)`.
    fn bounds(&self) -> (u32, u32, u32, u32) {
        match self {
            Edges::Tight(e) => (e.x0, e.x1, e.y0, e.y1),
            Edges::Wide(e) => (e.x0, e.x1, e.y0, e.y1),
        }
    }
}

/// One set-up triangle: candidate pixels, the test's precomputed data.
struct Prepared<T: TriangleTest> {
    edges: Edges,
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
    // Each pixel's sample position, once; without them (a degenerate view,
    // rays not through their pixels) every triangle takes the whole-pixel
    // setup. With far fewer triangles than pixels (large triangles, each
    // covering many pixels) the sample pass costs more than the tight
    // coverage saves, so the whole-pixel setup is used then too.
    let few_triangles = mesh.num_triangles().saturating_mul(FEW_TRIANGLES_RATIO) < pixels;
    let samples = if few_triangles {
        None
    } else {
        let screen = Screen::new(view, width, height);
        screen.and_then(|s| Samples::new(&s, width, height, sample).map(|p| (s, p)))
    };
    // Setup and binning, in parallel, keeping mesh order.
    let bins = Bins::new(
        mesh.num_triangles(),
        BAND_HEIGHT,
        height.div_ceil(BAND_HEIGHT) as usize,
        |p| {
            let corners = mesh.triangle(p);
            let tight = match &samples {
                Some((screen, samples)) => Tight::new(screen, samples, corners, width, height),
                None => Tight::Fallback,
            };
            let edges = match tight {
                Tight::Setup(e) => Edges::Tight(e),
                Tight::Hidden => return None,
                Tight::Fallback => Edges::Wide(EdgeSetup::new(view, corners, width, height)?),
            };
            let [a, b, c] = corners;
            Some(Prepared::<T> {
                edges,
                tri: T::precompute(a, b, c),
                prim: p as u32,
            })
        },
        |t| {
            let (_, _, y0, y1) = t.edges.bounds();
            (y0, y1)
        },
    );
    let mut out: Vec<Option<Hit>> = vec![None; pixels];
    let w = width as usize;
    let pos: &[[f32; 2]] = samples.as_ref().map_or(&[], |(_, s)| &s.pos);
    out.par_chunks_mut(w * BAND_HEIGHT as usize)
        .enumerate()
        .for_each_init(
            || (Vec::new(), Vec::new()),
            |(rays, depth), (band, hits)| {
                let y_first = band as u32 * BAND_HEIGHT;
                let rows = (hits.len() / w) as u32;
                let first = y_first as usize * w;
                // The band's rays and per-ray data, made when a pixel first
                // becomes a candidate (background pixels never need one),
                // and the distance of each pixel's nearest hit so far.
                rays.clear();
                rays.resize(hits.len(), None);
                depth.clear();
                depth.resize(hits.len(), f32::INFINITY);
                for t in bins.band(band) {
                    let (x0, x1, ty0, ty1) = t.edges.bounds();
                    let y0 = ty0.max(y_first);
                    let y1 = ty1.min(y_first + rows - 1);
                    for y in y0..=y1 {
                        let row = (y - y_first) as usize * w;
                        for x in x0..=x1 {
                            let slot = row + x as usize;
                            match &t.edges {
                                Edges::Tight(e) => {
                                    // Nothing nearer than the triangle's
                                    // closest point can change the pixel.
                                    if depth[slot] <= e.tmin || !e.covers(pos[first + slot]) {
                                        continue;
                                    }
                                }
                                Edges::Wide(e) => {
                                    if !e.covers(x, y) {
                                        continue;
                                    }
                                }
                            }
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
                                    depth[slot] = h.t;
                                }
                            }
                        }
                    }
                }
            },
        );
    out
}
