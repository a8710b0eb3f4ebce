//! Indexed triangle meshes in f32, with optional per-vertex normals and
//! texture coordinates, materials and parts (scene-graph nodes) per triangle.

use crate::aabb::Aabb;
use crate::texture::Texture;
use glam::{DVec3, Vec2, Vec3};
use std::fmt;
use std::sync::Arc;

/// A surface material as read from MTL or glTF, kept for the renderers.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name in the source file.
    pub name: String,
    /// Diffuse (base) colour, linear RGB.
    pub diffuse: [f32; 3],
    /// Specular colour, linear RGB.
    pub specular: [f32; 3],
    /// Phong exponent.
    pub shininess: f32,
    /// Mirror reflectance in [0, 1].
    pub reflectivity: f32,
    /// Transmission in [0, 1] (glass when 1).
    pub transmission: f32,
    /// Index of refraction.
    pub ior: f32,
    /// Emitted radiance, linear RGB.
    pub emission: [f32; 3],
    /// Diffuse texture path or URI, if any.
    pub diffuse_texture: Option<String>,
    /// The decoded base-colour texture (linear), multiplied into `diffuse`
    /// at the hit's texture coordinates, when the loader could read it.
    pub base_texture: Option<Arc<Texture>>,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            diffuse: [0.8, 0.8, 0.8],
            specular: [0.04, 0.04, 0.04],
            shininess: 32.0,
            reflectivity: 0.0,
            transmission: 0.0,
            ior: 1.5,
            emission: [0.0; 3],
            diffuse_texture: None,
            base_texture: None,
        }
    }
}

/// A named part of a mesh: a glTF node, an OBJ object/group, or the whole file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Part {
    /// Name in the source file (may be empty).
    pub name: String,
    /// glTF node index, when the part came from a glTF node.
    pub node: Option<u32>,
}

/// An indexed triangle mesh.
///
/// Invariants checked by [`TriangleMesh::validate`]: every index is below
/// `positions.len()`, every coordinate is finite, optional per-vertex arrays
/// have one entry per position, and per-triangle arrays one entry per triangle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as three vertex indices, counter-clockwise seen from the front.
    pub indices: Vec<[u32; 3]>,
    /// Per-vertex normals, if the source had them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, if the source had them.
    pub uvs: Option<Vec<Vec2>>,
    /// Materials referenced by `tri_material`.
    pub materials: Vec<Material>,
    /// Material index per triangle (empty: all use material 0 or the default).
    pub tri_material: Vec<u32>,
    /// Parts referenced by `tri_part`.
    pub parts: Vec<Part>,
    /// Part index per triangle (empty: one part).
    pub tri_part: Vec<u32>,
}

/// What is wrong with a mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshError {
    /// The mesh has no triangles.
    Empty,
    /// Triangle `tri` refers to vertex `index`, but there are only `count`.
    IndexOutOfRange {
        tri: usize,
        index: u32,
        count: usize,
    },
    /// Vertex `vertex` has a NaN or infinite coordinate.
    NonFinite { vertex: usize },
    /// Vertex `vertex` has a coordinate beyond [`MAX_COORDINATE`].
    TooFar { vertex: usize },
    /// An attribute array has the wrong length.
    Length {
        what: &'static str,
        got: usize,
        expected: usize,
    },
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MeshError::Empty => write!(f, "the mesh has no triangles"),
            MeshError::IndexOutOfRange { tri, index, count } => write!(
                f,
                "triangle {tri} refers to vertex {index}, but there are only {count} vertices"
            ),
            MeshError::NonFinite { vertex } => {
                write!(f, "vertex {vertex} has a NaN or infinite coordinate")
            }
            MeshError::TooFar { vertex } => write!(
                f,
                "vertex {vertex} has a coordinate beyond ±{MAX_COORDINATE:e}, where the f32 \
                 products of the ray and winding-number tests overflow; move or scale the mesh"
            ),
            MeshError::Length {
                what,
                got,
                expected,
            } => {
                write!(f, "{what} has {got} entries, expected {expected}")
            }
        }
    }
}

impl std::error::Error for MeshError {}

/// Largest coordinate magnitude a valid mesh holds. The ray-triangle tests
/// and the winding number multiply three coordinate differences in `f32`;
/// up to twice this, such products stay below `f32::MAX` (`(2·10¹²)³ =
/// 8·10³⁶`), beyond it they overflow and rays miss what they hit.
pub const MAX_COORDINATE: f32 = 1e12;

impl TriangleMesh {
    /// A mesh from positions and triangles, with no attributes.
    pub fn new(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Self {
        TriangleMesh {
            positions,
            indices,
            ..Default::default()
        }
    }

    /// A mesh of separate triangles, each with corners of its own (no
    /// vertex shared): triangle `t` is `tris[t]`.
    pub fn from_triangles(tris: &[[Vec3; 3]]) -> Self {
        let positions = tris.iter().flatten().copied().collect();
        let indices = (0..tris.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        TriangleMesh::new(positions, indices)
    }

    /// A mesh copied from vertex and index arrays as Embree's buffers,
    /// numpy and trimesh hold them: `positions` one `[x, y, z]` per vertex,
    /// `indices` three vertex indices per triangle. Checked as
    /// [`TriangleMesh::validate`] checks (indices in range, coordinates
    /// finite), so that a structure built over it never reads out of bounds;
    /// no triangles at all give an empty mesh, which every structure
    /// accepts.
    pub fn from_arrays(positions: &[[f32; 3]], indices: &[[u32; 3]]) -> Result<Self, MeshError> {
        let mesh = TriangleMesh::new(
            positions.iter().map(|&p| Vec3::from(p)).collect(),
            indices.to_vec(),
        );
        match mesh.validate() {
            Ok(()) | Err(MeshError::Empty) => Ok(mesh),
            Err(e) => Err(e),
        }
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.indices.len()
    }

    /// The three corners of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Bounding box of triangle `i`.
    pub fn triangle_bounds(&self, i: usize) -> Aabb {
        let [a, b, c] = self.triangle(i);
        Aabb::new(a.min(b).min(c), a.max(b).max(c))
    }

    /// Bounding box of all vertices referenced by triangles.
    pub fn bounds(&self) -> Aabb {
        self.indices
            .iter()
            .flatten()
            .fold(Aabb::EMPTY, |b, &i| b.grow(self.positions[i as usize]))
    }

    /// Geometric (unnormalised, area-weighted) normal of triangle `i`.
    pub fn face_normal(&self, i: usize) -> Vec3 {
        let [a, b, c] = self.triangle(i);
        (b - a).cross(c - a)
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.num_triangles())
            .map(|i| 0.5 * self.face_normal(i).length() as f64)
            .sum()
    }

    /// Part index of triangle `i` (0 when the mesh has no parts).
    pub fn part_of(&self, i: usize) -> u32 {
        self.tri_part.get(i).copied().unwrap_or(0)
    }

    /// Material index of triangle `i` (0 when the mesh has no materials).
    pub fn material_of(&self, i: usize) -> u32 {
        self.tri_material.get(i).copied().unwrap_or(0)
    }

    /// Panics, naming the triangle, when a triangle refers to a vertex the
    /// mesh does not have: what a structure built straight from the mesh
    /// (not through `build_accel`, which validates) checks first, so that
    /// a hand-made mesh fails with that message rather than an index out of
    /// bounds deep in the build.
    pub fn assert_indices_in_range(&self) {
        if let Err(e) = self.indices_in_range() {
            panic!(
                "{e} (check hand-made meshes with TriangleMesh::validate, or build through \
                 build_accel, which does)"
            );
        }
    }

    /// The first triangle referring to a vertex the mesh does not have, as
    /// [`MeshError::IndexOutOfRange`].
    fn indices_in_range(&self) -> Result<(), MeshError> {
        let n = self.positions.len();
        for (t, tri) in self.indices.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    tri: t,
                    index: i,
                    count: n,
                });
            }
        }
        Ok(())
    }

    /// Check the invariants listed on the type.
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.indices.is_empty() {
            return Err(MeshError::Empty);
        }
        let n = self.positions.len();
        if let Some(v) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshError::NonFinite { vertex: v });
        }
        if let Some(v) = self
            .positions
            .iter()
            .position(|p| p.abs().max_element() > MAX_COORDINATE)
        {
            return Err(MeshError::TooFar { vertex: v });
        }
        self.indices_in_range()?;
        let check = |what, got: usize, expected: usize| {
            if got != expected {
                Err(MeshError::Length {
                    what,
                    got,
                    expected,
                })
            } else {
                Ok(())
            }
        };
        if let Some(nr) = &self.normals {
            check("normals", nr.len(), n)?;
        }
        if let Some(uv) = &self.uvs {
            check("uvs", uv.len(), n)?;
        }
        if !self.tri_material.is_empty() {
            check("tri_material", self.tri_material.len(), self.indices.len())?;
        }
        if !self.tri_part.is_empty() {
            check("tri_part", self.tri_part.len(), self.indices.len())?;
        }
        Ok(())
    }

    /// Unit normal of triangle `i` by its winding (zero for a triangle
    /// without area). Where `e1 × e2` is too small for `f32` to normalize
    /// (a model nanometres across), it is computed in `f64`.
    pub fn unit_normal(&self, i: usize) -> Vec3 {
        let n = self.face_normal(i);
        if n.length_squared() >= f32::MIN_POSITIVE {
            return n.normalize();
        }
        let [a, b, c] = self.triangle(i).map(|v| v.as_dvec3());
        (b - a).cross(c - a).normalize_or_zero().as_vec3()
    }

    /// Area-weighted vertex normals, computed when the source had none
    /// (summed in `f64`, where the cross products of a model nanometres
    /// across do not underflow).
    pub fn compute_vertex_normals(&mut self) {
        let mut sums = vec![DVec3::ZERO; self.positions.len()];
        for i in 0..self.num_triangles() {
            let [a, b, c] = self.triangle(i).map(|v| v.as_dvec3());
            let n = (b - a).cross(c - a);
            for &v in &self.indices[i] {
                sums[v as usize] += n;
            }
        }
        let normals = sums
            .iter()
            .map(|n| n.normalize_or_zero().as_vec3())
            .collect();
        self.normals = Some(normals);
    }

    /// Append another mesh, offsetting its indices, materials and parts.
    pub fn append(&mut self, other: &TriangleMesh) {
        let base = self.positions.len() as u32;
        let (my_tris, my_mats, my_parts) =
            (self.indices.len(), self.materials.len(), self.parts.len());
        // Attributes present on only one side are filled with defaults.
        merge_attr(
            &mut self.normals,
            &other.normals,
            self.positions.len(),
            other.positions.len(),
            Vec3::ZERO,
        );
        merge_attr(
            &mut self.uvs,
            &other.uvs,
            self.positions.len(),
            other.positions.len(),
            Vec2::ZERO,
        );
        self.positions.extend_from_slice(&other.positions);
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|i| i + base)));
        let fill = |dst: &mut Vec<u32>, src: &[u32], offset: usize, n_other: usize, mine: usize| {
            if dst.is_empty() && mine > 0 {
                dst.resize(mine, 0);
            }
            if src.is_empty() {
                dst.extend(std::iter::repeat_n(offset as u32, n_other));
            } else {
                dst.extend(src.iter().map(|&m| m + offset as u32));
            }
        };
        let n_other = other.indices.len();
        if self.materials.is_empty() && my_tris > 0 {
            self.materials.push(Material::default());
        }
        let mat_offset = self.materials.len();
        if other.materials.is_empty() {
            self.materials.push(Material::default());
        } else {
            self.materials.extend_from_slice(&other.materials);
        }
        fill(
            &mut self.tri_material,
            &other.tri_material,
            mat_offset.max(my_mats),
            n_other,
            my_tris,
        );
        if self.parts.is_empty() && my_tris > 0 {
            self.parts.push(Part {
                name: String::new(),
                node: None,
            });
        }
        let part_offset = self.parts.len();
        if other.parts.is_empty() {
            self.parts.push(Part {
                name: String::new(),
                node: None,
            });
        } else {
            self.parts.extend_from_slice(&other.parts);
        }
        fill(
            &mut self.tri_part,
            &other.tri_part,
            part_offset.max(my_parts),
            n_other,
            my_tris,
        );
    }
}

fn merge_attr<T: Copy>(
    dst: &mut Option<Vec<T>>,
    src: &Option<Vec<T>>,
    mine: usize,
    theirs: usize,
    zero: T,
) {
    match (dst.as_mut(), src) {
        (None, None) => {}
        (Some(d), Some(s)) => d.extend_from_slice(s),
        (Some(d), None) => d.extend(std::iter::repeat_n(zero, theirs)),
        (None, Some(s)) => {
            let mut d = vec![zero; mine];
            d.extend_from_slice(s);
            *dst = Some(d);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> TriangleMesh {
        TriangleMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn validate_finds_each_defect() {
        assert_eq!(quad().validate(), Ok(()));
        assert_eq!(TriangleMesh::default().validate(), Err(MeshError::Empty));
        let mut far = quad();
        far.positions[2].y = -0.9e12;
        assert_eq!(far.validate(), Ok(()));
        far.positions[3].z = 2e12;
        assert_eq!(far.validate(), Err(MeshError::TooFar { vertex: 3 }));
        let mut m = quad();
        m.indices[1][2] = 9;
        assert_eq!(
            m.validate(),
            Err(MeshError::IndexOutOfRange {
                tri: 1,
                index: 9,
                count: 4
            })
        );
        let mut m = quad();
        m.positions[2].y = f32::NAN;
        assert_eq!(m.validate(), Err(MeshError::NonFinite { vertex: 2 }));
    }

    #[test]
    fn area_and_normals_of_unit_square() {
        let mut m = quad();
        assert!((m.area() - 1.0).abs() < 1e-6);
        m.compute_vertex_normals();
        for n in m.normals.unwrap() {
            assert!((n - Vec3::Z).length() < 1e-6);
        }
    }

    #[test]
    fn append_offsets_indices_parts_and_materials() {
        let mut a = quad();
        let b = quad();
        a.append(&b);
        assert_eq!(a.num_triangles(), 4);
        assert_eq!(a.indices[2], [4, 5, 6]);
        assert_eq!(a.tri_part, vec![0, 0, 1, 1]);
        assert_eq!(a.tri_material, vec![0, 0, 1, 1]);
        assert_eq!(a.validate(), Ok(()));
        assert!((a.area() - 2.0).abs() < 1e-6);
    }
}
