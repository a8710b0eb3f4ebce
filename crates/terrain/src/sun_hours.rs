//! Hours of direct sun per grid point over a day: the shadow mask of the
//! sun at evenly spaced times while it is above the horizon, summed.

use crate::heightfield::HeightField;
use crate::pyramid::MaxMipmap;
use crate::shadow::{shadow_mask_for_targets, Light, ShadowMethod};
use crate::sun::sun_position;

/// Where and when: a UTC day and a place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunDay {
    /// Day of the year, 1 = 1 January.
    pub day: u32,
    /// Latitude, degrees north.
    pub lat: f64,
    /// Longitude, degrees east.
    pub lon: f64,
    /// Hours between sun positions.
    pub step_hours: f64,
}

/// Hours of sun per grid point.
#[derive(Clone, Debug, PartialEq)]
pub struct SunHours {
    /// Per grid point (row-major), hours of direct sun; NaN without data.
    pub hours: Vec<f32>,
    /// Sun positions above the horizon that were cast.
    pub positions: usize,
    /// Hours of daylight: positions × step.
    pub day_hours: f64,
}

impl SunDay {
    /// The UTC times (hours, the middle of each step) at which the sun is
    /// above the horizon.
    pub fn times(&self) -> Vec<f64> {
        (0..)
            .map(|k| (k as f64 + 0.5) * self.step_hours)
            .take_while(|&t| t < 24.0)
            .filter(|&t| sun_position(self.day, t, self.lat, self.lon).1 > 0.0)
            .collect()
    }
}

/// Hours of direct sun on `field` over `day` for targets `target_height`
/// metres above the ground: each position's mask counts one step where lit.
/// Grid points with `nodata` set get NaN. `progress` is called after each
/// sun position.
pub fn sun_hours(
    field: &HeightField,
    pyramid: &MaxMipmap,
    method: ShadowMethod,
    target_height: f64,
    day: &SunDay,
    nodata: &[bool],
    progress: &dyn Fn(),
) -> SunHours {
    let times = day.times();
    let step = day.step_hours;
    let mut hours = vec![0.0f32; field.width * field.height];
    for &t in &times {
        let (az, el) = sun_position(day.day, t, day.lat, day.lon);
        let light = Light::Sun {
            azimuth_deg: az,
            elevation_deg: el,
        };
        let mask =
            shadow_mask_for_targets(field, Some(pyramid), &light, method, target_height, &|_| {});
        for (h, &m) in hours.iter_mut().zip(&mask) {
            *h += m as f32 * step as f32;
        }
        progress();
    }
    for (h, &nd) in hours.iter_mut().zip(nodata) {
        if nd {
            *h = f32::NAN;
        }
    }
    SunHours {
        hours,
        positions: times.len(),
        day_hours: times.len() as f64 * step,
    }
}

impl SunHours {
    /// The most hours of sun on one grid point (0 when none has data).
    pub fn max(&self) -> f32 {
        self.hours
            .iter()
            .copied()
            .filter(|h| !h.is_nan())
            .fold(0.0f32, f32::max)
    }

    /// A preview image (RGB, row-major): dark blue for no sun to light
    /// yellow for sun all day, magenta without data.
    pub fn preview(&self) -> Vec<u8> {
        let day_len = self.day_hours;
        self.hours
            .iter()
            .flat_map(|&h| {
                if h.is_nan() {
                    return [255, 0, 255];
                }
                let f = if day_len > 0.0 {
                    (h as f64 / day_len).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                [
                    (30.0 + 225.0 * f) as u8,
                    (30.0 + 200.0 * f) as u8,
                    (80.0 + 60.0 * f) as u8,
                ]
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::Dem;

    #[test]
    fn a_flat_dem_sees_the_sun_all_day() {
        // On a flat DEM nothing casts a shadow: every point gets the whole
        // day's daylight, counted here from the sun's position directly.
        let dem = Dem::from_heights(5, 4, vec![100.0; 20]);
        let field = HeightField::new(&dem).unwrap();
        let pyramid = MaxMipmap::new(&field);
        let day = SunDay {
            day: 172,
            lat: 45.0,
            lon: 10.0,
            step_hours: 0.5,
        };
        let mut nodata = vec![false; 20];
        nodata[3] = true;
        let hours = sun_hours(
            &field,
            &pyramid,
            ShadowMethod::Fast,
            0.0,
            &day,
            &nodata,
            &|| {},
        );
        let above = (0..48)
            .filter(|k| sun_position(172, (*k as f64 + 0.5) * 0.5, 45.0, 10.0).1 > 0.0)
            .count();
        assert_eq!(hours.positions, above);
        for (i, h) in hours.hours.iter().enumerate() {
            if i == 3 {
                assert!(h.is_nan());
            } else {
                assert!((*h as f64 - above as f64 * 0.5).abs() < 1e-4);
            }
        }
        assert_eq!(hours.preview()[9..12], [255, 0, 255]);
    }
}
