//! Culling judges a model scaled by a power of two so that the largest
//! side of its box is at least 1. Multiplying `f32` coordinates by a power
//! of two that does not overflow is exact, so the scaled model is the same
//! geometry; but the ray tests' products of coordinates (a determinant is
//! a product of three) fall to the bottom of `f32`'s range on a model a
//! few picometres across, and the rays mode found every triangle of such
//! a model hidden.
//! Models of ordinary size are used as they are.

use raykit_core::TriangleMesh;
use std::borrow::Cow;

/// A mesh at unit scale, with the factor it was scaled by.
pub struct UnitScale<'a> {
    /// The mesh scaled ([`at_unit_scale`]).
    pub mesh: Cow<'a, TriangleMesh>,
    /// The factor, `f.0 * f.1`, as two powers of two that are each finite
    /// in `f32` (the product may not be).
    factor: (f32, f32),
}

impl UnitScale<'_> {
    /// A length measured on the scaled mesh, in the model's units.
    pub fn to_model(&self, length: f32) -> f32 {
        length / self.factor.0 / self.factor.1
    }
}

/// `mesh` scaled by `2^k` (`k ≥ 1`) so that the largest side of its box
/// lies in `[1, 2)`, or `mesh` itself when that side is at least 1, zero
/// or not finite, or the mesh fails [`TriangleMesh::validate`].
pub fn at_unit_scale(mesh: &TriangleMesh) -> UnitScale<'_> {
    let side = match mesh.validate() {
        Ok(()) => {
            let b = mesh.bounds();
            (b.max - b.min).max_element()
        }
        Err(_) => 0.0,
    };
    if !(side > 0.0 && side < 1.0 && side.is_finite()) {
        return UnitScale {
            mesh: Cow::Borrowed(mesh),
            factor: (1.0, 1.0),
        };
    }
    // The exponent that brings `side` into [1, 2): f32 sides are at least
    // 2^-149, so it is at most 149, applied in two steps that are each a
    // finite power of two.
    let k = -(side as f64).log2().floor() as i32;
    let k = if side as f64 * 2f64.powi(k) < 1.0 {
        k + 1
    } else {
        k
    };
    let factor = (2f32.powi(k / 2), 2f32.powi(k - k / 2));
    let mut scaled = mesh.clone();
    for p in &mut scaled.positions {
        *p = *p * factor.0 * factor.1;
    }
    UnitScale {
        mesh: Cow::Owned(scaled),
        factor,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::Vec3;

    fn side_of(mesh: &TriangleMesh) -> f32 {
        let b = mesh.bounds();
        (b.max - b.min).max_element()
    }

    #[test]
    fn tiny_models_come_to_unit_size_exactly() {
        for e in [1, 10, 40, 100, 126, 140] {
            let s = 2f64.powi(-e) as f32 * 1.5;
            let tris = [
                [Vec3::ZERO, Vec3::X * s, Vec3::Y * s * 0.3],
                [Vec3::Z * s * 0.7, Vec3::X * s, Vec3::Y * s],
            ];
            let mesh = TriangleMesh::from_triangles(&tris);
            let unit = at_unit_scale(&mesh);
            let scaled = &unit.mesh;
            assert_eq!(unit.to_model(side_of(scaled)), side_of(&mesh), "2^-{e}");
            let side = {
                let b = scaled.bounds();
                (b.max - b.min).max_element()
            };
            assert!((1.0..2.0).contains(&side), "2^-{e}: side {side}");
            // Exact: every coordinate divided back gives the original, in f64.
            let f = side as f64 / s as f64;
            for (p, q) in mesh.positions.iter().zip(&scaled.positions) {
                for k in 0..3 {
                    assert_eq!(q[k] as f64, p[k] as f64 * f, "2^-{e}");
                }
            }
        }
        let unit = TriangleMesh::from_triangles(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]);
        assert!(matches!(at_unit_scale(&unit).mesh, Cow::Borrowed(_)));
    }
}
