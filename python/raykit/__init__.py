"""raykit: rays and spatial queries on a Rust engine, numpy in and out.

- :class:`RaycastingScene`: Open3D's ``open3d.t.geometry.RaycastingScene``
  interface (change the import, keep the code);
- :mod:`raykit.trimesh`: a ray engine for trimesh
  (``mesh.ray = raykit.trimesh.RayMeshIntersector(mesh)``);
- :func:`load_mesh`: OBJ, PLY, STL, OFF, glTF and GLB files as arrays;
- :mod:`raykit.terrain`: exact shadow masks, viewsheds and renderings of
  height grids or GeoTIFFs;
- :func:`render`: pictures of a scene; :func:`cull`: visibility culling.

Work runs with the GIL released, on every core unless ``threads=`` (or
Open3D's ``nthreads=``) says otherwise.
"""

from . import terrain, trimesh
from ._raykit import __version__
from .cull import CullResult, cull
from .files import load_gltf_instances, load_mesh
from .raycasting import INVALID_ID, RaycastingScene
from .render import render

__all__ = [
    "INVALID_ID",
    "CullResult",
    "RaycastingScene",
    "__version__",
    "cull",
    "load_gltf_instances",
    "load_mesh",
    "render",
    "terrain",
    "trimesh",
]
