//! The regular grid of sample points around the model (Min 2008, first stage).

use raykit_core::{Aabb, Vec3};

/// Fraction of a cell by which the grid is shifted off the model's bounding
/// box, beyond the one-cell margin. CAD models have many axis-aligned faces
/// at round coordinates; an irrational-looking offset keeps grid planes from
/// coinciding with them (an axis ray lying in a face's plane would slip
/// through it, Min's (2008) depth buffer has the same blind spot).
pub const GRID_OFFSET: f32 = 0.381_966;

/// A regular grid of points around a model's bounding box (Min (2008), §
/// "directed distance field": the grid on which distances are stored).
///
/// Point `[i, j, k]` lies at `origin + spacing · (i, j, k)`. The grid keeps a
/// margin of `1 + GRID_OFFSET` cells below the box and at least one cell
/// above it on every axis, so every boundary point is outside the model and
/// front propagation can start there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// Position of point `[0, 0, 0]`.
    pub origin: Vec3,
    /// Distance between neighbouring points (the same on every axis).
    pub spacing: f32,
    /// Points per axis.
    pub dims: [usize; 3],
}

impl Grid {
    /// Fewest points along the longest axis: margins take 4, so 5 leaves one
    /// cell across the model.
    pub const MIN_RESOLUTION: usize = 5;
    /// Most points along the longest axis: point indices stay below 2³² and
    /// the two bytes per point (free steps, tags) below 2 GiB.
    pub const MAX_RESOLUTION: usize = 1024;

    /// The grid with `resolution` points along the longest axis of `bounds`
    /// (Min's (2008) grid size N), clamped to
    /// `[MIN_RESOLUTION, MAX_RESOLUTION]`. An empty or non-finite box gives a
    /// grid around the origin; a flat box a grid a few points thick.
    pub fn around(bounds: &Aabb, resolution: usize) -> Grid {
        let n = resolution.clamp(Self::MIN_RESOLUTION, Self::MAX_RESOLUTION);
        let ok = !bounds.is_empty() && bounds.min.is_finite() && bounds.max.is_finite();
        let (min, extent) = if ok {
            (bounds.min, bounds.extent())
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        let longest = extent.max_element();
        // The longest axis spans n - 1 cells: n - 4 over the box, 2 + offset
        // of margin, and the rest (under one cell) above.
        let mut spacing = longest / (n - 4) as f32;
        if !(spacing.is_finite() && spacing > 0.0) {
            spacing = if longest > 0.0 { longest } else { 1.0 };
        }
        let dims = extent.to_array().map(|e| {
            let cells = (e / spacing + 2.0 + GRID_OFFSET).ceil() as usize;
            (cells + 1).clamp(4, n)
        });
        Grid {
            origin: min - Vec3::splat(spacing * (1.0 + GRID_OFFSET)),
            spacing,
            dims,
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// True when the grid has no points (never, for a grid from [`Grid::around`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Distance in the point array between neighbours along `axis`.
    #[inline]
    pub fn stride(&self, axis: usize) -> usize {
        match axis {
            0 => 1,
            1 => self.dims[0],
            _ => self.dims[0] * self.dims[1],
        }
    }

    /// Linear index of point `c` (x fastest).
    #[inline]
    pub fn index(&self, c: [usize; 3]) -> usize {
        c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])
    }

    /// Coordinates of the point with linear index `idx`.
    #[inline]
    pub fn coords(&self, idx: usize) -> [usize; 3] {
        let (nx, ny) = (self.dims[0], self.dims[1]);
        [idx % nx, (idx / nx) % ny, idx / (nx * ny)]
    }

    /// Position of point `c`.
    #[inline]
    pub fn point(&self, c: [usize; 3]) -> Vec3 {
        self.origin + self.spacing * Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)
    }

    /// True for points on the grid's outer boundary (outside the model by
    /// construction: the seeds of front propagation).
    #[inline]
    pub fn is_boundary(&self, c: [usize; 3]) -> bool {
        (0..3).any(|a| c[a] == 0 || c[a] + 1 == self.dims[a])
    }

    /// The two axes other than `axis`, in cyclic order.
    #[inline]
    pub fn cross_axes(axis: usize) -> (usize, usize) {
        ((axis + 1) % 3, (axis + 2) % 3)
    }

    /// Number of grid lines parallel to `axis`.
    pub fn lines(&self, axis: usize) -> usize {
        let (b, c) = Self::cross_axes(axis);
        self.dims[b] * self.dims[c]
    }

    /// Coordinates of point `i` on line `line` parallel to `axis` (lines are
    /// numbered with the first cross axis fastest).
    #[inline]
    pub fn line_point(&self, axis: usize, line: usize, i: usize) -> [usize; 3] {
        let (b, c) = Self::cross_axes(axis);
        let mut p = [0; 3];
        p[axis] = i;
        p[b] = line % self.dims[b];
        p[c] = line / self.dims[b];
        p
    }

    /// Number of the line parallel to `axis` through point `p`.
    #[inline]
    pub fn line_of(&self, axis: usize, p: [usize; 3]) -> usize {
        let (b, c) = Self::cross_axes(axis);
        p[b] + self.dims[b] * p[c]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn margins_hold_on_every_side() {
        let b = Aabb::new(Vec3::new(-1.0, 2.0, 0.0), Vec3::new(3.0, 2.5, 1.0));
        for n in [0, 5, 6, 17, 64, 100] {
            let g = Grid::around(&b, n);
            assert_eq!(g.dims[0], n.max(5));
            for a in 0..3 {
                let lo = g.origin[a];
                let hi = g.origin[a] + g.spacing * (g.dims[a] - 1) as f32;
                assert!(lo <= b.min[a] - g.spacing, "{n} {a}");
                assert!(hi >= b.max[a] + g.spacing * 0.999, "{n} {a} {hi}");
            }
        }
    }

    #[test]
    fn index_coords_and_lines_round_trip() {
        let g = Grid::around(&Aabb::new(Vec3::ZERO, Vec3::new(1.0, 0.5, 0.25)), 12);
        for idx in 0..g.len() {
            let c = g.coords(idx);
            assert_eq!(g.index(c), idx);
            for a in 0..3 {
                let line = g.line_of(a, c);
                assert_eq!(g.line_point(a, line, c[a]), c);
            }
        }
    }

    #[test]
    fn degenerate_boxes_give_small_valid_grids() {
        for b in [
            Aabb::EMPTY,
            Aabb::new(Vec3::ONE, Vec3::ONE),
            Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)),
        ] {
            let g = Grid::around(&b, 32);
            assert!(g.spacing > 0.0 && g.spacing.is_finite());
            assert!(g.dims.iter().all(|&d| (4..=32).contains(&d)), "{g:?}");
        }
    }
}
