//! The instanced scene and its builder: geometries stored once, placed by
//! instances, under a two-level BVH.

use super::error::SceneError;
use super::geometry::Geometry;
use super::instance::Instance;
use super::top_level::TopLevelBvh;
use super::transform::InstanceTransform;
use crate::accel::BuildOptions;
use crate::mesh::{MeshError, TriangleMesh};
use glam::Affine3A;
use rayon::prelude::*;
use serde::Serialize;

/// The ray mask that sees every geometry and instance.
pub const MASK_ALL: u32 = u32::MAX;

/// A geometry before its BVH is built.
struct PendingGeometry {
    mesh: TriangleMesh,
    mask: u32,
}

/// Collects geometries and instances, checking each as it is added, then
/// builds an [`InstancedScene`]. Geometry and instance ids are their
/// positions in the order added, from 0.
#[derive(Default)]
pub struct SceneBuilder {
    geometries: Vec<PendingGeometry>,
    instances: Vec<(u32, InstanceTransform, u32, Option<String>)>,
}

impl SceneBuilder {
    /// An empty scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add a geometry (seen by every ray mask); returns its id. The mesh must
    /// pass [`TriangleMesh::validate`], except that it may be empty.
    pub fn add_geometry(&mut self, mesh: TriangleMesh) -> Result<u32, SceneError> {
        let id = self.geometries.len() as u32;
        match mesh.validate() {
            Ok(()) | Err(MeshError::Empty) => {}
            Err(error) => {
                return Err(SceneError::BadMesh {
                    geometry: id,
                    error,
                })
            }
        }
        self.geometries.push(PendingGeometry {
            mesh,
            mask: MASK_ALL,
        });
        Ok(id)
    }

    /// Add an instance of `geometry` placed by `to_world`; returns its id.
    /// Refused, naming the instance, when the geometry does not exist or
    /// the transform is not finite or not invertible.
    pub fn add_instance(&mut self, geometry: u32, to_world: Affine3A) -> Result<u32, SceneError> {
        self.push_instance(geometry, to_world, None)
    }

    /// [`SceneBuilder::add_instance`] with a name that errors and
    /// [`Instance::name`] report.
    pub fn add_named_instance(
        &mut self,
        name: &str,
        geometry: u32,
        to_world: Affine3A,
    ) -> Result<u32, SceneError> {
        self.push_instance(geometry, to_world, Some(name.to_string()))
    }

    fn push_instance(
        &mut self,
        geometry: u32,
        to_world: Affine3A,
        name: Option<String>,
    ) -> Result<u32, SceneError> {
        let instance = self.instances.len() as u32;
        if geometry as usize >= self.geometries.len() {
            return Err(SceneError::UnknownGeometry {
                instance,
                name,
                geometry,
                count: self.geometries.len(),
            });
        }
        let transform = match InstanceTransform::new(to_world) {
            Ok(t) => t,
            Err(problem) => {
                return Err(SceneError::BadTransform {
                    instance,
                    name,
                    problem,
                })
            }
        };
        self.instances.push((geometry, transform, MASK_ALL, name));
        Ok(instance)
    }

    /// Set a geometry's ray mask (every bit set by default).
    pub fn set_geometry_mask(&mut self, geometry: u32, mask: u32) -> Result<(), SceneError> {
        let count = self.geometries.len();
        let g = self
            .geometries
            .get_mut(geometry as usize)
            .ok_or(SceneError::UnknownId {
                what: "geometry",
                id: geometry,
                count,
            })?;
        g.mask = mask;
        Ok(())
    }

    /// Set an instance's ray mask (every bit set by default).
    pub fn set_instance_mask(&mut self, instance: u32, mask: u32) -> Result<(), SceneError> {
        let count = self.instances.len();
        let i = self
            .instances
            .get_mut(instance as usize)
            .ok_or(SceneError::UnknownId {
                what: "instance",
                id: instance,
                count,
            })?;
        i.2 = mask;
        Ok(())
    }

    /// Number of geometries added.
    pub fn num_geometries(&self) -> usize {
        self.geometries.len()
    }

    /// Number of instances added.
    pub fn num_instances(&self) -> usize {
        self.instances.len()
    }

    /// Build every geometry's BVH (in parallel) with `options`, then the top
    /// level over the instances' world boxes.
    pub fn build(self, options: &BuildOptions) -> InstancedScene {
        let geometries: Vec<Geometry> = self
            .geometries
            .into_par_iter()
            .map(|g| Geometry::build(g.mesh, g.mask, options))
            .collect();
        let instances: Vec<Instance> = self
            .instances
            .into_iter()
            .map(|(geometry, transform, mask, name)| {
                let object = geometries[geometry as usize].bounds();
                let world_box = if object.is_empty() {
                    object
                } else {
                    transform.world_box(&object)
                };
                Instance {
                    geometry,
                    transform,
                    mask,
                    name,
                    world_box,
                }
            })
            .collect();
        let (boxes, ids): (Vec<_>, Vec<_>) = instances
            .iter()
            .enumerate()
            .filter(|(_, i)| !i.world_box.is_empty())
            .map(|(k, i)| (i.world_box, k as u32))
            .unzip();
        let top = TopLevelBvh::build(&boxes, &ids);
        InstancedScene {
            geometries,
            instances,
            top,
        }
    }
}

/// Several triangle meshes (geometries), each stored once with its own
/// 8-wide BVH, placed any number of times by instances (a geometry and an
/// affine transform), under a top-level 8-wide BVH over the instances'
/// world boxes: Embree's two-level BVH (Wald et al. 2014, "Embree: a kernel
/// framework for efficient CPU ray tracing"), instancing as pbrt-v4's
/// `TransformedPrimitive` under a BVH over instances.
///
/// A ray is tested against the top level in world space; for each instance
/// box it enters it is taken into that instance's object space (origin and
/// direction by the inverse transform, the direction not normalised, so
/// `t` is the same on both rays and hits of different instances compare
/// directly) and traced through the geometry's BVH with the world ray's
/// current nearest `t` as its `tfar`.
///
/// Ray masks: every query takes a 32-bit mask `m`; an instance is seen
/// when `m` shares a bit with both the instance's and its geometry's mask
/// ([`MASK_ALL`] sees everything). Rays that are not valid (NaN or
/// infinite origin or direction, zero direction) miss.
pub struct InstancedScene {
    pub(crate) geometries: Vec<Geometry>,
    pub(crate) instances: Vec<Instance>,
    pub(crate) top: TopLevelBvh,
}

/// Size figures of an [`InstancedScene`].
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SceneStats {
    /// Geometries.
    pub geometries: usize,
    /// Instances.
    pub instances: usize,
    /// Triangles stored (each geometry's once).
    pub stored_triangles: usize,
    /// Triangles in the world (each instance's geometry's, summed): what a
    /// flattened scene would store.
    pub instanced_triangles: usize,
    /// Nodes of the top-level BVH.
    pub top_nodes: usize,
    /// Bytes held: meshes, bottom-level BVHs (and multi-hit BVHs made so
    /// far), instances and the top level.
    pub bytes: usize,
}

impl InstancedScene {
    /// The geometries, indexed by geometry id.
    pub fn geometries(&self) -> &[Geometry] {
        &self.geometries
    }

    /// The instances, indexed by instance id.
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// Size figures.
    pub fn stats(&self) -> SceneStats {
        let stored_triangles = self
            .geometries
            .iter()
            .map(|g| g.mesh().num_triangles())
            .sum();
        let instanced_triangles = self
            .instances
            .iter()
            .map(|i| self.geometries[i.geometry as usize].mesh().num_triangles())
            .sum();
        let bytes = self.geometries.iter().map(|g| g.bytes()).sum::<usize>()
            + self.instances.len() * std::mem::size_of::<Instance>()
            + self.top.bytes();
        SceneStats {
            geometries: self.geometries.len(),
            instances: self.instances.len(),
            stored_triangles,
            instanced_triangles,
            top_nodes: self.top.num_nodes(),
            bytes,
        }
    }

    /// Whether a ray with mask `mask` sees instance `inst`.
    #[inline]
    pub(crate) fn visible(&self, inst: &Instance, mask: u32) -> bool {
        inst.mask & mask != 0 && self.geometries[inst.geometry as usize].mask() & mask != 0
    }
}
