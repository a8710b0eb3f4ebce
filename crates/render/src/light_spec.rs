//! Light specifications as text: point, directional and spot lights, each
//! with a colour given as the irradiance it delivers at a reference point
//! (the scene centre, or the spot's target).

use raykit_core::{Light, PointLight, Vec3};

/// The syntax of a light specification, for help texts.
pub const LIGHT_SPEC_HELP: &str = "Light, repeatable: `X,Y,Z[:R,G,B]` or `point:X,Y,Z[:R,G,B]` (a point \
light; the colour is its irradiance at the scene centre), `dir:DX,DY,DZ[:R,G,B]` (a directional \
light travelling along D, colour = irradiance), `spot:X,Y,Z:TX,TY,TZ:ANGLE[:R,G,B]` (a spot at X \
aimed at T with an outer half-angle in degrees, colour = irradiance at T). Replaces the scene's lights.";

/// Parse `x,y,z`.
pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected three numbers x,y,z, got '{s}'"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => Err(format!("expected three finite numbers x,y,z, got '{s}'")),
    }
}

/// [`parse_vec3`], the error prefixed by `what` the numbers are.
fn vec3(s: &str, what: &str) -> Result<Vec3, String> {
    parse_vec3(s).map_err(|e| format!("{what}: {e}"))
}

/// An optional non-negative colour `R,G,B`, white when absent.
fn colour(s: Option<&&str>) -> Result<Vec3, String> {
    let c = match s {
        Some(c) => vec3(c, "the colour R,G,B")?,
        None => Vec3::ONE,
    };
    if c.min_element() < 0.0 {
        return Err(format!("the colour must not be negative, got {c}"));
    }
    Ok(c)
}

/// Parse one light specification (the syntax of [`LIGHT_SPEC_HELP`]);
/// `centre` is the scene centre, where a point light's colour is its
/// irradiance.
pub fn parse_light_spec(spec: &str, centre: Vec3) -> Result<Light, String> {
    let parts: Vec<&str> = spec.split(':').collect();
    let (kind, rest) = match parts[0] {
        "point" | "dir" | "spot" => (parts[0], &parts[1..]),
        _ => ("point", &parts[..]),
    };
    match kind {
        "point" => {
            if rest.is_empty() || rest.len() > 2 {
                return Err("expected X,Y,Z[:R,G,B]".into());
            }
            let p = vec3(rest[0], "the position X,Y,Z")?;
            let c = colour(rest.get(1))?;
            let d = p.distance(centre).max(1e-6);
            Ok(PointLight::with_irradiance_at(p, c, d).into())
        }
        "dir" => {
            if rest.is_empty() || rest.len() > 2 {
                return Err("expected dir:DX,DY,DZ[:R,G,B]".into());
            }
            let d = vec3(rest[0], "the direction DX,DY,DZ")?;
            if d.length_squared() == 0.0 {
                return Err("the direction must not be zero".into());
            }
            Ok(Light::Directional {
                direction: d.normalize(),
                irradiance: colour(rest.get(1))?,
            })
        }
        _ => {
            if rest.len() < 3 || rest.len() > 4 {
                return Err("expected spot:X,Y,Z:TX,TY,TZ:ANGLE[:R,G,B]".into());
            }
            let p = vec3(rest[0], "the position X,Y,Z")?;
            let t = vec3(rest[1], "the target TX,TY,TZ")?;
            let angle: f32 = rest[2]
                .trim()
                .parse()
                .ok()
                .filter(|a: &f32| *a > 0.0 && *a < 90.0)
                .ok_or_else(|| {
                    format!(
                        "the angle must be between 0 and 90 degrees, got '{}'",
                        rest[2]
                    )
                })?;
            if p.distance(t) == 0.0 {
                return Err("the spot's position and target must differ".into());
            }
            let c = colour(rest.get(3))?;
            let d = p.distance(t);
            Ok(Light::Spot {
                position: p,
                direction: (t - p).normalize(),
                intensity: c * d * d,
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
            let l = parse_light_spec(spec, centre).unwrap();
            assert!(
                (l.toward(centre).irradiance - Vec3::ONE).length() < 1e-5,
                "{spec}"
            );
        }
        let l = parse_light_spec("dir:0,-2,0:0.5,0.5,0.5", centre).unwrap();
        let s = l.toward(Vec3::ZERO);
        assert_eq!((s.to_light, s.irradiance), (Vec3::Y, Vec3::splat(0.5)));
        let l = parse_light_spec("spot:0,5,0:0,0,0:30:2,2,2", centre).unwrap();
        assert!((l.toward(Vec3::ZERO).irradiance - Vec3::splat(2.0)).length() < 1e-4);
        assert_eq!(l.toward(Vec3::new(10.0, 0.0, 0.0)).irradiance, Vec3::ZERO);
        for bad in [
            "",
            "1,2",
            "dir:0,0,0",
            "spot:0,1,0:0,0,0:95",
            "point:1,2,3:-1,0,0",
            "spot:1,1,1",
        ] {
            assert!(parse_light_spec(bad, centre).is_err(), "{bad}");
        }
    }
}
