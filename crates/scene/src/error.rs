//! Errors of [`crate::builtin`].

use crate::builtins::BUILTINS;
use std::fmt;

/// What is wrong with a built-in scene specification such as
/// `terrain:triangles=1000000,seed=3`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SceneError {
    /// No built-in scene has this name.
    UnknownScene {
        /// The name given.
        name: String,
    },
    /// The scene takes no such key.
    UnknownKey {
        /// The scene.
        scene: &'static str,
        /// The key given.
        key: String,
        /// The keys the scene takes.
        valid: &'static [&'static str],
    },
    /// A parameter is not of the form `key=value`.
    Malformed {
        /// The offending text.
        param: String,
    },
    /// A key appears twice.
    DuplicateKey {
        /// The key.
        key: String,
    },
    /// A value is not a non-negative integer.
    BadValue {
        /// The key.
        key: String,
        /// The value given.
        value: String,
    },
    /// A value is outside the accepted range.
    OutOfRange {
        /// The key.
        key: String,
        /// The value given.
        value: u64,
        /// Smallest accepted value.
        min: u64,
        /// Largest accepted value.
        max: u64,
    },
}

fn list(items: &[&str]) -> String {
    items.join(", ")
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SceneError::UnknownScene { name } => {
                if name.is_empty() {
                    write!(f, "no scene name given; built-in scenes:")?;
                } else {
                    write!(f, "unknown built-in scene `{name}`; built-in scenes:")?;
                }
                for b in BUILTINS {
                    write!(
                        f,
                        "\n  {:<9} {} (keys: {})",
                        b.name,
                        b.description,
                        list(b.keys)
                    )?;
                }
                Ok(())
            }
            SceneError::UnknownKey { scene, key, valid } => write!(
                f,
                "scene `{scene}` takes no key `{key}`; valid keys: {}",
                list(valid)
            ),
            SceneError::Malformed { param } => write!(
                f,
                "malformed scene parameter `{param}`: expected key=value (e.g. `cornell:seed=3`)"
            ),
            SceneError::DuplicateKey { key } => write!(f, "scene parameter `{key}` given twice"),
            SceneError::BadValue { key, value } => write!(
                f,
                "scene parameter `{key}`: `{value}` is not a non-negative integer"
            ),
            SceneError::OutOfRange {
                key,
                value,
                min,
                max,
            } => write!(
                f,
                "scene parameter `{key}` = {value} is out of range [{min}, {max}]"
            ),
        }
    }
}

impl std::error::Error for SceneError {}
