//! A terrain image or fly-through as `raykit terrain render` makes it: the
//! light (sun or point light above the ground), the exact shadow mask (Min
//! 2008), the surface colour (height ramp or draped orthophoto) and the
//! cameras (given, default, or along a path), then per frame a cast by any
//! caster and Phong shading on the declared surface.

use crate::camera::{centre, default_camera, path_cameras, EyeTarget, TerrainCamera};
use crate::dem::Dem;
use crate::georef::{format_number, MapWorld};
use crate::heightfield::HeightField;
use crate::pyramid::MaxMipmap;
use crate::shade::{heatmap, Albedo, Drape, Shading};
use crate::shadow::{light_above_ground, shadow_mask, Light, ShadowMethod};
use crate::view::CastImage;
use std::path::PathBuf;
use std::time::Instant;

/// The sun of a render given neither a sun nor a point light: azimuth 135°,
/// elevation 35°.
pub const DEFAULT_SUN: [f64; 2] = [135.0, 35.0];

/// What to render, in map coordinates; the error messages name each field
/// by its command-line flag (`--eye`, `--light`, ...).
#[derive(Clone, Debug, Default)]
pub struct TerrainRenderOptions {
    /// Camera position (map X, Y, height Z); `None`: the default view.
    pub eye: Option<[f64; 3]>,
    /// Point looked at; `None`: the surface at the DEM's centre.
    pub target: Option<[f64; 3]>,
    /// Fly-through eye positions (at least two); overrides eye and target.
    pub path: Option<Vec<[f64; 3]>>,
    /// Frames of the fly-through.
    pub frames: u32,
    /// Sun azimuth and elevation, degrees ([`DEFAULT_SUN`] when neither
    /// this nor `light` is given).
    pub sun: Option<[f64; 2]>,
    /// Point light: map X, Y and height above the ground there.
    pub light: Option<[f64; 3]>,
    /// Whether the shadow mask darkens the shading.
    pub shadows: bool,
    /// Orthophoto (an RGB image file) stretched over the DEM.
    pub drape: Option<PathBuf>,
}

/// The light, shadow mask, colours and cameras of a render, ready for
/// its frames.
pub struct TerrainRender<'a> {
    /// The surface.
    pub field: &'a HeightField,
    /// Map ↔ world coordinates of the DEM.
    pub geo: MapWorld<'a>,
    /// The light.
    pub light: Light,
    /// Per grid point 1 = lit (`None`: shadows off).
    pub mask: Option<Vec<u8>>,
    /// Seconds the shadow mask took.
    pub mask_seconds: f64,
    /// The draped image, if any.
    pub drape: Option<Drape>,
    /// Eye and target of each frame, world metres.
    pub cameras: Vec<EyeTarget>,
}

/// Figures of the frames of a render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameTimes {
    /// Seconds of each frame's cast.
    pub cast: Vec<f64>,
    /// Seconds of each frame's shading.
    pub shade: Vec<f64>,
    /// Seconds spent writing, all frames together.
    pub write: f64,
    /// Fewest and most boxes a frame used (the quadtree-box caster).
    pub boxes: (usize, usize),
    /// Most steps of a ray over the heat maps made (0 without them).
    pub steps_max: u32,
    /// Seconds from the first cast to the last write.
    pub wall: f64,
}

/// One frame's images.
pub struct RenderedFrame {
    /// The shaded image, 8-bit sRGB, row-major from the top.
    pub rgb: Vec<u8>,
    /// The steps-per-ray heat map and its maximum, when asked for.
    pub heat: Option<(Vec<u8>, u32)>,
}

impl<'a> TerrainRender<'a> {
    /// The light, mask, drape and cameras for `options` on `field` (built
    /// from `dem`) and its `pyramid`. Fails when a position is outside the
    /// DEM or a camera is degenerate, naming the flag.
    pub fn new(
        dem: &'a Dem,
        field: &'a HeightField,
        pyramid: &MaxMipmap,
        options: &TerrainRenderOptions,
    ) -> Result<TerrainRender<'a>, String> {
        let geo = MapWorld::new(dem, field);
        let light = light(dem, &geo, field, options)?;
        let (mask, mask_seconds) = if options.shadows {
            let start = Instant::now();
            let m = shadow_mask(field, pyramid, &light, ShadowMethod::Fast);
            (Some(m), start.elapsed().as_secs_f64())
        } else {
            (None, 0.0)
        };
        let drape = match &options.drape {
            Some(p) => {
                let img = image::open(p)
                    .map_err(|e| {
                        // The error and each of its causes, as a chain.
                        let mut message =
                            format!("--drape {}: cannot read the image: {e}", p.display());
                        let mut cause = std::error::Error::source(&e);
                        while let Some(c) = cause {
                            message += &format!(": {c}");
                            cause = c.source();
                        }
                        message
                    })?
                    .to_rgb8();
                Some(Drape::new(img.width(), img.height(), img.as_raw()))
            }
            None => None,
        };
        let cameras = cameras(&geo, field, options)?;
        Ok(TerrainRender {
            field,
            geo,
            light,
            mask,
            mask_seconds,
            drape,
            cameras,
        })
    }

    /// The shading of every frame.
    pub fn shading(&self) -> Shading<'_> {
        let albedo = match &self.drape {
            Some(d) => Albedo::Drape(d),
            None => Albedo::Ramp {
                zmin: self.field.zmin as f64,
                zmax: self.field.zmax as f64,
            },
        };
        Shading {
            field: self.field,
            light: self.light,
            mask: self.mask.as_deref(),
            albedo,
        }
    }

    /// Shade the cast of `camera` (parallel over rows), and its heat map
    /// when `heat` is set.
    pub fn shade(&self, camera: &TerrainCamera, cast: &CastImage, heat: bool) -> RenderedFrame {
        let rgb = self.shading().image(&camera.frame(), &cast.hits);
        RenderedFrame {
            rgb,
            heat: heat.then(|| heatmap(&cast.steps)),
        }
    }

    /// Every frame at `width` × `height` pixels and `vfov_deg`: cast by
    /// `cast`, shaded (with its heat map when `heat` is set), and handed to
    /// `write` with its index; `progress` gets the frames done and the
    /// seconds so far after each. The first error of `cast` or `write` ends
    /// the render.
    #[allow(clippy::too_many_arguments)]
    pub fn render_frames(
        &self,
        width: u32,
        height: u32,
        vfov_deg: f64,
        heat: bool,
        cast: &dyn Fn(&TerrainCamera) -> Result<CastImage, String>,
        write: &mut dyn FnMut(usize, &RenderedFrame) -> Result<(), String>,
        progress: &dyn Fn(usize, f64),
    ) -> Result<FrameTimes, String> {
        let mut times = FrameTimes {
            boxes: (usize::MAX, 0),
            ..Default::default()
        };
        let wall = Instant::now();
        for (i, &(eye, target)) in self.cameras.iter().enumerate() {
            let camera = TerrainCamera {
                eye,
                target,
                vfov_deg,
                width,
                height,
            };
            let start = Instant::now();
            let image = cast(&camera)?;
            times.cast.push(start.elapsed().as_secs_f64());
            let start = Instant::now();
            let frame = self.shade(&camera, &image, heat);
            times.shade.push(start.elapsed().as_secs_f64());
            let start = Instant::now();
            write(i, &frame)?;
            times.write += start.elapsed().as_secs_f64();
            if let Some((_, max)) = &frame.heat {
                times.steps_max = times.steps_max.max(*max);
            }
            times.boxes = (
                times.boxes.0.min(image.boxes),
                times.boxes.1.max(image.boxes),
            );
            progress(i + 1, wall.elapsed().as_secs_f64());
        }
        times.wall = wall.elapsed().as_secs_f64();
        Ok(times)
    }

    /// The light in words: "sun 135°/35°" or "point light at 812.0 m".
    pub fn light_text(&self) -> String {
        match self.light {
            Light::Sun {
                azimuth_deg,
                elevation_deg,
            } => format!("sun {azimuth_deg}°/{elevation_deg}°"),
            Light::Point(p) => format!("point light at {:.1} m", p[2]),
        }
    }
}

/// The point light above the ground, or the sun. A point light over
/// `dem`'s no-data cells is refused: the ground under it is unknown.
fn light(
    dem: &Dem,
    geo: &MapWorld<'_>,
    field: &HeightField,
    options: &TerrainRenderOptions,
) -> Result<Light, String> {
    Ok(match options.light {
        Some(l) => {
            let w = geo.to_world([l[0], l[1], 0.0]);
            let p = light_above_ground(field, w[0], w[1], l[2]).ok_or_else(|| {
                format!(
                    "--light {},{}: outside the DEM; expected map coordinates within {}",
                    format_number(l[0]),
                    format_number(l[1]),
                    geo.describe_extent()
                )
            })?;
            let (gx, gy) = (w[0] / field.sx, -w[1] / field.sy);
            let no_ground = field.samples_under(gx, gy).find(|&(c, r)| {
                dem.heights
                    .get(r * dem.width + c)
                    .is_some_and(|h| h.is_nan())
            });
            if let Some((col, row)) = no_ground {
                return Err(format!(
                    "--light {},{}: the ground there has no data (no height at row {row}, column {col})",
                    format_number(l[0]),
                    format_number(l[1]),
                ));
            }
            Light::Point(p)
        }
        None => {
            let [az, el] = options.sun.unwrap_or(DEFAULT_SUN);
            Light::Sun {
                azimuth_deg: az,
                elevation_deg: el,
            }
        }
    })
}

/// Eye and target of every frame, world metres.
fn cameras(
    geo: &MapWorld<'_>,
    field: &HeightField,
    options: &TerrainRenderOptions,
) -> Result<Vec<EyeTarget>, String> {
    let (_, _, diag) = geo.extent();
    if let Some(points) = &options.path {
        let world = points
            .iter()
            .enumerate()
            .map(|(i, p)| geo.check(&format!("--path (point {})", i + 1), *p, true))
            .collect::<Result<Vec<_>, _>>()?;
        return path_cameras(&world, options.frames, diag).map_err(|e| format!("--path: {e}"));
    }
    let (def_eye, def_target) = default_camera(field);
    let eye = match options.eye {
        Some(e) => geo.check("--eye", e, true)?,
        None => def_eye,
    };
    let target = match options.target {
        Some(t) => geo.check("--target", t, false)?,
        None if options.eye.is_some() => centre(field),
        None => def_target,
    };
    let d = [target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]];
    if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() <= 1e-9 * diag.max(1.0) {
        return Err(
            "--target must differ from --eye (the camera needs a direction to look in)".into(),
        );
    }
    Ok(vec![(eye, target)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fractal::fractal;
    use crate::view::{cast_image, Caster};

    #[test]
    fn frames_shade_the_cast_with_the_mask_of_the_light() {
        let dem = fractal(33, 3, 0.55);
        let field = HeightField::new(&dem).unwrap();
        let pyramid = MaxMipmap::new(&field);
        let options = TerrainRenderOptions {
            shadows: true,
            frames: 1,
            ..Default::default()
        };
        let job = TerrainRender::new(&dem, &field, &pyramid, &options).unwrap();
        // The mask is the library's mask for the default sun.
        let sun = Light::Sun {
            azimuth_deg: DEFAULT_SUN[0],
            elevation_deg: DEFAULT_SUN[1],
        };
        let mask = shadow_mask(&field, &pyramid, &sun, ShadowMethod::BruteForce);
        assert_eq!(job.mask.as_deref(), Some(&mask[..]));
        // The default view is the camera module's.
        assert_eq!(job.cameras, vec![default_camera(&field)]);
        let (eye, target) = job.cameras[0];
        let camera = TerrainCamera {
            eye,
            target,
            vfov_deg: 50.0,
            width: 24,
            height: 16,
        };
        let cast = cast_image(&field, &pyramid, &camera, Caster::March);
        let frame = job.shade(&camera, &cast, true);
        let direct = Shading {
            field: &field,
            light: sun,
            mask: Some(&mask),
            albedo: Albedo::Ramp {
                zmin: field.zmin as f64,
                zmax: field.zmax as f64,
            },
        }
        .image(&camera.frame(), &cast.hits);
        assert_eq!(frame.rgb, direct);
        assert_eq!(frame.heat, Some(heatmap(&cast.steps)));
    }

    #[test]
    fn positions_outside_the_dem_name_their_flag() {
        let dem = fractal(17, 1, 0.55);
        let field = HeightField::new(&dem).unwrap();
        let pyramid = MaxMipmap::new(&field);
        let options = TerrainRenderOptions {
            light: Some([-1e7, -1e7, 10.0]),
            ..Default::default()
        };
        let err = TerrainRender::new(&dem, &field, &pyramid, &options)
            .err()
            .unwrap();
        assert!(err.starts_with("--light "), "{err}");
    }
}
