"""A ray engine for trimesh: ``RayMeshIntersector`` with the interface of
``trimesh.ray.ray_triangle.RayMeshIntersector`` and
``trimesh.ray.ray_pyembree.RayMeshIntersector``.

Plug it into a mesh with::

    import trimesh, raykit.trimesh
    mesh = trimesh.load("bunny.ply")
    mesh.ray = raykit.trimesh.RayMeshIntersector(mesh)
    mesh.ray.intersects_location(origins, directions)

The mesh is shifted by the lower corner of its bounding box (in float64)
before it is rounded to the engine's float32, and so are the rays, so that
meshes far from the origin keep their precision; rays from far away are
moved along themselves to just outside the mesh first, in float64, so that
their origins keep it too; hit locations are
computed in float64 from the hit triangle's own vertices and the
barycentric coordinates. Directions are normalised, as trimesh's engines
do.

All hits along a ray (``multiple_hits=True``) are the ray's crossings of
the surface, as :meth:`raykit.RaycastingScene.list_intersections` lists
them: a crossing at a shared edge or vertex is reported once, on one of the
triangles there, decided exactly. Repeated nearest-hit queries that step
past each hit by a small gap, as trimesh's embreex engine does, can report
such a crossing twice: the triangle tests accept hits just beyond a
triangle's edges, so that no ray slips between two triangles, and at a
grazing angle the neighbour's hit lies further along the ray than the gap.
"""

from __future__ import annotations

import numpy as np

from . import _arrays, _raykit
from .raycasting import _check_coordinates, _used

class RayMeshIntersector:
    """Ray queries on a ``trimesh.Trimesh``, answered by raykit.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The mesh (anything with ``vertices``, ``faces`` and ``scale``). The
        acceleration structure is built at the first query and rebuilt when
        the mesh changes.
    threads : int
        Threads per query; 0 (default) uses every core.
    accel, test : str
        Structure and triangle test, as in :class:`raykit.RaycastingScene`.
    """

    def __init__(self, mesh, threads: int = 0, accel: str = "bvh8", test: str = "moller"):
        self.mesh = mesh
        self._threads = _arrays.threads(threads)
        self._accel = accel
        self._test = test
        self._key = None
        self._scene = None
        self._shift = None

    def __getstate__(self):
        """Picklable (for multiprocessing, joblib, dask): the mesh and the
        settings; the structure is built again at the first query."""
        state = self.__dict__.copy()
        state.update(_scene=None, _key=None)
        return state

    def _built(self):
        key = hash(self.mesh)
        if self._scene is None or key != self._key:
            vertices = np.asarray(self.mesh.vertices, dtype=np.float64)
            faces = _arrays.indices(np.asarray(self.mesh.faces), "mesh.faces")
            # The shift comes from the vertices the faces use: one no face
            # uses, however far, does not cost the mesh its precision.
            used = vertices[_used(faces, len(vertices))]
            used = used[np.isfinite(used).all(axis=1)]
            self._shift = used.min(axis=0) if len(used) else np.zeros(3)
            shifted = _check_coordinates(vertices - self._shift, faces)
            self._scene = _raykit.Scene(
                shifted, faces, np.array([0, len(faces)], dtype=np.uint32), self._accel, self._test, self._threads
            )
            self._vertices = vertices
            self._faces = faces
            self._sphere = _arrays.bounding_sphere([vertices[_used(faces, len(vertices))] - self._shift])
            self._key = key
        return self._scene

    def _rays(self, ray_origins, ray_directions) -> np.ndarray:
        o = np.asarray(_arrays.to_numpy(ray_origins))
        d = np.asarray(_arrays.to_numpy(ray_directions))
        for a, name in ((o, "ray_origins"), (d, "ray_directions")):
            if a.dtype.kind not in "fiu":
                raise ValueError(f"{name} must hold real numbers, got dtype {a.dtype}")
            if a.ndim != 2 or a.shape[1] != 3:
                raise ValueError(f"{name} must have shape (n, 3), got {a.shape}")
        if o.shape != d.shape:
            raise ValueError(f"ray_origins and ray_directions must have the same shape, got {o.shape} and {d.shape}")
        self._built()
        d = d.astype(np.float64)
        norm = np.linalg.norm(d, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            d = np.where(norm > 0, d / norm, d)
        rays = np.concatenate([o.astype(np.float64), d], axis=1)
        flat, _, _ = _arrays.ray_rows(rays, "rays", self._shift, self._sphere, threads=self._threads)
        return flat

    def _locations(self, tri: np.ndarray, uv: np.ndarray) -> np.ndarray:
        corners = self._vertices[self._faces[tri]]
        u, v = uv[:, 0:1].astype(np.float64), uv[:, 1:2].astype(np.float64)
        return (1.0 - u - v) * corners[:, 0] + u * corners[:, 1] + v * corners[:, 2]

    def _first(self, ray_origins, ray_directions):
        rays = self._rays(ray_origins, ray_directions)
        t, _, prim, uv, _ = self._scene.cast_rays(rays, self._threads)
        return prim, uv

    def intersects_first(self, ray_origins, ray_directions, **kwargs) -> np.ndarray:
        """Index of the first triangle each ray hits, -1 on a miss: ``(n,)`` int64."""
        prim, _ = self._first(ray_origins, ray_directions)
        out = prim.astype(np.int64)
        out[prim == _raykit.INVALID_ID] = -1
        return out

    def intersects_any(self, ray_origins, ray_directions, **kwargs) -> np.ndarray:
        """Whether each ray hits the mesh: ``(n,)`` bool."""
        rays = self._rays(ray_origins, ray_directions)
        return self._scene.test_occlusions(rays, 0.0, np.inf, self._threads)

    def intersects_id(
        self,
        ray_origins,
        ray_directions,
        multiple_hits: bool = True,
        max_hits: int = 100,
        return_locations: bool = False,
        **kwargs,
    ):
        """Triangles hit by the rays: ``(index_tri, index_ray)`` int64, and
        with ``return_locations`` the ``(h, 3)`` float64 hit points.

        ``multiple_hits``: every hit along each ray (at most ``max_hits``),
        ordered by ray, then distance; otherwise the first hit only.
        """
        if multiple_hits:
            cap = _arrays.max_hits(max_hits)
            rays = self._rays(ray_origins, ray_directions)
            _, ray, _, _, tri, uv = _raykit.list_intersections(self._scene, rays, cap, self._threads)
        else:
            prim, uv_all = self._first(ray_origins, ray_directions)
            ray = np.flatnonzero(prim != _raykit.INVALID_ID)
            tri, uv = prim[ray], uv_all[ray]
        index_tri, index_ray = tri.astype(np.int64), ray.astype(np.int64)
        if return_locations:
            return index_tri, index_ray, self._locations(index_tri, uv)
        return index_tri, index_ray

    def intersects_location(self, ray_origins, ray_directions, multiple_hits: bool = True, **kwargs):
        """Where the rays hit the mesh: ``(locations (h, 3) float64,
        index_ray (h,) int64, index_tri (h,) int64)``."""
        index_tri, index_ray, locations = self.intersects_id(
            ray_origins, ray_directions, multiple_hits=multiple_hits, return_locations=True, **kwargs
        )
        return locations, index_ray, index_tri

    def contains_points(self, points) -> np.ndarray:
        """Whether each point lies inside the mesh: ``(n,)`` bool.

        By the generalized winding number (Jacobson et al. 2013, with Barill
        et al.'s 2018 fast approximation) rather than ray parity: right on
        meshes that are not watertight, have duplicated faces or overlapping
        parts (trimesh's own engines count ray crossings). Points with NaN
        or infinite coordinates are outside.
        """
        p = np.asarray(_arrays.to_numpy(points))
        if p.dtype.kind not in "fiu":
            raise ValueError(f"points must hold real numbers, got dtype {p.dtype}")
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"points must have shape (n, 3), got {p.shape}")
        scene = self._built()
        shifted = np.ascontiguousarray(p.astype(np.float64) - self._shift, dtype=np.float32)
        return _raykit.occupancy(scene, shifted, self._threads) > 0.5
