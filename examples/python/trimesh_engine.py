"""raykit as trimesh's ray engine: plug it into a mesh and query it as
usual.

    python examples/python/trimesh_engine.py MESH
"""

import sys

import numpy as np
import trimesh

import raykit
import raykit.trimesh

vertices, triangles, _ = raykit.load_mesh(sys.argv[1])
mesh = trimesh.Trimesh(vertices, triangles, process=False)
mesh.ray = raykit.trimesh.RayMeshIntersector(mesh)

# A grid of parallel rays down through the mesh's bounding box.
(x0, y0, z0), (x1, y1, z1) = mesh.bounds
x, y = np.meshgrid(np.linspace(x0, x1, 200), np.linspace(y0, y1, 200))
origins = np.stack([x.ravel(), y.ravel(), np.full(x.size, z1 + 1.0)], axis=1)
directions = np.tile([0.0, 0.0, -1.0], (len(origins), 1))

first = mesh.ray.intersects_first(origins, directions)
locations, index_ray, index_tri = mesh.ray.intersects_location(origins, directions)
layers = np.bincount(index_ray, minlength=len(origins))
print(f"{(first >= 0).sum()} of {len(origins)} rays hit; {len(locations)} surface crossings, "
      f"up to {layers.max()} along one ray; mean crossings per hitting ray {layers[layers > 0].mean():.2f}")
