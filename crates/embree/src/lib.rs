//! Embree (Wald, Woop, Benthin, Johnson & Ernst 2014, "Embree: a kernel
//! framework for efficient CPU ray tracing") as a yardstick for raykit's
//! acceleration structures: the same triangle mesh built into an Embree
//! scene, answering the same rays through raykit-core's [`Accel`] trait and
//! through Embree's own batch APIs, so a benchmark or a test can check that
//! the answers agree and compare speeds. Never the engine itself.
//!
//! Two versions, each behind a cargo feature of its own, both off by
//! default:
//! - `embree3`: Embree 3 from Debian's `libembree-dev`, declared by hand
//!   and linked as `-lembree3` (`Embree3Device`, `Embree3Scene`).
//! - `embree4`: Embree 4, found and loaded at run time with libloading
//!   (`Embree4`, `Embree4Device`, `Embree4Scene`), e.g. the
//!   `libembree4` of the PyPI wheel `embreex`; building needs neither its
//!   headers nor its library.
//!
//! The features are off by default because the crate is a workspace
//! member: `cargo build` and `cargo test --workspace` build every member,
//! and an unconditional `-lembree3` would make them fail on a machine
//! without `libembree-dev`. Without features the crate holds only the
//! shared [`Quality`]. The root package's `embree` feature turns both on,
//! and so does `--all-features`, which CI uses with `libembree-dev`
//! installed and `embreex` in its Python.
//!
//! [`Accel`]: raykit_core::Accel

#[cfg(feature = "embree3")]
mod embree3;
#[cfg(feature = "embree4")]
mod embree4;
#[cfg(feature = "embree3")]
mod ffi3;
#[cfg(feature = "embree4")]
mod ffi4;
#[cfg(feature = "embree4")]
mod library4;
#[cfg(any(feature = "embree3", feature = "embree4"))]
mod mesh_scene;
#[cfg(any(feature = "embree3", feature = "embree4"))]
mod rtcore;

#[cfg(feature = "embree3")]
pub use embree3::{Embree3Device, Embree3Scene};
#[cfg(feature = "embree4")]
pub use embree4::{Embree4Device, Embree4Scene, QueryApi};
#[cfg(feature = "embree4")]
pub use library4::{Embree4, LIBRARY_ENV, PYTHON_ENV};

/// Embree's build quality, the same setting in both versions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// `RTC_BUILD_QUALITY_MEDIUM`: the default fast build.
    Medium,
    /// `RTC_BUILD_QUALITY_HIGH`: with spatial splits.
    High,
}

/// Environment variable with extra settings for Embree's device
/// configuration string, e.g. `isa=avx2` or `verbose=1`, for experiments.
pub const CONFIG_ENV: &str = "RAYKIT_EMBREE_CONFIG";
