//! An instance: a geometry placed in the world by an affine transform.

use super::transform::InstanceTransform;
use crate::aabb::Aabb;

/// One placement of a geometry: its id, the checked transform, a ray mask
/// and an optional name (a glTF node's, for example) used in messages.
#[derive(Clone, Debug)]
pub struct Instance {
    pub(crate) geometry: u32,
    pub(crate) transform: InstanceTransform,
    pub(crate) mask: u32,
    pub(crate) name: Option<String>,
    /// The geometry's padded bounds taken to world space (empty for an
    /// empty geometry).
    pub(crate) world_box: Aabb,
}

impl Instance {
    /// The geometry placed.
    pub fn geometry(&self) -> u32 {
        self.geometry
    }

    /// The object-to-world transform and its inverse.
    pub fn transform(&self) -> &InstanceTransform {
        &self.transform
    }

    /// The instance's ray mask: a ray with mask `m` sees it when
    /// `mask & m != 0` (and its geometry's mask also shares a bit with `m`).
    pub fn mask(&self) -> u32 {
        self.mask
    }

    /// The name given when it was added.
    pub fn name(&self) -> Option<&str> {
        self.name.as_deref()
    }

    /// A world-space box holding every hit the instance can report.
    pub fn world_box(&self) -> Aabb {
        self.world_box
    }
}
