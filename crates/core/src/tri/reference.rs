//! Placeholder for the f64 reference test.
