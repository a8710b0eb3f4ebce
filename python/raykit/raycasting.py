"""``RaycastingScene``: Open3D's ``open3d.t.geometry.RaycastingScene`` on
raykit's engine.

Method names, arguments, result keys, shapes and dtypes follow Open3D, so
code written for Open3D runs after changing its import. Results are numpy
arrays (of :class:`raykit._arrays.Array`, which also has Open3D's
``.numpy()``). Beyond Open3D: ``accel=`` and ``test=`` choose the
acceleration structure and the ray/triangle test, inputs may be float64 as
well as float32, :meth:`RaycastingScene.save` and
:meth:`RaycastingScene.load_structure` keep the built structure in a file,
and :meth:`RaycastingScene.update_vertices` refits it to moved vertices.

Several geometries: each ``add_triangles`` call appends one geometry; they
are concatenated into one triangle mesh with one acceleration structure,
built at the first query after a change (as Open3D commits its scene),
and each hit's triangle is mapped back to its geometry id (the number of
the ``add_triangles`` call, from 0) and its index within that geometry.
"""

from __future__ import annotations

import math
import os

import numpy as np

from . import _arrays, _raykit

INVALID_ID = 4294967295
"""``geometry_ids`` and ``primitive_ids`` of a ray that hits nothing (Open3D's value)."""

def _mesh_arrays(mesh) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of an Open3D (tensor or legacy) or trimesh mesh."""
    vertex = getattr(mesh, "vertex", None)
    triangle = getattr(mesh, "triangle", None)
    if vertex is not None and triangle is not None:  # open3d.t.geometry.TriangleMesh
        return _arrays.to_numpy(vertex["positions"]), _arrays.to_numpy(triangle["indices"])
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):  # trimesh.Trimesh
        return np.asarray(mesh.vertices), np.asarray(mesh.faces)
    if hasattr(mesh, "vertices") and hasattr(mesh, "triangles"):  # open3d.geometry.TriangleMesh
        return np.asarray(mesh.vertices), np.asarray(mesh.triangles)
    raise ValueError(
        "add_triangles takes (vertex_positions, triangle_indices) arrays or a mesh "
        f"(Open3D TriangleMesh, legacy or tensor, or trimesh.Trimesh); got {type(mesh).__name__}"
    )


class RaycastingScene:
    """A scene of triangle meshes for ray casting (Open3D's interface).

    Parameters
    ----------
    nthreads : int
        Threads used to build the acceleration structure; 0 (default) uses
        every core.
    device : optional
        Accepted for Open3D compatibility; only the CPU is supported.
    accel : str
        The acceleration structure: ``"bvh8"`` (default, the fastest),
        ``"bvh4"``, ``"bvh2"``, ``"bvh-threaded"``, ``"kd-stack"``,
        ``"kd-ropes"``, ``"kd-restart"``, ``"kd-backtrack"`` or ``"brute"``.
    test : str
        The ray/triangle test: ``"moller"`` (default; Möller and Trumbore
        1997), ``"plucker"`` or ``"projection"``.
    """

    INVALID_ID = INVALID_ID

    def __init__(self, nthreads: int = 0, device=None, *, accel: str = "bvh8", test: str = "moller"):
        if device is not None and "CPU" not in str(device).upper():
            raise ValueError(f"raykit runs on the CPU only; got device {device}")
        self._nthreads = _arrays.threads(nthreads)
        self._accel_name = accel
        self._test_name = test
        self._vertices: list[np.ndarray] = []
        self._triangles: list[np.ndarray] = []
        self._scene = None
        # Check the names now rather than at the first query.
        _raykit.Scene(
            np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32), np.zeros(1, np.uint32), accel, test
        )

    def add_triangles(self, vertex_positions, triangle_indices=None) -> int:
        """Add a triangle mesh; returns its geometry id (0, 1, 2, ...).

        Either ``add_triangles(vertex_positions, triangle_indices)`` with an
        ``(n, 3)`` float array and an ``(m, 3)`` integer array, or
        ``add_triangles(mesh)`` with an Open3D ``TriangleMesh`` (tensor or
        legacy) or a ``trimesh.Trimesh``. Indices out of range, NaN or
        infinite coordinates raise ``ValueError``.
        """
        if triangle_indices is None:
            vertex_positions, triangle_indices = _mesh_arrays(vertex_positions)
        v = _arrays.floats(vertex_positions, "vertex_positions", last=3)
        if v.ndim != 2:
            raise ValueError(f"vertex_positions must have shape (n, 3), got {v.shape}")
        t = _arrays.indices(triangle_indices, "triangle_indices")
        if t.size and int(t.max()) >= len(v):
            bad = int(np.argmax(t.max(axis=1) >= len(v)))
            raise ValueError(
                f"triangle {bad} refers to vertex {int(t[bad].max())}, but there are only {len(v)} vertices"
            )
        if not np.isfinite(v).all():
            bad = int(np.argmax(~np.isfinite(v).all(axis=1)))
            raise ValueError(f"vertex {bad} has a NaN or infinite coordinate")
        self._vertices.append(v)
        self._triangles.append(t)
        self._scene = None
        return len(self._vertices) - 1

    def _mesh(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Vertices, triangles (indices shifted to the concatenated vertices)
        and first triangle of each geometry, over every geometry added."""
        counts = [len(t) for t in self._triangles]
        offsets = np.zeros(len(counts) + 1, dtype=np.uint64)
        np.cumsum(counts, out=offsets[1:])
        if offsets[-1] > np.iinfo(np.uint32).max:
            raise ValueError("a scene holds at most 4294967295 triangles")
        base = 0
        shifted = []
        for v, t in zip(self._vertices, self._triangles):
            shifted.append(t + np.uint32(base) if base else t)
            base += len(v)
        if base > np.iinfo(np.uint32).max:
            raise ValueError("a scene holds at most 4294967295 vertices")
        return (
            np.ascontiguousarray(self._all_vertices()),
            np.ascontiguousarray(np.concatenate(shifted) if shifted else np.zeros((0, 3), np.uint32)),
            offsets.astype(np.uint32),
        )

    def _all_vertices(self) -> np.ndarray:
        """The vertices of every geometry, concatenated."""
        return np.concatenate(self._vertices) if self._vertices else np.zeros((0, 3), np.float32)

    def _built(self):
        """The engine's scene over every geometry added so far (built once)."""
        if self._scene is None:
            vertices, triangles, offsets = self._mesh()
            self._scene = _raykit.Scene(
                vertices, triangles, offsets, self._accel_name, self._test_name, self._nthreads
            )
        return self._scene

    def cast_rays(self, rays, nthreads: int = 0) -> dict:
        """First intersection of each ray.

        ``rays``: shape ``(..., 6)`` (at least two dimensions), rows
        ``[ox, oy, oz, dx, dy, dz]``; the direction need not be unit length,
        ``t_hit`` is measured in its length. Returns a dict of
        ``t_hit`` ``(...)`` float32 (inf on a miss), ``geometry_ids`` and
        ``primitive_ids`` ``(...)`` uint32 (``INVALID_ID`` on a miss),
        ``primitive_uvs`` ``(..., 2)`` float32 (barycentric u, v: the hit is
        ``(1-u-v)·v0 + u·v1 + v·v2``) and ``primitive_normals`` ``(..., 3)``
        float32 (the hit triangle's unit normal, by its winding; 0 on a miss).
        Rays with NaN or infinite coordinates miss.
        """
        flat, lead = _arrays.rows(rays, "rays", 6)
        t, g, p, uv, n = self._built().cast_rays(flat, _arrays.threads(nthreads), _image_width(lead))
        return {
            "primitive_uvs": _arrays.result(uv.reshape(lead + (2,))),
            "primitive_ids": _arrays.result(p.reshape(lead)),
            "geometry_ids": _arrays.result(g.reshape(lead)),
            "primitive_normals": _arrays.result(n.reshape(lead + (3,))),
            "t_hit": _arrays.result(t.reshape(lead)),
        }

    def test_occlusions(self, rays, tnear: float = 0.0, tfar: float = math.inf, nthreads: int = 0):
        """Whether each ray meets a triangle with ``t`` in ``[tnear, tfar]``.

        ``rays`` as in :meth:`cast_rays`; returns a bool array of shape
        ``(...)``. Stops at the first triangle found, so it is faster than
        :meth:`cast_rays`.
        """
        flat, lead = _arrays.rows(rays, "rays", 6)
        tnear, tfar = float(tnear), float(tfar)
        if math.isnan(tnear) or math.isnan(tfar):
            raise ValueError(f"tnear and tfar must be numbers, got {tnear} and {tfar}")
        hit = self._built().test_occlusions(flat, tnear, tfar, _arrays.threads(nthreads), _image_width(lead))
        return _arrays.result(hit.reshape(lead))

    def count_intersections(self, rays, nthreads: int = 0):
        """Number of triangles each ray crosses for ``t >= 0``.

        ``rays`` as in :meth:`cast_rays`; returns an int32 array of shape
        ``(...)``. Each triangle counts once per ray (textbook
        Möller–Trumbore without tolerance, so a crossing near a shared edge
        is not counted on both neighbours; a ray exactly through an edge may
        count it on both or neither). Rays with NaN or infinite coordinates
        count 0.
        """
        flat, lead = _arrays.rows(rays, "rays", 6)
        counts = _raykit.count_intersections(self._built(), flat, _arrays.threads(nthreads))
        return _arrays.result(counts.reshape(lead))

    def list_intersections(self, rays, nthreads: int = 0, *, max_hits: int | None = None) -> dict:
        """Every intersection along each ray for ``t >= 0``, sorted by ``t``.

        ``rays`` as in :meth:`cast_rays`. Returns a dict in Open3D's layout:
        ``ray_splits`` ``(num_rays + 1,)`` uint32 (the hits of ray ``i`` are
        ``ray_splits[i]:ray_splits[i+1]``), ``ray_ids``, ``t_hit``,
        ``geometry_ids``, ``primitive_ids`` ``(num_intersections,)`` and
        ``primitive_uvs`` ``(num_intersections, 2)``. Beyond Open3D:
        ``max_hits`` keeps only the first ``max_hits`` hits of each ray.
        """
        flat, _ = _arrays.rows(rays, "rays", 6)
        cap = np.iinfo(np.uint64).max if max_hits is None else int(max_hits)
        if cap < 0:
            raise ValueError(f"max_hits must be >= 0, got {max_hits}")
        splits, ray_ids, t, g, p, uv = _raykit.list_intersections(
            self._built(), flat, cap, _arrays.threads(nthreads)
        )
        return {
            "ray_splits": _arrays.result(splits),
            "ray_ids": _arrays.result(ray_ids),
            "t_hit": _arrays.result(t),
            "geometry_ids": _arrays.result(g),
            "primitive_ids": _arrays.result(p),
            "primitive_uvs": _arrays.result(uv),
        }

    def compute_closest_points(self, query_points, nthreads: int = 0, *, max_distance: float = math.inf) -> dict:
        """Closest surface point to each query point (Ericson's point-triangle
        test, nearest BVH box first).

        ``query_points``: shape ``(..., 3)``. Returns a dict of ``points``
        ``(..., 3)`` float32, ``geometry_ids`` and ``primitive_ids`` ``(...)``
        uint32, ``primitive_uvs`` ``(..., 2)`` float32 (barycentrics: the
        point is ``(1-u-v)·v0 + u·v1 + v·v2``) and ``primitive_normals``
        ``(..., 3)`` float32 (the triangle's unit normal). Beyond Open3D:
        ``max_distance`` limits the search; points with no surface within
        it, and points with NaN or infinite coordinates, get NaN points and
        ``INVALID_ID``.
        """
        flat, lead = _arrays.rows(query_points, "query_points", 3)
        pts, g, p, uv, n, _ = _raykit.closest_points(
            self._built(), flat, float(max_distance), _arrays.threads(nthreads)
        )
        return {
            "points": _arrays.result(pts.reshape(lead + (3,))),
            "geometry_ids": _arrays.result(g.reshape(lead)),
            "primitive_ids": _arrays.result(p.reshape(lead)),
            "primitive_uvs": _arrays.result(uv.reshape(lead + (2,))),
            "primitive_normals": _arrays.result(n.reshape(lead + (3,))),
        }

    def compute_distance(self, query_points, nthreads: int = 0):
        """Distance from each query point to the surface: float32 ``(...)``
        (NaN for points with NaN or infinite coordinates)."""
        flat, lead = _arrays.rows(query_points, "query_points", 3)
        d = _raykit.distance(self._built(), flat, _arrays.threads(nthreads))
        return _arrays.result(d.reshape(lead))

    def compute_signed_distance(self, query_points, nthreads: int = 0, nsamples: int = 1):
        """Signed distance from each query point: float32 ``(...)``, negative
        inside.

        The sign comes from the generalized winding number (Jacobson et al.
        2013, with Barill et al.'s 2018 fast approximation), not from one
        ray's parity as in Open3D: it is right on meshes with holes,
        duplicated triangles or overlapping parts, where parity flips.
        ``nsamples`` (Open3D's number of rays) is accepted and must be odd,
        but is not needed.
        """
        _check_nsamples(nsamples)
        flat, lead = _arrays.rows(query_points, "query_points", 3)
        d = _raykit.signed_distance(self._built(), flat, _arrays.threads(nthreads))
        return _arrays.result(d.reshape(lead))

    def compute_occupancy(self, query_points, nthreads: int = 0, nsamples: int = 1):
        """Whether each query point is inside (1.0) or outside (0.0):
        float32 ``(...)``, by the generalized winding number (at least ½ is
        inside; see :meth:`compute_signed_distance`). ``nsamples`` is
        accepted for Open3D compatibility and must be odd."""
        _check_nsamples(nsamples)
        flat, lead = _arrays.rows(query_points, "query_points", 3)
        occ = _raykit.occupancy(self._built(), flat, _arrays.threads(nthreads))
        return _arrays.result(occ.reshape(lead))

    def compute_winding_number(self, query_points, nthreads: int = 0, *, beta: float = 2.0):
        """Generalized winding number of each query point (beyond Open3D):
        float32 ``(...)``, about 1 inside a closed surface, 0 outside, in
        between near holes. ``beta``: Barill et al.'s accuracy (a cluster of
        triangles is approximated by a dipole when the point is farther than
        ``beta`` times its radius; ``inf`` sums every triangle exactly)."""
        flat, lead = _arrays.rows(query_points, "query_points", 3)
        w = _raykit.winding_number(self._built(), flat, float(beta), _arrays.threads(nthreads))
        return _arrays.result(w.reshape(lead))

    @staticmethod
    def create_rays_pinhole(*args, **kwargs):
        """Rays of a pinhole camera, shape ``(height_px, width_px, 6)`` float32,
        with Open3D's two forms and conventions:

        ``create_rays_pinhole(intrinsic_matrix, extrinsic_matrix, width_px, height_px)``
        with a 3×3 intrinsic matrix and a 4×4 world-to-camera matrix; or
        ``create_rays_pinhole(fov_deg, center, eye, up, width_px, height_px)``
        with the horizontal field of view in degrees. Directions are not
        normalised (unit depth along the view axis).
        """
        return _arrays.result(_pinhole(*args, **kwargs))

    # Beyond Open3D.

    @property
    def accel(self) -> str:
        """The acceleration structure's name."""
        return self._accel_name

    @property
    def test(self) -> str:
        """The ray/triangle test's name."""
        return self._test_name

    def save(self, path) -> None:
        """Write the ray acceleration structure (built first if needed) to
        ``path``, for :meth:`load_structure` (beyond Open3D).

        Only ``"bvh8"`` and ``"bvh4"`` have a saved form. The file is
        versioned and checksummed, holds a checksum of the mesh, and is
        written to a temporary file then renamed over ``path``. Raises
        ``OSError`` when it cannot be written and ``ValueError`` for a scene
        without triangles or a structure with no saved form.
        """
        self._built().save(os.fspath(path))

    def load_structure(self, path) -> None:
        """Load the ray acceleration structure of the geometries added so
        far from ``path`` (written by :meth:`save` for the same mesh) instead
        of building it (beyond Open3D).

        The file's structure and triangle test replace ``accel`` and
        ``test``. Raises ``OSError`` (``FileNotFoundError``) when the file
        cannot be read and ``ValueError``, naming the byte offset and field,
        when it is damaged or was saved for another mesh (its mesh
        checksum differs). Adding a geometry afterwards builds a new
        structure at the next query.
        """
        vertices, triangles, offsets = self._mesh()
        scene = _raykit.Scene(
            vertices,
            triangles,
            offsets,
            self._accel_name,
            self._test_name,
            self._nthreads,
            os.fspath(path),
        )
        self._scene = scene
        self._accel_name = scene.accel
        self._test_name = scene.test

    def update_vertices(
        self, geometry_id: int, vertex_positions, *, max_degradation: float | None = None
    ) -> dict | None:
        """Move the vertices of geometry ``geometry_id`` to
        ``vertex_positions`` (as many as it has, same triangles) and refit
        the ray acceleration structure to them (beyond Open3D).

        A refit recomputes every box of the BVH bottom-up in O(n) and keeps
        its topology (Wald, Boulos and Shirley 2007): answers stay exact,
        but traversal may slow as boxes overlap more. When the refit tree's
        SAH cost passes ``max_degradation`` (default 1.5, the engine's
        balance of refit and rebuild costs) times the built tree's, or the
        structure has no refit (only ``"bvh8"`` and ``"bvh4"`` have), it is
        rebuilt. The point-query structure is rebuilt at its next use.
        Returns ``{"rebuilt": bool, "degradation": float}`` (degradation NaN
        when the structure has no refit), or ``None`` when no structure was
        built yet (it is built at the next query).
        """
        gid = int(geometry_id)
        if not 0 <= gid < len(self._vertices):
            raise ValueError(f"geometry_id {geometry_id} out of range: the scene has {len(self._vertices)} geometries")
        v = _arrays.floats(vertex_positions, "vertex_positions", last=3)
        old = self._vertices[gid]
        if v.shape != old.shape:
            raise ValueError(f"vertex_positions must have shape {old.shape} (geometry {gid}'s), got {v.shape}")
        if not np.isfinite(v).all():
            bad = int(np.argmax(~np.isfinite(v).all(axis=1)))
            raise ValueError(f"vertex {bad} has a NaN or infinite coordinate")
        self._vertices[gid] = v
        if self._scene is None:
            return None
        try:
            limit = {} if max_degradation is None else {"max_degradation": float(max_degradation)}
            return self._scene.refit(np.ascontiguousarray(self._all_vertices()), self._nthreads, **limit)
        except BaseException:
            self._vertices[gid] = old
            raise

    def stats(self) -> dict:
        """Size and quality of the acceleration structure: nodes, leaves,
        bytes, node_bytes, depth, sah_cost, triangle_refs (builds it if needed)."""
        return self._built().stats()


def _check_nsamples(nsamples) -> None:
    """Open3D's ``nsamples`` must be a positive odd integer."""
    if isinstance(nsamples, bool) or not isinstance(nsamples, (int, np.integer)) or nsamples < 1 or nsamples % 2 == 0:
        raise ValueError(f"nsamples must be a positive odd integer, got {nsamples!r}")


def _image_width(lead: tuple) -> int:
    """Rays shaped ``(..., height, width, 6)`` are images: the engine traces
    them in square pixel blocks (same answers, more coherent packets)."""
    return lead[-1] if len(lead) >= 2 else 0


def _look_at(center, eye, up) -> np.ndarray:
    """Open3D's world-to-camera matrix of a camera at ``eye`` looking at
    ``center``: camera x = up × forward, y = forward × x, z = forward."""
    center, eye, up = (np.asarray(_arrays.to_numpy(a), dtype=np.float64).reshape(3) for a in (center, eye, up))
    forward = center - eye
    norm = np.linalg.norm(forward)
    if not norm > 0:
        raise ValueError("eye and center must differ")
    forward /= norm
    right = np.cross(up, forward)
    rn = np.linalg.norm(right)
    if not rn > 0:
        raise ValueError("up must not be parallel to the viewing direction")
    right /= rn
    down = np.cross(forward, right)
    rotation = np.stack([right, down, forward])
    extrinsic = np.eye(4)
    extrinsic[:3, :3] = rotation
    extrinsic[:3, 3] = -rotation @ eye
    return extrinsic


def _pinhole(*args, **kwargs) -> np.ndarray:
    names_k = ("intrinsic_matrix", "extrinsic_matrix", "width_px", "height_px")
    names_f = ("fov_deg", "center", "eye", "up", "width_px", "height_px")
    if "fov_deg" in kwargs or (args and np.ndim(_arrays.to_numpy(args[0])) == 0):
        bound = dict(zip(names_f, args), **kwargs)
        width, height = int(bound["width_px"]), int(bound["height_px"])
        focal = 0.5 * width / math.tan(math.radians(float(bound["fov_deg"])) * 0.5)
        intrinsic = np.array([[focal, 0, 0.5 * width], [0, focal, 0.5 * height], [0, 0, 1]])
        extrinsic = _look_at(bound["center"], bound["eye"], bound["up"])
    else:
        bound = dict(zip(names_k, args), **kwargs)
        width, height = int(bound["width_px"]), int(bound["height_px"])
        intrinsic = np.asarray(_arrays.to_numpy(bound["intrinsic_matrix"]), dtype=np.float64)
        extrinsic = np.asarray(_arrays.to_numpy(bound["extrinsic_matrix"]), dtype=np.float64)
    if intrinsic.shape != (3, 3) or extrinsic.shape != (4, 4):
        raise ValueError(
            f"expected a 3x3 intrinsic and a 4x4 extrinsic matrix, got {intrinsic.shape} and {extrinsic.shape}"
        )
    if width <= 0 or height <= 0:
        raise ValueError(f"width_px and height_px must be positive, got {width} x {height}")
    rotation, translation = extrinsic[:3, :3], extrinsic[:3, 3]
    origin = -rotation.T @ translation
    x, y = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    pixels = np.stack([x, y, np.ones_like(x)], axis=-1)
    camera = pixels @ np.linalg.inv(intrinsic).T
    directions = camera @ rotation
    rays = np.empty((height, width, 6), dtype=np.float32)
    rays[..., :3] = origin
    rays[..., 3:] = directions
    return rays
