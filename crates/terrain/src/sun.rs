//! Where the sun is: azimuth and elevation for a UTC time and a place, by
//! the NOAA solar calculator's formulas (Spencer's declination and equation
//! of time series; no refraction), good to a few tenths of a degree — ample
//! for hours of sunlight on a DEM.

/// Sun azimuth (degrees clockwise from north) and elevation (degrees above
/// the horizon) on day-of-year `day` (1 = 1 January) at `utc_hours` (0..24)
/// for latitude `lat` and longitude `lon` (degrees, east positive).
pub fn sun_position(day: u32, utc_hours: f64, lat: f64, lon: f64) -> (f64, f64) {
    use std::f64::consts::PI;
    let g = 2.0 * PI / 365.0 * (day as f64 - 1.0 + (utc_hours - 12.0) / 24.0);
    let eqtime = 229.18
        * (0.000075 + 0.001868 * g.cos()
            - 0.032077 * g.sin()
            - 0.014615 * (2.0 * g).cos()
            - 0.040849 * (2.0 * g).sin());
    let decl = 0.006918 - 0.399912 * g.cos() + 0.070257 * g.sin() - 0.006758 * (2.0 * g).cos()
        + 0.000907 * (2.0 * g).sin()
        - 0.002697 * (3.0 * g).cos()
        + 0.00148 * (3.0 * g).sin();
    let true_solar_minutes = utc_hours * 60.0 + eqtime + 4.0 * lon;
    let hour_angle = (true_solar_minutes / 4.0 - 180.0).to_radians();
    let phi = lat.to_radians();
    let cos_zenith =
        (phi.sin() * decl.sin() + phi.cos() * decl.cos() * hour_angle.cos()).clamp(-1.0, 1.0);
    let zenith = cos_zenith.acos();
    let elevation = 90.0 - zenith.to_degrees();
    // Azimuth clockwise from north.
    let az = (-(hour_angle.sin()) * decl.cos())
        .atan2(phi.cos() * decl.sin() - phi.sin() * decl.cos() * hour_angle.cos());
    ((az.to_degrees() + 360.0) % 360.0, elevation)
}

/// Day of year (1..=366) of a Gregorian date, or `None` if it is not a date.
pub fn day_of_year(year: i32, month: u32, day: u32) -> Option<u32> {
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    let days = [
        31,
        if leap { 29 } else { 28 },
        31,
        30,
        31,
        30,
        31,
        31,
        30,
        31,
        30,
        31,
    ];
    if !(1..=12).contains(&month) || day == 0 || day > days[month as usize - 1] {
        return None;
    }
    Some(days[..month as usize - 1].iter().sum::<u32>() + day)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noon_elevation_follows_latitude_and_declination() {
        // Around the June solstice at the Tropic of Cancer the sun is near the
        // zenith at local solar noon (12:00 UTC at longitude 0, give or take
        // the equation of time).
        let (_, el) = sun_position(172, 12.0, 23.44, 0.0);
        assert!(el > 88.5, "{el}");
        // Equinox, equator, 6 h after noon: on the horizon, due west.
        let (az, el) = sun_position(80, 18.0, 0.0, 0.0);
        assert!(el.abs() < 2.0 && (az - 270.0).abs() < 3.0, "{az} {el}");
        // Morning sun is in the east, afternoon sun in the west (Stockholm-ish).
        let (am, _) = sun_position(172, 6.0, 59.3, 18.0);
        let (pm, _) = sun_position(172, 16.0, 59.3, 18.0);
        assert!(am > 45.0 && am < 135.0, "{am}");
        assert!(pm > 225.0 && pm < 315.0, "{pm}");
        // Polar night: the sun never rises at 80° N in late December.
        assert!((0..24).all(|h| sun_position(355, h as f64, 80.0, 0.0).1 < 0.0));
    }

    #[test]
    fn days_of_year() {
        assert_eq!(day_of_year(2026, 1, 1), Some(1));
        assert_eq!(day_of_year(2026, 12, 31), Some(365));
        assert_eq!(day_of_year(2024, 12, 31), Some(366));
        assert_eq!(day_of_year(2026, 2, 29), None);
        assert_eq!(day_of_year(2026, 13, 1), None);
    }
}
