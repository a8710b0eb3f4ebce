//! Shading for `raykit terrain render`: Phong on the declared surface's hit
//! triangle, the shadow mask, a hypsometric colour ramp or a draped image,
//! the sky, and the steps-per-ray heat map.

use raykit_terrain::camera::CameraFrame;
use raykit_terrain::heightfield::{HeightField, Steps, TerrainHit};
use raykit_terrain::shadow::Light;
use rayon::prelude::*;

/// Linear RGB.
type Rgb = [f64; 3];

/// Ambient, diffuse and specular weights and the Phong exponent.
const AMBIENT: f64 = 0.22;
const DIFFUSE: f64 = 0.85;
const SPECULAR: f64 = 0.12;
const SHININESS: i32 = 24;

/// Sky colours (linear): straight up, at the horizon, straight down.
const ZENITH: Rgb = [0.20, 0.38, 0.78];
const HORIZON: Rgb = [0.72, 0.80, 0.90];
const NADIR: Rgb = [0.55, 0.60, 0.66];

/// Hypsometric tints (sRGB, 0..1) at normalised heights 0..1.
const RAMP: [(f64, Rgb); 7] = [
    (0.00, [0.16, 0.40, 0.20]),
    (0.15, [0.33, 0.55, 0.27]),
    (0.35, [0.63, 0.66, 0.38]),
    (0.55, [0.60, 0.47, 0.31]),
    (0.72, [0.46, 0.36, 0.28]),
    (0.87, [0.62, 0.61, 0.60]),
    (1.00, [0.98, 0.98, 0.98]),
];

/// Heat-map colours (sRGB, 0..1) from zero to the most steps.
const HEAT: [(f64, Rgb); 5] = [
    (0.00, [0.00, 0.00, 0.02]),
    (0.25, [0.26, 0.04, 0.45]),
    (0.50, [0.73, 0.19, 0.33]),
    (0.75, [0.98, 0.55, 0.04]),
    (1.00, [0.99, 1.00, 0.80]),
];

/// An orthophoto stretched over the DEM's extent (pixel-is-area: its left
/// edge is the left edge of the DEM's first pixel, i.e. grid column −0.5).
pub struct Drape {
    width: usize,
    height: usize,
    /// Linear RGB per pixel, row-major from the top (north).
    rgb: Vec<[f32; 3]>,
}

impl Drape {
    /// From 8-bit sRGB pixels.
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
        let p = |x: usize, y: usize| self.rgb[y * self.width + x];
        let mut out = [0.0; 3];
        for (k, o) in out.iter_mut().enumerate() {
            let top = p(x0, y0)[k] as f64 * (1.0 - ax) + p(x1, y0)[k] as f64 * ax;
            let bottom = p(x0, y1)[k] as f64 * (1.0 - ax) + p(x1, y1)[k] as f64 * ax;
            *o = top * (1.0 - ay) + bottom * ay;
        }
        out
    }
}

/// Where the surface colour comes from.
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

/// Everything the shading of one frame reads.
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

fn lerp3(a: Rgb, b: Rgb, t: f64) -> Rgb {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

fn dot(a: Rgb, b: Rgb) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(a: Rgb) -> Rgb {
    let l = dot(a, a).sqrt();
    if l > 0.0 {
        [a[0] / l, a[1] / l, a[2] / l]
    } else {
        [0.0, 0.0, 1.0]
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

/// The sky seen along unit world direction `d` (z up).
pub fn sky(d: Rgb) -> Rgb {
    let z = d[2].clamp(-1.0, 1.0);
    if z >= 0.0 {
        lerp3(HORIZON, ZENITH, z.sqrt())
    } else {
        lerp3(HORIZON, NADIR, (-z).sqrt())
    }
}

/// The hit triangle's unit normal in world metres, from the hit's position
/// (`u`, `v`) in cell (`col`, `row`): the upper triangle ((c, r), (c+1, r),
/// (c+1, r+1)) where u ≥ v, the lower one ((c, r), (c+1, r+1), (c, r+1))
/// otherwise, as `heightfield.rs` declares them.
pub fn triangle_normal(field: &HeightField, col: usize, row: usize, u: f64, v: f64) -> Rgb {
    // z = z0 + du·u + dv·v with u = x / sx, v = −y / sy.
    let p = field.cell_plane(col, row, u >= v);
    let (dzdx, dzdy) = (p.du / field.sx, -p.dv / field.sy);
    normalize([-dzdx, -dzdy, 1.0])
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
    fn shade_hit(&self, ctx: &Tables, frame: &CameraFrame, d: Rgb, hit: &TerrainHit) -> Rgb {
        let f = self.field;
        let ray = f.grid_ray(frame.camera.eye, d);
        let p = ray.at(hit.t);
        let (col, row) = (hit.col as usize, hit.row as usize);
        let u = (p[0] - col as f64).clamp(0.0, 1.0);
        let v = (p[1] - row as f64).clamp(0.0, 1.0);
        let mut n = triangle_normal(f, col, row, u, v);
        if dot(n, d) > 0.0 {
            n = [-n[0], -n[1], -n[2]]; // seen from below
        }
        let world = [p[0] * f.sx, -p[1] * f.sy, p[2]];
        let l = match self.light {
            Light::Sun {
                azimuth_deg,
                elevation_deg,
            } => Light::sun_direction(azimuth_deg, elevation_deg),
            Light::Point(q) => normalize([q[0] - world[0], q[1] - world[1], q[2] - world[2]]),
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
        let ndotl = dot(n, l).max(0.0);
        let view = [-d[0], -d[1], -d[2]];
        let refl = [
            2.0 * dot(n, l) * n[0] - l[0],
            2.0 * dot(n, l) * n[1] - l[1],
            2.0 * dot(n, l) * n[2] - l[2],
        ];
        let spec = if ndotl > 0.0 {
            SPECULAR * dot(refl, view).max(0.0).powi(SHININESS)
        } else {
            0.0
        };
        let ambient = AMBIENT * (0.6 + 0.4 * n[2].abs());
        let k = ambient + DIFFUSE * ndotl * lit;
        [
            albedo[0] * k + spec * lit,
            albedo[1] * k + spec * lit,
            albedo[2] * k + spec * lit,
        ]
    }

    /// The frame as 8-bit sRGB, row-major from the top (parallel over rows).
    pub fn image(&self, frame: &CameraFrame, hits: &[Option<TerrainHit>]) -> Vec<u8> {
        let (w, h) = (frame.camera.width as usize, frame.camera.height as usize);
        let ctx = Tables {
            gamma: Gamma::new(),
            ramp: ramp_table(),
        };
        let mut rgb = vec![0u8; w * h * 3];
        rgb.par_chunks_mut(w * 3).enumerate().for_each(|(y, line)| {
            for x in 0..w {
                let d = frame.direction(x as u32, y as u32);
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
/// largest; returns the 8-bit RGB pixels and that largest count.
pub fn heatmap(steps: &[Steps]) -> (Vec<u8>, u32) {
    let max = steps.iter().map(|s| s.cells + s.nodes).max().unwrap_or(0);
    (heatmap_scaled(steps, max), max)
}

/// Steps per ray as a heat map, linear from 0 to `max` (so several maps can
/// share one scale); 8-bit RGB pixels.
pub fn heatmap_scaled(steps: &[Steps], max: u32) -> Vec<u8> {
    steps
        .par_iter()
        .flat_map_iter(|s| {
            let t = if max > 0 {
                (s.cells + s.nodes) as f64 / max as f64
            } else {
                0.0
            };
            ramp(&HEAT, t).map(|c| (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_terrain::Dem;

    #[test]
    fn normals_follow_the_declared_triangles() {
        // Cell heights: (0,0)=0, (1,0)=1, (0,1)=0, (1,1)=1 -> a plane rising
        // east by 1 per 2 m (sx = 2): both triangles give the same normal.
        let mut dem = Dem::from_heights(2, 2, vec![0.0, 1.0, 0.0, 1.0]);
        dem.georef.pixel_width = 2.0;
        let f = HeightField::new(&dem).unwrap();
        let n_up = triangle_normal(&f, 0, 0, 0.7, 0.2);
        let n_lo = triangle_normal(&f, 0, 0, 0.2, 0.7);
        let expect = normalize([-0.5, 0.0, 1.0]);
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
        assert!(sky([0.0, 1.0, 0.0])[0] > sky([0.0, 0.0, 1.0])[0]);
    }
}
