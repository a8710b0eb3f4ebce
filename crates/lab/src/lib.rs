//! raykit's measurement harness: the published experiments reproduced on
//! this machine (`raykit experiment`), the engine benchmarks (`raykit
//! bench`) and the comparisons with other engines (`raykit bench --compare
//! embree`), with the timing, plotting and checking they share. The
//! `raykit` command line parses arguments and calls in here; every result
//! is checked against an independent answer (brute force, f64, a second
//! structure) as it is measured.

#![warn(missing_docs)]

pub mod args;
pub mod bench;
pub mod experiment;
pub mod gpu_measure;
pub mod measure;
pub mod one_ray;
pub mod plot;
