//! Names of the run-time choices (structures, triangle tests, ray sets,
//! build qualities): `Display` writes a choice's name and `FromStr` reads it
//! back, with an error that lists the choices, so every front end (the CLI,
//! the Python package, configuration files) spells them the same way.

use std::fmt;

/// A name that is none of a choice's names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownName {
    /// What was being named, e.g. "structure".
    pub what: &'static str,
    /// The name given.
    pub given: String,
    /// The names that would have been accepted.
    pub choices: Vec<&'static str>,
}

impl fmt::Display for UnknownName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown {} {:?} (choose from {})",
            self.what,
            self.given,
            self.choices.join(", ")
        )
    }
}

impl std::error::Error for UnknownName {}

/// Implements `Display` (the name) and `FromStr` (the name back, or
/// [`UnknownName`]) for a `Copy` enum with `ALL` and `name(self)`.
macro_rules! named_choice {
    ($ty:ty, $what:literal) => {
        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl ::std::str::FromStr for $ty {
            type Err = $crate::names::UnknownName;

            fn from_str(s: &str) -> Result<Self, Self::Err> {
                <$ty>::ALL
                    .into_iter()
                    .find(|k| k.name() == s)
                    .ok_or_else(|| $crate::names::UnknownName {
                        what: $what,
                        given: s.to_string(),
                        choices: <$ty>::ALL.iter().map(|k| k.name()).collect(),
                    })
            }
        }
    };
}
pub(crate) use named_choice;
