//! Vertices far from the coordinates' origin, read to their precision.
//!
//! Meshes store `f32`, which at projected coordinates (UTM northings are
//! millions of metres) is half a metre apart: a model there loses its
//! shape on loading. Text formats and `double` PLY properties carry more.
//! When asked, the loaders read such coordinates in `f64` and store them
//! relative to an origin taken from the first vertex, so the caller can
//! put them back in `f64` ([`crate::LoadedMesh::origin`]). The origin is a
//! multiple of the `f32` spacing there, so `f32` input moves exactly.

use raykit_core::glam::DVec3;
use raykit_core::{Vec3, MAX_COORDINATE};

/// A first vertex with a coordinate at least this large moves the origin
/// to it: `f32` is 1/128 apart there, a centimetre in metres.
pub(crate) const FAR: f64 = 65_536.0;

/// Places vertices relative to the origin chosen at the first one.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FarOrigin {
    /// Whether far coordinates move the origin at all.
    keep_precision: bool,
    /// The origin, once the first vertex chose it.
    origin: Option<DVec3>,
}

impl FarOrigin {
    /// A placement that moves the origin to a far first vertex when
    /// `keep_precision`, and otherwise keeps it at zero.
    pub(crate) fn new(keep_precision: bool) -> Self {
        FarOrigin {
            keep_precision,
            origin: None,
        }
    }

    /// Whether coordinates should be read as `f64` and passed to
    /// [`Self::place`]: when asked to keep precision, unless the first
    /// vertex was near enough to keep the origin at zero. Otherwise they
    /// are read as `f32`, as [`crate::load`] reads them.
    #[inline]
    pub(crate) fn keeps_precision(&self) -> bool {
        self.keep_precision && self.origin != Some(DVec3::ZERO)
    }

    /// `p` relative to the origin, as stored; the first call chooses the
    /// origin from `p`.
    #[inline]
    pub(crate) fn place(&mut self, p: [f64; 3]) -> Vec3 {
        let o = self.origin_for(p);
        Vec3::new(
            (p[0] - o.x) as f32,
            (p[1] - o.y) as f32,
            (p[2] - o.z) as f32,
        )
    }

    /// The origin, chosen from `p` unless a point before chose it.
    #[inline]
    pub(crate) fn origin_for(&mut self, p: [f64; 3]) -> DVec3 {
        let keep = self.keep_precision;
        *self
            .origin
            .get_or_insert_with(|| if keep { origin_near(p) } else { DVec3::ZERO })
    }

    /// The origin chosen (zero when none was needed).
    pub(crate) fn origin(&self) -> [f64; 3] {
        self.origin.unwrap_or(DVec3::ZERO).to_array()
    }
}

/// Why a vertex read as `read` and stored as `stored` cannot be held: a
/// stored coordinate that is not finite or lies beyond [`MAX_COORDINATE`]
/// (a finite `f64` may still overflow `f32`); `None` when it can.
pub(crate) fn out_of_range(read: [f64; 3], stored: Vec3) -> Option<String> {
    if stored.is_finite() && stored.abs().max_element() <= MAX_COORDINATE {
        return None;
    }
    // Each as briefly as it was read: an f32 one as an f32.
    let brief = |c: f64| match c as f32 {
        f if f64::from(f) == c => format!("{f:e}"),
        _ => format!("{c:e}"),
    };
    let [x, y, z] = read.map(brief);
    Some(format!(
        "vertex ({x}, {y}, {z}) lies beyond ±{MAX_COORDINATE:e} (from the first vertex's \
         origin when far coordinates keep their precision), where the f32 ray tests overflow; \
         move or scale the mesh"
    ))
}

/// The origin for a file whose first vertex is `p`: zero unless `p` is
/// finite with a coordinate of at least [`FAR`], else `p` rounded to a
/// multiple of the `f32` spacing at its largest coordinate (2⁻²³ times the
/// largest power of two not above it), which every `f32` coordinate of
/// that size or larger is a multiple of.
fn origin_near(p: [f64; 3]) -> DVec3 {
    let p = DVec3::from_array(p);
    let far = p.abs().max_element();
    if !p.is_finite() || far < FAR {
        return DVec3::ZERO;
    }
    let step = (2.0f64).powi(far.log2().floor() as i32 - 23);
    (p / step).round() * step
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f32 coordinates near a far first vertex move by the origin exactly
    /// (checked in f64), and near coordinates keep the origin at zero.
    #[test]
    fn f32_coordinates_near_the_first_vertex_move_exactly() {
        let first = [429_252.37_f32, 5_150_885.5, 312.25];
        let mut far = FarOrigin::new(true);
        let stored = far.place(first.map(f64::from));
        let o = far.origin();
        assert!(o[1] != 0.0 && (o[1] - 5_150_885.5).abs() <= 0.25);
        for k in 0..1000 {
            let q = first.map(|c| c + (k as f32 - 500.0) * 0.37);
            let s = far.place(q.map(f64::from));
            for a in 0..3 {
                assert_eq!(f64::from(s[a]) + o[a], f64::from(q[a]), "{q:?}");
            }
        }
        assert_eq!(stored.to_array().map(f64::from)[1] + o[1], 5_150_885.5);
        let mut near = FarOrigin::new(true);
        near.place([100.0, -2000.0, 3.0]);
        assert_eq!(near.origin(), [0.0; 3]);
        let mut off = FarOrigin::new(false);
        off.place([1e7, 1e7, 1e7]);
        assert_eq!(off.origin(), [0.0; 3]);
        let mut inf = FarOrigin::new(true);
        inf.place([f64::INFINITY, 0.0, 0.0]);
        assert_eq!(inf.origin(), [0.0; 3]);
    }
}
