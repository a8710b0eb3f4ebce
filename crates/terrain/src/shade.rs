//! Shading of terrain images: Phong (ambient + diffuse + specular) on the
//! declared surface's hit triangle, modulated by Min's (2008) per-grid-point
//! shadow mask (PAPERS.md 003), a hypsometric colour ramp or a draped image,
//! the sky, and the steps-per-ray heat map of the casters.

use crate::camera::CameraFrame;
use crate::heightfield::{HeightField, Steps, TerrainHit};
use crate::shadow::Light;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// Linear RGB.
type Rgb = DVec3;

/// Ambient, diffuse and specular weights and the Phong exponent.
const AMBIENT: f64 = 0.22;
const DIFFUSE: f64 = 0.85;
const SPECULAR: f64 = 0.12;
const SHININESS: i32 = 24;

/// Sky colours (linear): straight up, at the horizon, straight down.
const ZENITH: Rgb = DVec3::new(0.20, 0.38, 0.78);
const HORIZON: Rgb = DVec3::new(0.72, 0.80, 0.90);
const NADIR: Rgb = DVec3::new(0.55, 0.60, 0.66);

/// Hypsometric tints (sRGB, 0..1) at normalised heights 0..1.
const RAMP: [(f64, Rgb); 7] = [
    (0.00, DVec3::new(0.16, 0.40, 0.20)),
    (0.15, DVec3::new(0.33, 0.55, 0.27)),
    (0.35, DVec3::new(0.63, 0.66, 0.38)),
    (0.55, DVec3::new(0.60, 0.47, 0.31)),
    (0.72, DVec3::new(0.46, 0.36, 0.28)),
    (0.87, DVec3::new(0.62, 0.61, 0.60)),
    (1.00, DVec3::new(0.98, 0.98, 0.98)),
];

/// Heat-map colours (sRGB, 0..1) from zero to the most steps.
const HEAT: [(f64, Rgb); 5] = [
    (0.00, DVec3::new(0.00, 0.00, 0.02)),
    (0.25, DVec3::new(0.26, 0.04, 0.45)),
    (0.50, DVec3::new(0.73, 0.19, 0.33)),
    (0.75, DVec3::new(0.98, 0.55, 0.04)),
    (1.00, DVec3::new(0.99, 1.00, 0.80)),
];

/// An orthophoto stretched over the DEM's extent (pixel-is-area: its left
/// edge is the left edge of the DEM's first pixel, i.e. grid column −0.5),
/// so that aerial imagery of the same area colours the surface.
pub struct Drape {
    width: usize,
    height: usize,
    /// Linear RGB per pixel, row-major from the top (north).
    rgb: Vec<[f32; 3]>,
}

impl Drape {
    /// From 8-bit sRGB pixels, row-major from the top; converted once to
    /// linear RGB so that shading and filtering work on light intensities.
    pub fn new(width: u32, height: u32, srgb8: &[u8]) -> Drape {
        let lut: Vec<f32> = (0..256)
            .map(|i| srgb_to_linear(i as f64 / 255.0) as f32)
            .collect();
        let rgb = srgb8
            .chunks_exact(3)
            .map(|p| [lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]])
            .collect();
        Drape {
            width: width as usize,
            height: height as usize,
            rgb,
        }
    }

    /// Bilinear sample at grid position (`gx`, `gy`) of a `gw` × `gh` grid.
    fn sample(&self, gx: f64, gy: f64, gw: usize, gh: usize) -> Rgb {
        let fx =
            ((gx + 0.5) / gw as f64 * self.width as f64 - 0.5).clamp(0.0, (self.width - 1) as f64);
        let fy = ((gy + 0.5) / gh as f64 * self.height as f64 - 0.5)
            .clamp(0.0, (self.height - 1) as f64);
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (ax, ay) = (fx - x0 as f64, fy - y0 as f64);
        let p = |x: usize, y: usize| Vec3::from_array(self.rgb[y * self.width + x]).as_dvec3();
        let top = p(x0, y0) * (1.0 - ax) + p(x1, y0) * ax;
        let bottom = p(x0, y1) * (1.0 - ax) + p(x1, y1) * ax;
        top * (1.0 - ay) + bottom * ay
    }
}

/// Where the surface colour comes from: height tints (readable relief
/// without imagery) or a draped image.
pub enum Albedo<'a> {
    /// The hypsometric ramp over `[zmin, zmax]`.
    Ramp {
        /// Lowest height of the DEM.
        zmin: f64,
        /// Highest height of the DEM.
        zmax: f64,
    },
    /// A draped image.
    Drape(&'a Drape),
}

/// Everything the shading of one frame reads: the surface whose triangle
/// normals are lit, the light, the shadow mask and the surface colour.
pub struct Shading<'a> {
    /// The surface.
    pub field: &'a HeightField,
    /// The light.
    pub light: Light,
    /// Per grid point 1 = lit, 0 = shadow (`None`: no shadows).
    pub mask: Option<&'a [u8]>,
    /// Surface colour.
    pub albedo: Albedo<'a>,
}

/// `a` + (`b` − `a`)·`t` (glam's `lerp` rounds differently: a·(1−t) + b·t).
fn lerp3(a: Rgb, b: Rgb, t: f64) -> Rgb {
    a + (b - a) * t
}

/// `a` divided by its length; straight up for the zero vector.
fn normalize(a: DVec3) -> DVec3 {
    let l = a.length();
    if l > 0.0 {
        a / l
    } else {
        DVec3::Z
    }
}

/// Piecewise-linear colour ramp over `stops` at `t` in 0..1.
fn ramp(stops: &[(f64, Rgb)], t: f64) -> Rgb {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    for w in stops.windows(2) {
        let ((t0, c0), (t1, c1)) = (w[0], w[1]);
        if t <= t1 {
            return lerp3(c0, c1, ((t - t0) / (t1 - t0)).clamp(0.0, 1.0));
        }
    }
    stops[stops.len() - 1].1
}

fn srgb_to_linear(c: f64) -> f64 {
    c.max(0.0).powf(2.2)
}

/// Entries of the tables below.
const LUT: usize = 4096;

/// Linear → 8-bit sRGB through a table indexed by √linear (fine steps in
/// the darks, where the gamma curve is steep).
struct Gamma(Vec<u8>);

impl Gamma {
    fn new() -> Gamma {
        Gamma(
            (0..=LUT)
                .map(|i| {
                    let lin = (i as f64 / LUT as f64).powi(2);
                    (lin.powf(1.0 / 2.2) * 255.0 + 0.5) as u8
                })
                .collect(),
        )
    }

    fn to_u8(&self, linear: f64) -> u8 {
        let i = (linear.clamp(0.0, 1.0).sqrt() * LUT as f64 + 0.5) as usize;
        self.0[i.min(LUT)]
    }
}

/// Per-frame lookup tables.
struct Tables {
    gamma: Gamma,
    ramp: Vec<Rgb>,
}

/// The hypsometric ramp in linear RGB at `LUT + 1` normalised heights.
fn ramp_table() -> Vec<Rgb> {
    (0..=LUT)
        .map(|i| ramp(&RAMP, i as f64 / LUT as f64).map(srgb_to_linear))
        .collect()
}

/// The sky seen along unit world direction `d` (z up): a gradient from the
/// horizon's haze to the zenith's blue above, to a grey below, so rays that
/// miss the terrain still show which way is up.
pub fn sky(d: DVec3) -> Rgb {
    let z = d.z.clamp(-1.0, 1.0);
    if z >= 0.0 {
        lerp3(HORIZON, ZENITH, z.sqrt())
    } else {
        lerp3(HORIZON, NADIR, (-z).sqrt())
    }
}

/// The hit triangle's unit normal in world metres, from the hit's position
/// (`u`, `v`) in cell (`col`, `row`): the upper triangle ((c, r), (c+1, r),
/// (c+1, r+1)) where u ≥ v, the lower one ((c, r), (c+1, r+1), (c, r+1))
/// otherwise, as `heightfield.rs` declares them. Flat shading per triangle
/// shows the surface the casters intersect, not a smoothed one.
pub fn triangle_normal(field: &HeightField, col: usize, row: usize, u: f64, v: f64) -> DVec3 {
    // z = z0 + du·u + dv·v with u = x / sx, v = −y / sy.
    let p = field.cell_plane(col, row, u >= v);
    let (dzdx, dzdy) = (p.du / field.sx, -p.dv / field.sy);
    normalize(DVec3::new(-dzdx, -dzdy, 1.0))
}

/// Bilinear interpolation of the mask's four cell corners at (`u`, `v`).
fn mask_at(mask: &[u8], width: usize, col: usize, row: usize, u: f64, v: f64) -> f64 {
    let m = |c: usize, r: usize| mask[r * width + c] as f64;
    let top = m(col, row) * (1.0 - u) + m(col + 1, row) * u;
    let bottom = m(col, row + 1) * (1.0 - u) + m(col + 1, row + 1) * u;
    top * (1.0 - v) + bottom * v
}

impl Shading<'_> {
    /// Linear colour of `hit` seen along unit world direction `d` from
    /// `frame`'s eye.
    fn shade_hit(&self, ctx: &Tables, frame: &CameraFrame, d: DVec3, hit: &TerrainHit) -> Rgb {
        let f = self.field;
        let ray = f.grid_ray(frame.camera.eye, d.to_array());
        let p = ray.at(hit.t);
        let (col, row) = (hit.col as usize, hit.row as usize);
        let u = (p[0] - col as f64).clamp(0.0, 1.0);
        let v = (p[1] - row as f64).clamp(0.0, 1.0);
        let mut n = triangle_normal(f, col, row, u, v);
        if n.dot(d) > 0.0 {
            n = -n; // seen from below
        }
        let world = DVec3::new(p[0] * f.sx, -p[1] * f.sy, p[2]);
        let l = match self.light {
            Light::Sun {
                azimuth_deg,
                elevation_deg,
            } => DVec3::from_array(Light::sun_direction(azimuth_deg, elevation_deg)),
            Light::Point(q) => normalize(DVec3::from_array(q) - world),
        };
        let lit = self
            .mask
            .map_or(1.0, |m| mask_at(m, f.width, col, row, u, v));
        let albedo = match self.albedo {
            Albedo::Ramp { zmin, zmax } => {
                let t = if zmax > zmin {
                    (p[2] - zmin) / (zmax - zmin)
                } else {
                    0.0
                };
                let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
                ctx.ramp[(t * LUT as f64 + 0.5) as usize]
            }
            Albedo::Drape(img) => img.sample(p[0], p[1], f.width, f.height),
        };
        let ndotl = n.dot(l).max(0.0);
        let view = -d;
        let refl = n * (2.0 * n.dot(l)) - l;
        let spec = if ndotl > 0.0 {
            SPECULAR * refl.dot(view).max(0.0).powi(SHININESS)
        } else {
            0.0
        };
        let ambient = AMBIENT * (0.6 + 0.4 * n.z.abs());
        let k = ambient + DIFFUSE * ndotl * lit;
        albedo * k + DVec3::splat(spec * lit)
    }

    /// The frame as 8-bit sRGB, row-major from the top (parallel over rows):
    /// each pixel's hit shaded, or the sky where its ray misses.
    pub fn image(&self, frame: &CameraFrame, hits: &[Option<TerrainHit>]) -> Vec<u8> {
        let (w, h) = (frame.camera.width as usize, frame.camera.height as usize);
        let ctx = Tables {
            gamma: Gamma::new(),
            ramp: ramp_table(),
        };
        let mut rgb = vec![0u8; w * h * 3];
        rgb.par_chunks_mut(w * 3).enumerate().for_each(|(y, line)| {
            for x in 0..w {
                let d = DVec3::from_array(frame.direction(x as u32, y as u32));
                let c = match &hits[y * w + x] {
                    Some(hit) => self.shade_hit(&ctx, frame, d, hit),
                    None => sky(d),
                };
                for k in 0..3 {
                    line[3 * x + k] = ctx.gamma.to_u8(c[k]);
                }
            }
        });
        rgb
    }
}

/// Steps per ray (cells + nodes) as a heat map, linear from 0 to the
/// largest; returns the 8-bit RGB pixels and that largest count. It shows
/// where a caster works hardest (the per-pixel cost picture of PAPERS.md 004).
pub fn heatmap(steps: &[Steps]) -> (Vec<u8>, u32) {
    let max = steps.iter().map(|s| s.cells + s.nodes).max().unwrap_or(0);
    (heatmap_scaled(steps, max), max)
}

/// Steps per ray as a heat map, linear from 0 to `max` (so several maps can
/// share one scale, e.g. to compare casters); 8-bit RGB pixels.
pub fn heatmap_scaled(steps: &[Steps], max: u32) -> Vec<u8> {
    steps
        .par_iter()
        .flat_map_iter(|s| {
            let t = if max > 0 {
                (s.cells + s.nodes) as f64 / max as f64
            } else {
                0.0
            };
            ramp(&HEAT, t)
                .to_array()
                .map(|c| (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Dem;

    #[test]
    fn normals_follow_the_declared_triangles() {
        // Cell heights: (0,0)=0, (1,0)=1, (0,1)=0, (1,1)=1 -> a plane rising
        // east by 1 per 2 m (sx = 2): both triangles give the same normal.
        let mut dem = Dem::from_heights(2, 2, vec![0.0, 1.0, 0.0, 1.0]);
        dem.georef.pixel_width = 2.0;
        let f = HeightField::new(&dem).unwrap();
        let n_up = triangle_normal(&f, 0, 0, 0.7, 0.2);
        let n_lo = triangle_normal(&f, 0, 0, 0.2, 0.7);
        // The plane z = x / 2 has the normal (−1/2, 0, 1) / |(−1/2, 0, 1)|.
        let len = (0.25f64 + 1.0).sqrt();
        let expect = [-0.5 / len, 0.0, 1.0 / len];
        for k in 0..3 {
            assert!((n_up[k] - expect[k]).abs() < 1e-12);
            assert!((n_lo[k] - expect[k]).abs() < 1e-12);
        }
        // Only (1,1) raised: the upper triangle tilts south-ish (it holds
        // (1,0) and (1,1); its height rises towards the south row), the
        // lower one holds (0,1) and (1,1) and rises east.
        let dem = Dem::from_heights(2, 2, vec![0.0, 0.0, 0.0, 1.0]);
        let f = HeightField::new(&dem).unwrap();
        let up = triangle_normal(&f, 0, 0, 0.9, 0.1);
        let lo = triangle_normal(&f, 0, 0, 0.1, 0.9);
        // Upper: z = v (rises south, i.e. towards −y): normal points north (+y).
        assert!(up[1] > 0.5 && up[0].abs() < 1e-12);
        // Lower: z = u (rises east): normal points west (−x).
        assert!(lo[0] < -0.5 && lo[1].abs() < 1e-12);
    }

    #[test]
    fn ramp_ends_and_heatmap_scale() {
        assert_eq!(ramp(&RAMP, -1.0), RAMP[0].1);
        assert_eq!(ramp(&RAMP, 2.0), RAMP[6].1);
        let steps = [Steps { cells: 0, nodes: 0 }, Steps { cells: 3, nodes: 1 }];
        let (rgb, max) = heatmap(&steps);
        assert_eq!(max, 4);
        assert_eq!(rgb.len(), 6);
        assert_ne!(rgb[0..3], rgb[3..6]);
    }

    #[test]
    fn sky_is_brighter_at_the_horizon_than_at_the_zenith_in_red() {
        assert!(sky(DVec3::Y).x > sky(DVec3::Z).x);
        // At the horizon, the zenith and the nadir the gradient is its end colours.
        for (d, c) in [(DVec3::Y, HORIZON), (DVec3::Z, ZENITH), (-DVec3::Z, NADIR)] {
            assert!((sky(d) - c).abs().max_element() < 1e-12, "{d}");
        }
    }

    #[test]
    fn gamma_table_matches_the_power_law() {
        // The table against linear^(1/2.2) computed directly: within one
        // step of 8 bits (the table samples √linear).
        let g = Gamma::new();
        for i in 0..=1000 {
            let lin = i as f64 / 1000.0;
            let exact = lin.powf(1.0 / 2.2) * 255.0;
            assert!(
                (g.to_u8(lin) as f64 - exact).abs() <= 1.0,
                "linear {lin}: {} vs {exact}",
                g.to_u8(lin)
            );
        }
    }

    #[test]
    fn drape_samples_bilinearly_in_linear_light() {
        // A 2 × 1 image (black, white) over a 2 × 1 grid: grid point 0 sits
        // on the black pixel's centre, grid point 1 on the white one's, and
        // half-way the mean of the two linear values (0 and 1).
        let d = Drape::new(2, 1, &[0, 0, 0, 255, 255, 255]);
        assert_eq!(d.sample(0.0, 0.0, 2, 1), DVec3::ZERO);
        assert_eq!(d.sample(1.0, 0.0, 2, 1), DVec3::ONE);
        let mid = d.sample(0.5, 0.0, 2, 1);
        assert!((mid - DVec3::splat(0.5)).abs().max_element() < 1e-6);
    }
}
