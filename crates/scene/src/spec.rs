//! The `NAME:key=value,...` specification parser behind `--scene`: builds a
//! built-in scene of [`crate::BUILTINS`] from its keys.

use crate::builtins::BUILTINS;
use crate::error::SceneError;
use crate::{cornell, scatter, shirley6, terrain, Scene};

/// Seed used when a specification gives none.
pub const DEFAULT_SEED: u64 = 1;

/// Largest `triangles` accepted (the meshes need about 40 bytes a triangle).
pub const MAX_TRIANGLES: u64 = 50_000_000;

/// Build a built-in scene from a specification `NAME` or
/// `NAME:key=value,key=value` (keys: `seed` for every scene, `triangles` for
/// `terrain` and `scatter`; integers may contain `_`).
///
/// ```
/// let s = raykit_scene::builtin("terrain:triangles=2000,seed=7").unwrap();
/// assert_eq!(s.mesh.num_triangles(), 2 * 32 * 32);
/// assert!(raykit_scene::builtin("teapot").is_err());
/// ```
pub fn builtin(spec: &str) -> Result<Scene, SceneError> {
    let (name, params) = match spec.split_once(':') {
        Some((n, p)) => (n.trim(), p),
        None => (spec.trim(), ""),
    };
    let info = BUILTINS
        .iter()
        .find(|b| b.name == name)
        .ok_or_else(|| SceneError::UnknownScene { name: name.into() })?;
    let mut seed = None;
    let mut triangles = None;
    for param in params.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (key, value) = param
            .split_once('=')
            .map(|(k, v)| (k.trim(), v.trim()))
            .ok_or_else(|| SceneError::Malformed {
                param: param.into(),
            })?;
        let slot = match key {
            "seed" if info.keys.contains(&"seed") => &mut seed,
            "triangles" if info.keys.contains(&"triangles") => &mut triangles,
            _ => {
                return Err(SceneError::UnknownKey {
                    scene: info.name,
                    key: key.into(),
                    valid: info.keys,
                })
            }
        };
        if slot.is_some() {
            return Err(SceneError::DuplicateKey { key: key.into() });
        }
        *slot = Some(parse_u64(key, value)?);
    }
    let seed = seed.unwrap_or(DEFAULT_SEED);
    let triangles = |default: u64, min: u64| match triangles {
        None => Ok(default as usize),
        Some(t) if (min..=MAX_TRIANGLES).contains(&t) => Ok(t as usize),
        Some(t) => Err(SceneError::OutOfRange {
            key: "triangles".into(),
            value: t,
            min,
            max: MAX_TRIANGLES,
        }),
    };
    Ok(match info.name {
        "cornell" => cornell::cornell(seed),
        "whitted" => cornell::whitted(seed),
        "shirley6" => shirley6::shirley6(seed),
        "terrain" => terrain::terrain(
            seed,
            triangles(
                terrain::DEFAULT_TRIANGLES as u64,
                terrain::MIN_TRIANGLES as u64,
            )?,
        ),
        _ => scatter::scatter(
            seed,
            triangles(
                scatter::DEFAULT_TRIANGLES as u64,
                scatter::MIN_TRIANGLES as u64,
            )?,
        ),
    })
}

fn parse_u64(key: &str, value: &str) -> Result<u64, SceneError> {
    let digits: String = value.chars().filter(|&c| c != '_').collect();
    if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_digit()) {
        return Err(SceneError::BadValue {
            key: key.into(),
            value: value.into(),
        });
    }
    digits.parse().map_err(|_| SceneError::BadValue {
        key: key.into(),
        value: value.into(),
    })
}
