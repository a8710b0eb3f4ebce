//! Shadow maps (paper 001): filled in by the shadow-map work.
