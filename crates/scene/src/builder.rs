//! An incremental builder for meshes with per-vertex normals, materials and
//! parts, and the primitive shapes the built-in scenes are made of.

use raykit_core::glam::{Affine3A, Vec3};
use raykit_core::Icosphere;
use raykit_core::{Material, Part, TriangleMesh};

/// Builds a [`TriangleMesh`] shape by shape.
///
/// Every triangle gets a material (an index returned by
/// [`MeshBuilder::add_material`]) and belongs to the part opened by the last
/// [`MeshBuilder::begin_part`] (part 0, unnamed, before the first call).
/// Flat shapes (quads, grids, boxes) get their own vertices per face, carrying
/// the face normal; smooth shapes (icospheres) share vertices and carry the
/// surface normal.
#[derive(Clone, Debug, Default)]
pub struct MeshBuilder {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
    materials: Vec<Material>,
    tri_material: Vec<u32>,
    parts: Vec<Part>,
    tri_part: Vec<u32>,
}

impl MeshBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add a material and return its index.
    pub fn add_material(&mut self, material: Material) -> u32 {
        self.materials.push(material);
        (self.materials.len() - 1) as u32
    }

    /// Start a new part named `name`; the triangles added from now on belong
    /// to it. Returns the part index.
    pub fn begin_part(&mut self, name: impl Into<String>) -> u32 {
        self.parts.push(Part {
            name: name.into(),
            node: None,
        });
        (self.parts.len() - 1) as u32
    }

    /// Number of triangles so far.
    pub fn num_triangles(&self) -> usize {
        self.indices.len()
    }

    /// Add a vertex with a normal (normalised here) and return its index.
    pub fn push_vertex(&mut self, position: Vec3, normal: Vec3) -> u32 {
        self.positions.push(position);
        self.normals.push(normal.normalize_or_zero());
        (self.positions.len() - 1) as u32
    }

    /// Add a triangle over existing vertices with material `material`.
    pub fn push_triangle(&mut self, tri: [u32; 3], material: u32) {
        if self.parts.is_empty() {
            self.begin_part("");
        }
        self.indices.push(tri);
        self.tri_material.push(material);
        self.tri_part.push((self.parts.len() - 1) as u32);
    }

    /// A flat quad with corners in counter-clockwise order seen from the front
    /// (two triangles, four vertices carrying the face normal).
    pub fn add_quad(&mut self, corners: [Vec3; 4], material: u32) {
        let [a, b, c, d] = corners;
        let n = (b - a).cross(c - a) + (c - a).cross(d - a);
        let v = corners.map(|p| self.push_vertex(p, n));
        self.push_triangle([v[0], v[1], v[2]], material);
        self.push_triangle([v[0], v[2], v[3]], material);
    }

    /// A flat parallelogram `origin + s·u + t·v`, `s, t` in `[0, 1]`, split
    /// into `nu × nv` cells of two triangles each, front side towards `u × v`.
    /// `material` gives the material of cell `(i, j)` (a checkerboard, say).
    pub fn add_grid(
        &mut self,
        origin: Vec3,
        u: Vec3,
        v: Vec3,
        (nu, nv): (u32, u32),
        material: impl Fn(u32, u32) -> u32,
    ) {
        let n = u.cross(v);
        let base = self.positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                let p = origin + u * (i as f32 / nu as f32) + v * (j as f32 / nv as f32);
                self.push_vertex(p, n);
            }
        }
        let at = |i: u32, j: u32| base + j * (nu + 1) + i;
        for j in 0..nv {
            for i in 0..nu {
                let m = material(i, j);
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                self.push_triangle([a, b, c], m);
                self.push_triangle([a, c, d], m);
            }
        }
    }

    /// The cube `[-0.5, 0.5]³` mapped by `transform`: six flat faces of two
    /// triangles, outward-facing, closed (corner positions are shared exactly
    /// between faces, vertices are not).
    pub fn add_box(&mut self, transform: Affine3A, material: u32) {
        let corner = |i: usize| {
            let p = Vec3::new(
                if i & 1 == 0 { -0.5 } else { 0.5 },
                if i & 2 == 0 { -0.5 } else { 0.5 },
                if i & 4 == 0 { -0.5 } else { 0.5 },
            );
            transform.transform_point3(p)
        };
        let c: [Vec3; 8] = std::array::from_fn(corner);
        // Counter-clockwise seen from outside (for a transform that keeps
        // handedness; a mirroring transform flips them all).
        const FACES: [[usize; 4]; 6] = [
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
        ];
        for f in FACES {
            self.add_quad(f.map(|i| c[i]), material);
        }
    }

    /// The sphere `ico` (a unit icosphere) mapped by `transform`, with smooth
    /// normals transformed by the inverse transpose (correct under
    /// non-uniform scaling).
    pub fn add_icosphere(&mut self, ico: &Icosphere, transform: Affine3A, material: u32) {
        let normal_matrix = transform.matrix3.inverse().transpose();
        let base = self.positions.len() as u32;
        for &p in &ico.positions {
            self.push_vertex(transform.transform_point3(p), normal_matrix * p);
        }
        for t in &ico.indices {
            self.push_triangle(t.map(|i| i + base), material);
        }
    }

    /// The finished mesh (normals always present; the default material is
    /// added when none was).
    pub fn finish(mut self) -> TriangleMesh {
        if self.materials.is_empty() {
            self.materials.push(Material::default());
        }
        TriangleMesh {
            positions: self.positions,
            indices: self.indices,
            normals: Some(self.normals),
            uvs: None,
            materials: self.materials,
            tri_material: self.tri_material,
            parts: self.parts,
            tri_part: self.tri_part,
        }
    }
}

/// A material with a diffuse colour and a specular highlight, everything else
/// at its default.
pub fn material(name: &str, diffuse: [f32; 3], specular: f32, shininess: f32) -> Material {
    Material {
        name: name.into(),
        diffuse,
        specular: [specular; 3],
        shininess,
        ..Material::default()
    }
}
