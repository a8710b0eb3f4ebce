//! The leaves of the wide BVHs and their per-ray test, written
//! once for both kinds: Embree-style packs of four Möller triangles
//! ([`Tri4Leaves`], Wald et al. 2014's `triangle4`) or one triangle after
//! the other for the other tests. Used by [`super::Bvh4`] and [`super::Bvh8`].

use super::build::{BuildOptions, BuildQuality};
use super::tri4::{Ray4, Tri4Leaves};
use crate::accel::leaf::LeafTriangles;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::tri::TriangleTest;

/// The leaves of a wide BVH: packs of four for [`crate::tri::Moller`],
/// single triangles for the other tests.
pub(crate) enum Leaves<T: TriangleTest> {
    /// One triangle after the other; leaf references are triangle ranges.
    Single(LeafTriangles<T>),
    /// Packs of four; leaf references start at their first pack.
    Packed(Tri4Leaves),
}

/// A leaf test for one ray, so that traversal is written once for both kinds
/// of leaves (a trait rather than a closure, to force it inline).
pub(crate) trait LeafTest {
    /// Test the leaf `first`, `count` (see [`Tri4Leaves::test`]): the
    /// nearest hit goes to `best` and shrinks `tfar`; true for an any-hit
    /// query's hit.
    fn test<const ANY: bool>(
        &self,
        first: usize,
        count: usize,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool;

    /// Start fetching the leaf `first`, `count` (a hint; the one-triangle
    /// leaves do nothing).
    #[inline(always)]
    fn prefetch(&self, _first: usize, _count: usize) {}

    /// Whether an any-hit walk's leaf test still goes through every pack
    /// of a leaf (a walk to every crossing), so that every pack is fetched
    /// in that walk's order too, not only the first.
    const EVERY_PACK: bool = false;
}

impl<L: LeafTest> LeafTest for &L {
    #[inline(always)]
    fn test<const ANY: bool>(
        &self,
        first: usize,
        count: usize,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        (**self).test::<ANY>(first, count, tfar, best)
    }

    #[inline(always)]
    fn prefetch(&self, first: usize, count: usize) {
        (**self).prefetch(first, count)
    }

    const EVERY_PACK: bool = L::EVERY_PACK;
}

/// [`LeafTest`] over packs of four.
pub(crate) struct PackedLeaf<'a> {
    pub packs: &'a Tri4Leaves,
    pub ray: &'a Ray,
    pub r4: Ray4,
}

impl LeafTest for PackedLeaf<'_> {
    #[inline(always)]
    fn prefetch(&self, first: usize, count: usize) {
        // Every pack asked for (any-hit queries ask for the first only,
        // `prefetch::prefetch_with`): on incoherent rays 1.07-1.15x faster
        // on the scatter than the first pack alone, the dragon and the
        // terrain within the noise (BENCHMARKS.md).
        for k in 0..count.div_ceil(4) {
            super::prefetch::prefetch_pack(self.packs.packs(), first + k);
        }
    }

    #[inline(always)]
    fn test<const ANY: bool>(
        &self,
        first: usize,
        count: usize,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.packs
            .test::<ANY>(first, count, self.ray, &self.r4, tfar, best)
    }
}

/// [`LeafTest`] one triangle at a time.
pub(crate) struct SingleLeaf<'a, T: TriangleTest> {
    pub tris: &'a LeafTriangles<T>,
    pub ray: &'a Ray,
    pub rd: T::RayData,
}

impl<T: TriangleTest> LeafTest for SingleLeaf<'_, T> {
    #[inline(always)]
    fn test<const ANY: bool>(
        &self,
        first: usize,
        count: usize,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        self.tris
            .test::<ANY>(first, count, self.ray, &self.rd, tfar, best)
    }
}

/// The build options of a wide BVH: over packs of four (`packed`) the SAH
/// counts a leaf's pack tests (`leaf_block` 4, as Embree's builders for
/// `triangle4`), leaves hold up to [`BuildOptions::packed_leaf_size`]
/// triangles and [`BuildQuality::High`] fills every node
/// ([`BuildOptions::fill_wide_nodes`]); one-triangle leaves keep the
/// caller's options.
pub(crate) fn wide_build_options(options: &BuildOptions, packed: bool) -> BuildOptions {
    if packed {
        BuildOptions {
            leaf_block: 4,
            max_leaf_size: options.packed_leaf_size,
            fill_wide_nodes: options.quality == BuildQuality::High,
            ..options.clone()
        }
    } else {
        options.clone()
    }
}
