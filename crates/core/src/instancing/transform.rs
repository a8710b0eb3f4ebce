//! An instance's affine transform with the inverse that takes rays into
//! object space and the matrix that takes normals back to world space.

use crate::aabb::Aabb;
use crate::ray::Ray;
use glam::{Affine3A, DAffine3, Mat3A, Vec3};
use std::fmt;

/// Why a transform was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TransformError {
    /// An entry is NaN or infinite.
    NotFinite,
    /// The linear part is singular, or so nearly that its inverse is not
    /// finite or its columns are dependent to within rounding: `determinant`
    /// is its determinant, `relative` the determinant over the product of
    /// the columns' lengths (1 for a rotation times any scale, 0 when
    /// singular).
    NotInvertible {
        /// Determinant of the linear part (computed in `f64`).
        determinant: f64,
        /// Determinant over the product of the column lengths.
        relative: f64,
    },
}

impl fmt::Display for TransformError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TransformError::NotFinite => write!(f, "the transform has a NaN or infinite entry"),
            TransformError::NotInvertible {
                determinant,
                relative,
            } => write!(
                f,
                "the transform is not invertible (determinant {determinant:e}, \
                 {relative:e} relative to its column lengths)"
            ),
        }
    }
}

/// Columns whose determinant is below this fraction of the product of their
/// lengths are dependent to within `f32` rounding (a column rounded once
/// moves by about `1e-7` of its length).
const MIN_RELATIVE_DETERMINANT: f64 = 1e-9;

/// A checked affine transform from object space to world space: the
/// forward map, its inverse (computed in `f64` and rounded once, so that a
/// ray taken into object space carries one rounding per entry), and the
/// normal matrix.
///
/// Rays are transformed, not normalised: the object-space direction is the
/// inverse's linear part applied to the world direction, so a hit at `t`
/// in object space is the point at the same `t` on the world ray and
/// distances of different instances compare directly (as pbrt-v4's
/// `TransformedPrimitive` and Embree's instances do).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceTransform {
    to_world: Affine3A,
    to_object: Affine3A,
    /// Inverse transpose of the linear part: takes an object-space face
    /// normal to the world-space normal of the same side.
    normal: Mat3A,
}

impl InstanceTransform {
    /// Check `to_world` and precompute its inverse; refused when an entry
    /// is not finite or the linear part is (numerically) singular.
    pub fn new(to_world: Affine3A) -> Result<Self, TransformError> {
        let cols = to_world.to_cols_array();
        if !cols.iter().all(|c| c.is_finite()) {
            return Err(TransformError::NotFinite);
        }
        let d = DAffine3::from_cols_array(&cols.map(f64::from));
        let det = d.matrix3.determinant();
        let lengths =
            d.matrix3.x_axis.length() * d.matrix3.y_axis.length() * d.matrix3.z_axis.length();
        let relative = if lengths > 0.0 { det / lengths } else { 0.0 };
        let singular = TransformError::NotInvertible {
            determinant: det,
            relative,
        };
        if det == 0.0 || !det.is_finite() || relative.abs() < MIN_RELATIVE_DETERMINANT {
            return Err(singular);
        }
        let inv = d.inverse();
        let to_object = Affine3A::from_cols_array(&inv.to_cols_array().map(|c| c as f32));
        if !to_object.to_cols_array().iter().all(|c| c.is_finite()) {
            return Err(singular);
        }
        let normal = inv.matrix3.transpose();
        let normal = Mat3A::from_cols_array(&normal.to_cols_array().map(|c| c as f32));
        Ok(InstanceTransform {
            to_world,
            to_object,
            normal,
        })
    }

    /// The object-to-world transform.
    pub fn to_world(&self) -> Affine3A {
        self.to_world
    }

    /// The world-to-object transform.
    pub fn to_object(&self) -> Affine3A {
        self.to_object
    }

    /// `ray` in object space over `[ray.tnear, tfar]`, the direction
    /// transformed without normalising (so `t` keeps its meaning).
    #[inline]
    pub fn object_ray(&self, ray: &Ray, tfar: f32) -> Ray {
        Ray::segment(
            self.to_object.transform_point3(ray.origin),
            self.to_object.transform_vector3(ray.dir),
            ray.tnear,
            tfar,
        )
    }

    /// The world-space unit normal of the side of an object-space triangle
    /// whose normal is `face` (the inverse transpose applied). Under a
    /// mirroring transform the transformed corners wind the other way
    /// round that side, which stays the front: glTF's rule for nodes with a
    /// negative determinant, pbrt-v4's and Embree's normals of instances.
    #[inline]
    pub fn world_normal(&self, face: Vec3) -> Vec3 {
        (self.normal * face).normalize_or_zero()
    }

    /// A world-space box holding `object` transformed: the box of its eight
    /// corners mapped, widened by the rounding of that map.
    pub fn world_box(&self, object: &Aabb) -> Aabb {
        let b = Aabb::from_points(&object.corners().map(|c| self.to_world.transform_point3(c)));
        let scale = b.min.abs().max(b.max.abs()).max_element();
        let pad = Vec3::splat(8.0 * f32::EPSILON * scale);
        Aabb::new(b.min - pad, b.max + pad)
    }
}
