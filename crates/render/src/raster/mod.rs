//! CPU rasterization of primary visibility (paper 001): filled in by the rasterizer work.
