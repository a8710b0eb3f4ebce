//! Light specifications as written on a command line or in a config:
//! point, directional and spot lights (`--light` of `raykit render`).

use anyhow::{bail, Context, Result};
use raykit_core::{Light, PointLight, Vec3, MAX_CAMERA_COORDINATE};

/// Help text for `--light`.
pub const LIGHT_HELP: &str = "Light, repeatable: `X,Y,Z[:R,G,B]` or `point:X,Y,Z[:R,G,B]` (a point \
light; the colour is its irradiance at the scene centre), `dir:DX,DY,DZ[:R,G,B]` (a directional \
light travelling along D, colour = irradiance), `spot:X,Y,Z:TX,TY,TZ:ANGLE[:R,G,B]` (a spot at X \
aimed at T with an outer half-angle in degrees, colour = irradiance at T). Replaces the scene's lights.";

/// The three numbers of `x,y,z`, each checked by `ok`.
fn three<T: std::str::FromStr + Copy>(s: &str, ok: impl Fn(T) -> bool) -> Result<[T; 3], String> {
    let v: Vec<T> = s
        .split(',')
        .map(|c| c.trim().parse::<T>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected three numbers x,y,z, got '{s}'"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|&c| ok(c)) => Ok([x, y, z]),
        _ => Err(format!("expected three finite numbers x,y,z, got '{s}'")),
    }
}

/// Parse `x,y,z`.
pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    three(s, f32::is_finite).map(Vec3::from_array)
}

/// Parse `x,y,z` in `f64` (a camera position in a far model's
/// coordinates, where `f32` steps are too coarse), each within `f32`'s
/// range.
pub fn parse_dvec3(s: &str) -> Result<raykit_core::glam::DVec3, String> {
    three(s, |c: f64| c.is_finite() && c.abs() <= f32::MAX as f64)
        .map(raykit_core::glam::DVec3::from_array)
}

fn vec3(s: &str, what: &str) -> Result<Vec3> {
    parse_vec3(s)
        .map_err(anyhow::Error::msg)
        .with_context(|| what.to_string())
}

/// Why `position` cannot place a light, if it cannot: a coordinate beyond
/// ±[`MAX_CAMERA_COORDINATE`], the bound on camera coordinates (beyond it
/// the light's intensity, irradiance × distance², overflows f32).
pub fn light_position_problem(position: Vec3) -> Option<String> {
    (!position.is_finite() || position.abs().max_element() > MAX_CAMERA_COORDINATE).then(|| {
        format!(
            "the position {position} is beyond ±{MAX_CAMERA_COORDINATE:e}, the bound on camera \
             and light coordinates"
        )
    })
}

/// Closest a point light may be to the scene centre, where its colour is
/// the irradiance: at the centre itself that irradiance is undefined.
pub const MIN_LIGHT_TO_CENTRE: f32 = 1e-6;

/// A point light at `position` giving irradiance `colour` at `centre`, or
/// why not: a position beyond [`light_position_problem`]'s bound, one at
/// the centre (within [`MIN_LIGHT_TO_CENTRE`]), where irradiance is
/// undefined, or a colour so bright at that distance that the intensity
/// overflows f32.
pub fn point_light(position: Vec3, colour: Vec3, centre: Vec3) -> Result<Light, String> {
    if let Some(p) = light_position_problem(position) {
        return Err(p);
    }
    let d = position.distance(centre);
    if d < MIN_LIGHT_TO_CENTRE {
        return Err(format!(
            "the point light at {position} is at the scene centre {centre}, where its colour (the \
             irradiance it gives there) is undefined; move it off the centre, or use a spot \
             light (colour = irradiance at its target)"
        ));
    }
    let light = PointLight::with_irradiance_at(position, colour, d);
    if !light.intensity.is_finite() {
        return Err(format!(
            "the colour {colour} at {d:e} from the scene centre gives an intensity beyond f32"
        ));
    }
    Ok(light.into())
}

fn position(s: &str) -> Result<Vec3> {
    let p = vec3(s, "the position X,Y,Z")?;
    match light_position_problem(p) {
        Some(problem) => bail!("{problem}"),
        None => Ok(p),
    }
}

fn colour(s: Option<&&str>) -> Result<Vec3> {
    let c = match s {
        Some(c) => vec3(c, "the colour R,G,B")?,
        None => Vec3::ONE,
    };
    if c.min_element() < 0.0 {
        bail!("the colour must not be negative, got {c}");
    }
    Ok(c)
}

/// Parse one `--light` value; `centre` is the scene centre.
pub fn parse_light(spec: &str, centre: Vec3) -> Result<Light> {
    let parts: Vec<&str> = spec.split(':').collect();
    let (kind, rest) = match parts[0] {
        "point" | "dir" | "spot" => (parts[0], &parts[1..]),
        _ => ("point", &parts[..]),
    };
    match kind {
        "point" => {
            if rest.is_empty() || rest.len() > 2 {
                bail!("expected X,Y,Z[:R,G,B]");
            }
            let p = vec3(rest[0], "the position X,Y,Z")?;
            let c = colour(rest.get(1))?;
            point_light(p, c, centre).map_err(anyhow::Error::msg)
        }
        "dir" => {
            if rest.is_empty() || rest.len() > 2 {
                bail!("expected dir:DX,DY,DZ[:R,G,B]");
            }
            let d = vec3(rest[0], "the direction DX,DY,DZ")?;
            if d.length_squared() == 0.0 {
                bail!("the direction must not be zero");
            }
            Ok(Light::Directional {
                direction: d.normalize(),
                irradiance: colour(rest.get(1))?,
            })
        }
        _ => {
            if rest.len() < 3 || rest.len() > 4 {
                bail!("expected spot:X,Y,Z:TX,TY,TZ:ANGLE[:R,G,B]");
            }
            let p = position(rest[0])?;
            let t = vec3(rest[1], "the target TX,TY,TZ")?;
            if let Some(problem) = light_position_problem(t) {
                bail!("the target: {problem}");
            }
            let angle: f32 = rest[2]
                .trim()
                .parse()
                .ok()
                .filter(|a: &f32| *a > 0.0 && *a < 90.0)
                .with_context(|| {
                    format!(
                        "the angle must be between 0 and 90 degrees, got '{}'",
                        rest[2]
                    )
                })?;
            if p.distance(t) == 0.0 {
                bail!("the spot's position and target must differ");
            }
            let c = colour(rest.get(3))?;
            let d = p.distance(t);
            let intensity = c * d * d;
            if !intensity.is_finite() {
                bail!("the colour {c} at {d:e} from the target gives an intensity beyond f32");
            }
            Ok(Light::Spot {
                position: p,
                direction: (t - p).normalize(),
                intensity,
                cos_inner: (0.8 * angle).to_radians().cos(),
                cos_outer: angle.to_radians().cos(),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_specs_give_the_asked_irradiance() {
        let centre = Vec3::new(0.0, 1.0, 0.0);
        for spec in ["0,5,0", "point:0,5,0:1,1,1"] {
            let l = parse_light(spec, centre).unwrap();
            assert!(
                (l.toward(centre).irradiance - Vec3::ONE).length() < 1e-5,
                "{spec}"
            );
        }
        let l = parse_light("dir:0,-2,0:0.5,0.5,0.5", centre).unwrap();
        let s = l.toward(Vec3::ZERO);
        assert_eq!((s.to_light, s.irradiance), (Vec3::Y, Vec3::splat(0.5)));
        let l = parse_light("spot:0,5,0:0,0,0:30:2,2,2", centre).unwrap();
        assert!((l.toward(Vec3::ZERO).irradiance - Vec3::splat(2.0)).length() < 1e-4);
        assert_eq!(l.toward(Vec3::new(10.0, 0.0, 0.0)).irradiance, Vec3::ZERO);
        for bad in [
            "",
            "1,2",
            "dir:0,0,0",
            "spot:0,1,0:0,0,0:95",
            "point:1,2,3:-1,0,0",
            "spot:1,1,1",
            "point:0,1,0",
        ] {
            assert!(parse_light(bad, centre).is_err(), "{bad}");
        }
        // Just off the centre the colour is still the irradiance there.
        let l = parse_light("point:0,1.001,0:1,1,1", centre).unwrap();
        assert!((l.toward(centre).irradiance - Vec3::ONE).length() < 1e-3);
    }
}
