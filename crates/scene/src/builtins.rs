//! The catalogue of built-in scenes: names, descriptions and the keys each
//! specification takes.

/// One built-in scene: name, one-line description and the keys it takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuiltinInfo {
    /// Name used in specifications.
    pub name: &'static str,
    /// One line for `--help`.
    pub description: &'static str,
    /// Keys accepted after `NAME:`.
    pub keys: &'static [&'static str],
}

/// Names of the built-in scenes, in the order of [`BUILTINS`].
pub const BUILTIN_NAMES: &[&str] = &["cornell", "whitted", "shirley6", "terrain", "scatter"];

/// The built-in scenes with their descriptions and keys.
pub const BUILTINS: &[BuiltinInfo] = &[
    BuiltinInfo {
        name: "cornell",
        description: "Cornell box with a tall box, a short box and a smooth sphere, one light (1314 triangles)",
        keys: &["seed"],
    },
    BuiltinInfo {
        name: "whitted",
        description: "the Cornell box with a mirror tall box and a glass sphere (1314 triangles)",
        keys: &["seed"],
    },
    BuiltinInfo {
        name: "shirley6",
        description: "after Shirley's test scene 6 of the stack kd-tree GPU tracer: checkered ground, spheres and boxes (804 triangles)",
        keys: &["seed"],
    },
    BuiltinInfo {
        name: "terrain",
        description: "fBm noise terrain on an n x n grid, 2n^2 ~ triangles (default 200000), far sun",
        keys: &["seed", "triangles"],
    },
    BuiltinInfo {
        name: "scatter",
        description: "randomly rotated, stretched 80-triangle icospheres in a box (default 500000 triangles)",
        keys: &["seed", "triangles"],
    },
];

/// The one-line description of built-in scene `name`.
pub fn description(name: &str) -> Option<&'static str> {
    BUILTINS
        .iter()
        .find(|b| b.name == name)
        .map(|b| b.description)
}
