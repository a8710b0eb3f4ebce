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

Several geometries: each ``add_triangles`` call appends one geometry,
placed once where its vertices are. While every geometry is placed once and
nothing else, they are concatenated into one triangle mesh with one
acceleration structure, built at the first query after a change (as Open3D
commits its scene), and each hit's triangle is mapped back to its geometry
id (the number of the ``add_triangles`` call, from 0) and its index within
that geometry.

Instances (beyond Open3D): :meth:`RaycastingScene.add_instance` places a
geometry again with an affine transform, and ``add_triangles(...,
place=False)`` stores a geometry only for instances. A scene with instances
(or ray masks) keeps each geometry once with its own BVH under a top-level
BVH over the instances (a two-level BVH as in Embree and pbrt-v4), so
repeated parts cost memory once. Every placement is an instance: instance
ids count the placements from 0 in the order they were made, and the
results of such a scene carry ``instance_ids`` beside ``geometry_ids``
(the results of a scene without instances keep Open3D's keys exactly).

Far from the coordinates' origin (beyond Open3D): the engine stores
float32, which at UTM coordinates (millions of metres) is about half a
metre apart, so a model there loses its shape and its hits. A scene whose
first geometry lies farther from the origin than four times its own size
therefore keeps an :attr:`RaycastingScene.origin` near its centre: vertices,
ray origins, query points and instance placements are moved by it in
float64 before they are rounded to float32, and closest points are moved
back (returned as float64). Inputs, outputs and ``t_hit`` stay in the
caller's coordinates; float64 inputs keep their precision. ``origin=`` fixes
it instead, e.g. for geometries near zero that instances place far away.
"""

from __future__ import annotations

import inspect
import math
import warnings

import numpy as np

from . import _arrays, _raykit
from .files import fspath, load_gltf_instances

INVALID_ID = 4294967295
"""``geometry_ids`` and ``primitive_ids`` of a ray that hits nothing (Open3D's value)."""

_MASK_ALL = 0xFFFFFFFF
"""A ray mask that sees everything (the default of every mask)."""

_IDENTITY = np.ascontiguousarray(np.eye(4)[:3])
"""The (3, 4) matrix of an instance placed where its vertices are."""


def _check_mask(mask, what: str) -> int:
    """A 32-bit mask as an int, or ``ValueError``."""
    if type(mask) is int and 0 <= mask <= _MASK_ALL:
        return mask
    if isinstance(mask, bool) or not isinstance(mask, (int, np.integer)) or not 0 <= int(mask) <= _MASK_ALL:
        raise ValueError(f"{what} must be an integer in [0, 2**32 - 1], got {mask!r}")
    return int(mask)

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
    origin : array_like of 3 floats, optional
        The point coordinates are stored relative to (see :attr:`origin`);
        by default chosen from the first geometry when it lies far from
        zero.
    """

    INVALID_ID = INVALID_ID

    def __init__(
        self, nthreads: int = 0, device=None, *, accel: str = "bvh8", test: str = "moller", origin=None
    ):
        if device is not None and "CPU" not in str(device).upper():
            raise ValueError(f"raykit runs on the CPU only; got device {device}")
        self._origin = None if origin is None else _origin_of(origin)
        self._origin_given = origin is not None
        self._nthreads = _arrays.threads(nthreads, "nthreads")
        self._accel_name = accel
        self._test_name = test
        self._vertices: list[np.ndarray] = []
        # Bounding boxes of geometries by id, with the vertex array each was
        # taken from (see `_box`).
        self._boxes: dict = {}
        # Each geometry's vertices are stored relative to this point (None
        # for zero): the scene's origin, or for a geometry kept for
        # instances only, its own.
        self._geometry_origins: list[np.ndarray | None] = []
        self._triangles: list[np.ndarray] = []
        self._geometry_masks: list[int] = []
        # (geometry id, (3, 4) float64 object-to-world matrix or None for
        # the identity, mask) of each instance, by instance id.
        self._placements: list[tuple[int, np.ndarray | None, int]] = []
        self._scene = None
        self._flat_of_instances = None
        # Check the names now rather than at the first query.
        _raykit.Scene(
            np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32), np.zeros(1, np.uint32), accel, test
        )

    def __getstate__(self):
        """Picklable (for multiprocessing, joblib, dask): the geometries,
        instances and settings; the built structures are not kept, and are
        built again at the first query, as after adding a geometry."""
        state = self.__dict__.copy()
        state.update(_scene=None, _flat_of_instances=None)
        return state

    def __copy__(self):
        """A scene of the same geometries, instances and settings that
        changes apart from this one (``copy.copy``): its lists are its own,
        the vertex arrays (replaced, never changed in place) are shared,
        and its structures are built at its first query."""
        other = type(self).__new__(type(self))
        own = {k: v.copy() if isinstance(v, (list, dict)) else v for k, v in self.__getstate__().items()}
        other.__dict__.update(own)
        return other

    def add_triangles(
        self,
        vertex_positions=None,
        triangle_indices=None,
        *,
        mesh=None,
        place: bool = True,
        mask: int = _MASK_ALL,
    ) -> int:
        """Add a triangle mesh; returns its geometry id (0, 1, 2, ...).

        Either ``add_triangles(vertex_positions, triangle_indices)`` with an
        ``(n, 3)`` float array and an ``(m, 3)`` integer array, or
        ``add_triangles(mesh)`` (or ``mesh=``) with an Open3D
        ``TriangleMesh`` (tensor or legacy) or a ``trimesh.Trimesh``. Indices out of range, NaN or
        infinite coordinates, and coordinates beyond ``±1e12`` (where the
        engine's float32 products overflow) raise ``ValueError``.

        Beyond Open3D: ``place=False`` stores the mesh for
        :meth:`add_instance` without placing it where its vertices are;
        ``mask`` (32 bits, all set by default) is the geometry's ray mask:
        a ray query with ``mask=m`` sees the geometry only when ``m``
        shares a bit with it (and with the instance's mask).
        """
        mask = _check_mask(mask, "mask")
        if mesh is not None:
            if vertex_positions is not None or triangle_indices is not None:
                raise ValueError("give either mesh= or vertex_positions and triangle_indices, not both")
            vertex_positions = mesh
        if vertex_positions is None:
            raise ValueError("add_triangles needs a mesh, or vertex_positions and triangle_indices")
        if triangle_indices is None:
            vertex_positions, triangle_indices = _mesh_arrays(vertex_positions)
        raw = _arrays.reals(vertex_positions, "vertex_positions", last=3)
        if raw.ndim != 2:
            raise ValueError(f"vertex_positions must have shape (n, 3), got {raw.shape}")
        t = _arrays.indices(triangle_indices, "triangle_indices")
        if t.size and int(t.max()) >= len(raw):
            bad = int(np.argmax(t.max(axis=1) >= len(raw)))
            raise ValueError(
                f"triangle {bad} refers to vertex {int(t[bad].max())}, but there are only {len(raw)} vertices"
            )
        # Origins come from the vertices the triangles use: one no triangle
        # uses, however far, does not keep a far model at float32's mercy.
        used = raw[_used(t, len(raw))]
        origin = self._origin
        if not self._vertices and origin is None:
            origin = _far_origin(used)
        # A geometry placed where it is lives in the scene's coordinates; one
        # kept for instances only has its own origin (zero near zero), which
        # its instances' placements absorb.
        own = origin if place else _far_origin(used)
        shifted = _shifted(raw, own)
        v = _check_coordinates(shifted, t)
        _warn_if_coarse(shifted[_used(t, len(raw))], f"geometry {len(self._vertices)}")
        self._origin = origin
        self._vertices.append(v)
        self._geometry_origins.append(own)
        self._triangles.append(t)
        self._geometry_masks.append(mask)
        gid = len(self._vertices) - 1
        if place:
            self._placements.append((gid, None, _MASK_ALL))
        self._changed()
        return gid

    def add_instance(self, geometry_id: int, transform, *, mask: int = _MASK_ALL) -> int:
        """Place geometry ``geometry_id`` again, moved by the affine
        ``transform``; returns the instance id (beyond Open3D; Embree's
        instances).

        ``transform``: a 4×4 object-to-world matrix whose last row is
        ``[0, 0, 0, 1]``, or its top 3×4 part. The geometry is stored once
        however often it is placed. ``mask`` (32 bits) is the instance's
        ray mask. A ``geometry_id`` that is not an integer (numpy's are) or
        names no geometry, and a matrix that is not affine, not finite or
        not invertible, raise ``ValueError``.
        """
        gid = self._geometry_id(geometry_id)
        m = np.array(_arrays.to_numpy(transform), dtype=np.float64)
        iid = len(self._placements)
        if m.shape == (4, 4):
            if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
                raise ValueError(f"instance {iid}: the transform's last row must be [0, 0, 0, 1], got {m[3].tolist()}")
            m = m[:3]
        elif m.shape != (3, 4):
            raise ValueError(f"instance {iid}: the transform must have shape (4, 4) or (3, 4), got {m.shape}")
        mask = _check_mask(mask, "mask")
        own, world = self._geometry_origins[gid], self._origin
        if own is not None or world is not None:
            # The geometry is stored moved by its origin g and the world by
            # the scene's o: x -> M x + b becomes x' -> M x' + (M g + b - o).
            m = m.copy()
            if own is not None:
                m[:, 3] += m[:, :3] @ own
            if world is not None:
                m[:, 3] -= world
        m = np.ascontiguousarray(m)
        # The engine's own check (finite, invertible in float32), on an
        # empty geometry so that it costs nothing.
        try:
            _raykit.InstancedScene([(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32), 0)], [(0, m, 0)])
        except ValueError as e:
            raise ValueError(f"instance {iid}: {str(e).split(': ', 1)[-1]}") from None
        corners = _placed_corners(self._box(gid), m)
        if corners is not None:
            _check_placement(self._vertices[gid], corners, m, iid, gid)
            _warn_if_coarse(corners, f"instance {iid}")
        self._placements.append((gid, m, mask))
        self._changed()
        return iid

    def _geometry_id(self, geometry_id) -> int:
        """``geometry_id`` as an int: an integer (Python's or numpy's, not
        a bool, a float or a string) naming a geometry of the scene."""
        if isinstance(geometry_id, (bool, np.bool_)) or not isinstance(geometry_id, (int, np.integer)):
            raise ValueError(f"geometry_id must be an integer (a geometry id add_triangles returned), got {geometry_id!r}")
        if not 0 <= geometry_id < len(self._vertices):
            raise ValueError(f"geometry_id {geometry_id} out of range: the scene has {len(self._vertices)} geometries")
        return int(geometry_id)

    def _box(self, gid: int):
        """The bounding box ``(lo, hi)`` in float64 of the vertices geometry
        ``gid``'s triangles use, or None when they use none; kept while its
        vertex array is the same object (instances of one geometry are
        checked against it)."""
        v = self._vertices[gid]
        cached = self._boxes.get(gid)
        if cached is None or cached[0] is not v:
            u = v[_used(self._triangles[gid], len(v))]
            box = (u.min(axis=0).astype(np.float64), u.max(axis=0).astype(np.float64)) if len(u) else None
            cached = (v, box)
            self._boxes[gid] = cached
        return cached[1]

    def add_gltf(self, path, *, mask: int = _MASK_ALL) -> list[int]:
        """Add a glTF or GLB file with its instancing kept (beyond Open3D):
        each glTF mesh as a geometry stored once (``place=False``), and one
        instance per node that places it (see
        :func:`raykit.files.load_gltf_instances`), with ray mask ``mask``.
        Returns the instance ids, in the file's node order, which is the
        order :func:`raykit.load_mesh` numbers its parts. A node whose
        transform is not invertible (a zero scale hides nodes in many
        files) places only triangles no ray hits: it is left out with a
        ``UserWarning``. Added to an empty scene without ``origin=``, a file
        placed far from zero by its nodes sets the scene's :attr:`origin`
        near its first placement, as a far first geometry does."""
        geometries, instances = load_gltf_instances(path)
        if not self._vertices and self._origin is None and instances:
            # A file placed far by its nodes (a UTM or geocentric
            # translation) sets the scene's origin from its first placement.
            g, matrix, _, _ = instances[0]
            placed = geometries[g][0].astype(np.float64) @ matrix[:, :3].T + matrix[:, 3]
            self._origin = _far_origin(placed)
        first = [self.add_triangles(v, t, place=False) for v, t in geometries]
        ids = []
        for g, matrix, node, name in instances:
            try:
                ids.append(self.add_instance(first[g], matrix, mask=mask))
            except ValueError as e:
                if "invertible" not in str(e):
                    raise
                warnings.warn(f"{fspath(path)}: nodes[{node}] {name!r} left out: {e}", stacklevel=2)
        return ids

    def _changed(self) -> None:
        """Forget the built structures (rebuilt at the next query)."""
        self._scene = None
        self._flat_of_instances = None
        self._sphere_of_scene = None
        self._instanced_cache = None

    def _rays(self, rays, nthreads, every_dtype: bool = False):
        """``rays`` as the engine takes them (:func:`_arrays.ray_rows`):
        float64 rays from afar moved up to the scene, and rays of every
        dtype where the engine's own move does not cover them (counts and
        hit lists; the Plücker and projection tests)."""
        every = every_dtype or (self._test_name != "moller" and not self.instanced)
        return _arrays.ray_rows(
            rays, "rays", self._origin, self._sphere(), every_dtype=every, threads=_arrays.threads(nthreads, "nthreads")
        )

    def _sphere(self):
        """The bounding sphere of the placed geometries' boxes, in the
        scene's coordinates (None when empty), kept until the scene
        changes: rays from afar are moved to it (:func:`_arrays.ray_rows`)."""
        if getattr(self, "_sphere_of_scene", None) is None:
            corners = [_placed_corners(self._box(g), m) for g, m, _ in self._placements]
            corners = [c for c in corners if c is not None]
            self._sphere_of_scene = (_arrays.bounding_sphere(corners),)
        return self._sphere_of_scene[0]

    @property
    def instanced(self) -> bool:
        """Whether the scene is traced as instances over per-geometry BVHs
        (it has an instance, a geometry stored for instances only, or a
        mask) rather than as one concatenated mesh. Kept until the scene
        changes: every query asks."""
        cached = self.__dict__.get("_instanced_cache")
        if cached is None:
            cached = any(m != _MASK_ALL for m in self._geometry_masks) or (
                len(self._placements) != len(self._vertices)
                or any(g != k or t is not None or m != _MASK_ALL for k, (g, t, m) in enumerate(self._placements))
            )
            self._instanced_cache = cached
        return cached

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
        """The engine's scene over every geometry added so far (built once):
        a ``_raykit.Scene`` over the concatenated mesh, or a
        ``_raykit.InstancedScene`` when the scene is :attr:`instanced`."""
        if self._scene is None:
            if self.instanced:
                self._scene = _raykit.InstancedScene(
                    [
                        (np.ascontiguousarray(v, dtype=np.float32), np.ascontiguousarray(t), m)
                        for v, t, m in zip(self._vertices, self._triangles, self._geometry_masks)
                    ],
                    [(g, _IDENTITY if t is None else t, m) for g, t, m in self._placements],
                    self._nthreads,
                )
            else:
                vertices, triangles, offsets = self._mesh()
                self._scene = _raykit.Scene(
                    vertices, triangles, offsets, self._accel_name, self._test_name, self._nthreads
                )
        return self._scene

    def _point_scene(self):
        """The scene the point queries search, and the geometry id of each
        of its geometries: the scene itself, or, for an instanced scene, one
        mesh of every instance moved into place (concatenated by instance,
        so its geometry ids are instance ids), and whether each instance
        mirrors (None when there are none).

        A mirroring placement (negative determinant) turns each triangle's
        winding, and so its normal, inside out; its triangles are placed
        with their second and third corners swapped, as the glTF loader
        flattens mirrored nodes, so that the winding number, signed
        distance and occupancy see the instance's inside as inside. Its
        barycentrics then come with u and v swapped (see
        :meth:`compute_closest_points`)."""
        if not self.instanced:
            return self._built(), None, None
        if self._flat_of_instances is None:
            vertices, triangles, counts, mirrored = [], [], [0], []
            base = 0
            for g, t, _ in self._placements:
                v = self._vertices[g].astype(np.float64)
                tri = self._triangles[g]
                flip = t is not None and np.linalg.det(t[:, :3]) < 0.0
                if t is not None:
                    v = v @ t[:, :3].T + t[:, 3]
                if flip:
                    tri = tri[:, [0, 2, 1]]
                vertices.append(v.astype(np.float32))
                triangles.append(tri + np.uint32(base))
                mirrored.append(flip)
                base += len(v)
                counts.append(len(tri))
            offsets = np.cumsum(counts).astype(np.uint64)
            if base > np.iinfo(np.uint32).max or offsets[-1] > np.iinfo(np.uint32).max:
                raise ValueError("the placed instances hold more than 4294967295 vertices or triangles")
            scene = _raykit.Scene(
                np.ascontiguousarray(np.concatenate(vertices) if vertices else np.zeros((0, 3), np.float32)),
                np.ascontiguousarray(np.concatenate(triangles) if triangles else np.zeros((0, 3), np.uint32)),
                offsets.astype(np.uint32),
                "bvh8",
                "moller",
                self._nthreads,
            )
            geometry_of = np.array([g for g, _, _ in self._placements] + [INVALID_ID], dtype=np.uint32)
            self._flat_of_instances = (scene, geometry_of, np.array(mirrored + [False], dtype=bool))
        return self._flat_of_instances

    def cast_rays(self, rays, nthreads: int = 0, *, mask: int = _MASK_ALL) -> dict:
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

        Beyond Open3D: in a scene with instances (:attr:`instanced`), the
        key ``instance_ids`` ``(...)`` uint32 gives the instance hit (see
        :meth:`add_instance`); ``primitive_uvs`` refer to the geometry's
        own corners, and ``primitive_normals`` are in world space: the
        geometry's normal moved by the inverse transpose of the placement's
        3×3 part, made unit length. Under a mirroring placement (negative
        determinant) that is the outward side still: the normal of the
        placed triangle with its second and third corners swapped (as the
        glTF loader flattens mirrored nodes, and as the point queries see
        the instance), the opposite of the placed triangle's own winding.
        ``mask`` is the rays' 32-bit mask (see :meth:`add_triangles`).
        """
        flat, lead, t0 = self._rays(rays, nthreads)
        mask = _check_mask(mask, "mask")
        if self.instanced:
            t, g, inst, p, uv, n = self._built().cast_rays(
                flat, mask, _arrays.threads(nthreads, "nthreads"), _image_width(lead)
            )
        else:
            t, g, p, uv, n = self._built().cast_rays(flat, _arrays.threads(nthreads, "nthreads"), _image_width(lead))
            if mask == 0:
                t, g, p, uv, n = _missed(t, g, p, uv, n)
            inst = None
        if t0 is not None:
            t = (t + t0).astype(np.float32)
        out = {
            "primitive_uvs": _arrays.result(uv.reshape(lead + (2,))),
            "primitive_ids": _arrays.result(p.reshape(lead)),
            "geometry_ids": _arrays.result(g.reshape(lead)),
            "primitive_normals": _arrays.result(n.reshape(lead + (3,))),
            "t_hit": _arrays.result(t.reshape(lead)),
        }
        if inst is not None:
            out["instance_ids"] = _arrays.result(inst.reshape(lead))
        return out

    def test_occlusions(
        self, rays, tnear: float = 0.0, tfar: float = math.inf, nthreads: int = 0, *, mask: int = _MASK_ALL
    ):
        """Whether each ray meets a triangle with ``t`` in ``[tnear, tfar]``.

        ``rays`` as in :meth:`cast_rays`; returns a bool array of shape
        ``(...)``. Stops at the first triangle found, so it is faster than
        :meth:`cast_rays`. ``mask`` as in :meth:`cast_rays`.
        """
        tnear, tfar = float(tnear), float(tfar)
        if math.isnan(tnear) or math.isnan(tfar):
            raise ValueError(f"tnear and tfar must be numbers, got {tnear} and {tfar}")
        # A ray moved closer has its interval moved back by as much.
        flat, lead, t0 = self._rays(rays, nthreads)
        mask = _check_mask(mask, "mask")
        if self.instanced:
            hit = self._built().test_occlusions(
                flat, tnear, tfar, mask, _arrays.threads(nthreads, "nthreads"), _image_width(lead), moved=t0
            )
        else:
            hit = self._built().test_occlusions(
                flat, tnear, tfar, _arrays.threads(nthreads, "nthreads"), _image_width(lead), moved=t0
            )
            if mask == 0:
                hit[:] = False
        return _arrays.result(hit.reshape(lead))

    def count_intersections(self, rays, nthreads: int = 0, *, mask: int = _MASK_ALL):
        """Number of triangles each ray crosses for ``t >= 0``.

        ``rays`` as in :meth:`cast_rays`; returns an int32 array of shape
        ``(...)``. Each crossing counts once, rays exactly through a shared
        edge or corner included (they go to one of the triangles by exact
        edge signs, Woop et al. 2013, with ties broken alike for all of
        them), so a ray from outside crosses a closed mesh an even number of
        times. Rays with NaN or infinite coordinates count 0. ``mask`` as in
        :meth:`cast_rays`.
        """
        flat, lead, _ = self._rays(rays, nthreads, every_dtype=True)
        mask = _check_mask(mask, "mask")
        if self.instanced:
            counts = self._built().count_intersections(flat, mask, _arrays.threads(nthreads, "nthreads"))
        else:
            counts = _raykit.count_intersections(self._built(), flat, _arrays.threads(nthreads, "nthreads"))
            if mask == 0:
                counts[:] = 0
        return _arrays.result(counts.reshape(lead))

    def list_intersections(
        self, rays, nthreads: int = 0, *, max_hits: int | None = None, mask: int = _MASK_ALL
    ) -> dict:
        """Every intersection along each ray for ``t >= 0``, sorted by ``t``.

        ``rays`` as in :meth:`cast_rays`. Returns a dict in Open3D's layout:
        ``ray_splits`` ``(num_rays + 1,)`` uint32 (the hits of ray ``i`` are
        ``ray_splits[i]:ray_splits[i+1]``), ``ray_ids``, ``t_hit``,
        ``geometry_ids``, ``primitive_ids`` ``(num_intersections,)`` and
        ``primitive_uvs`` ``(num_intersections, 2)``. Beyond Open3D:
        ``max_hits`` keeps only the first ``max_hits`` hits of each ray,
        ``mask`` is as in :meth:`cast_rays`, and in a scene with instances
        ``instance_ids`` gives each hit's instance. A crossing at a shared
        edge or corner is listed once, as :meth:`count_intersections` counts
        it.
        """
        flat, _, t0 = self._rays(rays, nthreads, every_dtype=True)
        cap = _arrays.max_hits(max_hits)
        mask = _check_mask(mask, "mask")
        if self.instanced:
            splits, ray_ids, t, g, inst, p, uv = self._built().list_intersections(
                flat, cap, mask, _arrays.threads(nthreads, "nthreads")
            )
        else:
            splits, ray_ids, t, g, p, uv = _raykit.list_intersections(
                self._built(), flat, 0 if mask == 0 else cap, _arrays.threads(nthreads, "nthreads")
            )
            inst = None
        if t0 is not None:
            t = (t + t0[ray_ids]).astype(np.float32)
        out = {
            "ray_splits": _arrays.result(splits),
            "ray_ids": _arrays.result(ray_ids),
            "t_hit": _arrays.result(t),
            "geometry_ids": _arrays.result(g),
            "primitive_ids": _arrays.result(p),
            "primitive_uvs": _arrays.result(uv),
        }
        if inst is not None:
            out["instance_ids"] = _arrays.result(inst)
        return out

    def compute_closest_points(self, query_points, nthreads: int = 0, *, max_distance: float = math.inf) -> dict:
        """Closest surface point to each query point (Ericson's point-triangle
        test, nearest BVH box first).

        ``query_points``: shape ``(..., 3)``. Returns a dict of ``points``
        ``(..., 3)`` float32, ``geometry_ids`` and ``primitive_ids`` ``(...)``
        uint32, ``primitive_uvs`` ``(..., 2)`` float32 (barycentrics: the
        point is ``(1-u-v)·v0 + u·v1 + v·v2``) and ``primitive_normals``
        ``(..., 3)`` float32 (the triangle's unit normal); ``points`` are
        float64 in a scene with an :attr:`origin`. Beyond Open3D:
        ``max_distance`` limits the search; points with no surface within
        it, and points with NaN or infinite coordinates, get NaN points and
        ``INVALID_ID``. In a scene with instances the search covers every
        instance (masks do not apply) and the key ``instance_ids`` says
        which; uvs refer to the geometry's own corners and normals are as
        :meth:`cast_rays` gives them (outward under a mirroring placement).
        """
        flat, lead = _arrays.rows(query_points, "query_points", 3, shift=self._origin)
        scene, geometry_of, mirrored = self._point_scene()
        pts, g, p, uv, n, _ = _raykit.closest_points(scene, flat, float(max_distance), _arrays.threads(nthreads, "nthreads"))
        if self._origin is not None:
            pts = pts.astype(np.float64) + self._origin
        out = {}
        if geometry_of is not None:
            out["instance_ids"] = _arrays.result(g.reshape(lead))
            inst = np.minimum(g, len(geometry_of) - 1)
            # A mirrored instance's triangles are searched with their second
            # and third corners swapped: swap u and v back.
            swap = mirrored[inst]
            if swap.any():
                uv = np.where(swap[:, None], uv[:, ::-1], uv)
            g = geometry_of[inst]
        return out | {
            "points": _arrays.result(pts.reshape(lead + (3,))),
            "geometry_ids": _arrays.result(g.reshape(lead)),
            "primitive_ids": _arrays.result(p.reshape(lead)),
            "primitive_uvs": _arrays.result(uv.reshape(lead + (2,))),
            "primitive_normals": _arrays.result(n.reshape(lead + (3,))),
        }

    def compute_distance(self, query_points, nthreads: int = 0):
        """Distance from each query point to the surface: float32 ``(...)``
        (NaN for points with NaN or infinite coordinates)."""
        flat, lead = _arrays.rows(query_points, "query_points", 3, shift=self._origin)
        d = _raykit.distance(self._point_scene()[0], flat, _arrays.threads(nthreads, "nthreads"))
        return _arrays.result(d.reshape(lead))

    def compute_signed_distance(self, query_points, nthreads: int = 0, nsamples: int = 1):
        """Signed distance from each query point: float32 ``(...)``, negative
        inside.

        The sign comes from the generalized winding number (Jacobson et al.
        2013, with Barill et al.'s 2018 fast approximation), not from one
        ray's parity as in Open3D: it is right on meshes with holes,
        duplicated triangles or overlapping parts, where parity flips. It
        counts the faces' orientation, so the faces must be consistently
        oriented (outward normals); flipped faces, which parity ignores,
        change it. An instance placed by a mirroring matrix (negative
        determinant) keeps its inside: its triangles count with their
        winding reversed, as the glTF loader flattens mirrored nodes. ``nsamples`` (Open3D's number of rays) is accepted and must be odd,
        but is not needed.
        """
        _check_nsamples(nsamples)
        flat, lead = _arrays.rows(query_points, "query_points", 3, shift=self._origin)
        d = _raykit.signed_distance(self._point_scene()[0], flat, _arrays.threads(nthreads, "nthreads"))
        return _arrays.result(d.reshape(lead))

    def compute_occupancy(self, query_points, nthreads: int = 0, nsamples: int = 1):
        """Whether each query point is inside (1.0) or outside (0.0):
        float32 ``(...)``, by the generalized winding number (at least ½ is
        inside; see :meth:`compute_signed_distance`). ``nsamples`` is
        accepted for Open3D compatibility and must be odd."""
        _check_nsamples(nsamples)
        flat, lead = _arrays.rows(query_points, "query_points", 3, shift=self._origin)
        occ = _raykit.occupancy(self._point_scene()[0], flat, _arrays.threads(nthreads, "nthreads"))
        return _arrays.result(occ.reshape(lead))

    def compute_winding_number(self, query_points, nthreads: int = 0, *, beta: float = 2.0):
        """Generalized winding number of each query point (beyond Open3D):
        float32 ``(...)``, about 1 inside a closed surface, 0 outside, in
        between near holes. ``beta``: Barill et al.'s accuracy (a cluster of
        triangles is approximated by a dipole when the point is farther than
        ``beta`` times its radius; ``inf`` sums every triangle exactly)."""
        flat, lead = _arrays.rows(query_points, "query_points", 3, shift=self._origin)
        w = _raykit.winding_number(self._point_scene()[0], flat, float(beta), _arrays.threads(nthreads, "nthreads"))
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
    def origin(self) -> np.ndarray:
        """The point the scene's coordinates are stored relative to, float64
        ``(3,)`` (beyond Open3D): zero, or, for a scene whose first geometry
        lies far from the coordinates' origin (or was moved there by
        :meth:`update_vertices`), a point near its centre (a
        multiple of a power of two near its size, so float32 input moves
        exactly). Everything the scene takes and returns is in the caller's
        coordinates."""
        return np.zeros(3) if self._origin is None else self._origin.copy()

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
        ``path`` (``str``, ``bytes`` or ``os.PathLike``), for
        :meth:`load_structure` (beyond Open3D).

        Only ``"bvh8"`` and ``"bvh4"`` have a saved form. The file is
        versioned and checksummed, holds a checksum of the mesh, and is
        written to a temporary file then renamed over ``path``. Raises
        ``OSError`` when it cannot be written and ``ValueError`` for a scene
        without triangles, a structure with no saved form, or a scene with
        instances (whose two-level structure has no saved form).
        """
        self._not_instanced("save")
        self._built().save(fspath(path))

    def load_structure(self, path) -> None:
        """Load the ray acceleration structure of the geometries added so
        far from ``path`` (written by :meth:`save` for the same mesh) instead
        of building it (beyond Open3D).

        The file's structure and triangle test replace ``accel`` and
        ``test``. Raises ``OSError`` (``FileNotFoundError``) when the file
        cannot be read and ``ValueError``, naming the byte offset and field,
        when it is damaged or was saved for another mesh (its mesh
        checksum differs). Adding a geometry afterwards builds a new
        structure at the next query. Not for a scene with instances.
        """
        self._not_instanced("load_structure")
        vertices, triangles, offsets = self._mesh()
        scene = _raykit.Scene(
            vertices,
            triangles,
            offsets,
            self._accel_name,
            self._test_name,
            self._nthreads,
            fspath(path),
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
        structure has no refit (only ``"bvh8"`` and ``"bvh4"`` have), or the
        model moved too far for the scaling and placement it was built with
        (a Plücker or projection model moved far away, any model shrunk to a
        tiny size), it is rebuilt. The point-query structure is rebuilt at
        its next use. Returns ``{"rebuilt": bool, "degradation": float}``
        (degradation NaN when the structure was not refit), or ``None``
        when no structure was built yet (it is built at the next query). A
        scene of this geometry alone, without ``origin=``, chooses its
        :attr:`origin` again from the new positions, as if the geometry had
        been added there.
        """
        gid = self._geometry_id(geometry_id)
        raw = _arrays.reals(vertex_positions, "vertex_positions", last=3)
        old, old_origin = self._vertices[gid], self._geometry_origins[gid]
        if raw.shape != old.shape:
            raise ValueError(f"vertex_positions must have shape {old.shape} (geometry {gid}'s), got {raw.shape}")
        t = self._triangles[gid]
        own = old_origin
        # A scene of this one geometry, placed where it is, with an origin
        # chosen from it, chooses again: a mesh moved far away keeps its
        # float32 precision as it would added there.
        alone = len(self._vertices) == 1 and len(self._placements) == 1 and self._placements[0][1] is None
        if alone and not getattr(self, "_origin_given", False):
            own = _far_origin(raw[_used(t, len(raw))])
        shifted = _shifted(raw, own)
        v = _check_coordinates(shifted, t)
        _warn_if_coarse(shifted[_used(t, len(raw))], f"geometry {gid}")
        self._vertices[gid] = v
        self._geometry_origins[gid] = own
        self._sphere_of_scene = None
        if alone:
            self._origin = own
        self._flat_of_instances = None
        if self._scene is None:
            return None
        if self.instanced:
            # The geometry's own BVH is rebuilt with the scene at the next query.
            self._scene = None
            return {"rebuilt": True, "degradation": math.nan}
        try:
            limit = {} if max_degradation is None else {"max_degradation": float(max_degradation)}
            return self._scene.refit(np.ascontiguousarray(self._all_vertices()), self._nthreads, **limit)
        except BaseException:
            self._vertices[gid] = old
            self._geometry_origins[gid] = old_origin
            self._sphere_of_scene = None
            if alone:
                self._origin = old_origin
            raise

    def stats(self) -> dict:
        """Size and quality of the acceleration structure: nodes, leaves,
        bytes, node_bytes, depth, sah_cost, triangle_refs (builds it if
        needed); for a scene with instances, the triangles stored (each
        geometry once) and placed (as a flattened scene would store them)."""
        scene = self._built()
        if self.instanced:
            return {"stored_triangles": scene.stored_triangles, "placed_triangles": scene.placed_triangles}
        return scene.stats()

    def _not_instanced(self, what: str) -> None:
        if self.instanced:
            raise ValueError(f"{what}: a scene with instances has no saved form; only single-level scenes do")


def _used(t: np.ndarray, n: int) -> np.ndarray:
    """Which of ``n`` vertices the triangles ``t`` use (indices past ``n``
    left for the engine to refuse)."""
    used = np.zeros(n, dtype=bool)
    used[t[t < n]] = True
    return used


def _shifted(raw: np.ndarray, shift: np.ndarray | None) -> np.ndarray:
    """Vertices ``raw`` in float64, less ``shift`` (None for zero)."""
    v = raw.astype(np.float64)
    if shift is not None:
        v -= shift
    return v


def _check_coordinates(v: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Vertices ``v`` (float64, in the scene's coordinates) of triangles
    ``t`` as the engine's C-contiguous float32. Refuses used vertices that
    are not finite, or beyond the coordinates a mesh may hold (the f32
    products of the ray and winding-number tests overflow there), naming
    the first. Vertices no triangle uses may be anything, as in Open3D and
    trimesh: they are moved onto a used vertex (or zero), where they change
    no box."""
    nan = ~np.isfinite(v).all(axis=1)
    far = ~nan & (np.abs(v) > _raykit.MAX_COORDINATE).any(axis=1)
    if not (nan.any() or far.any()):
        return np.ascontiguousarray(v, dtype=np.float32)
    used = _used(t, len(v))
    if (nan & used).any():
        raise ValueError(f"vertex {int(np.argmax(nan & used))} has a NaN or infinite coordinate")
    if (far & used).any():
        raise ValueError(
            f"vertex {int(np.argmax(far & used))} has a coordinate beyond ±{_raykit.MAX_COORDINATE:.0e}, where the "
            "f32 products of the ray and winding-number tests overflow; move or scale the mesh"
        )
    v = v.copy()
    v[nan | far] = v[used][0] if used.any() else 0
    return np.ascontiguousarray(v, dtype=np.float32)


def _placed_corners(box, m: np.ndarray | None) -> np.ndarray | None:
    """The eight corners of ``box`` (``(lo, hi)``; None when the geometry
    is empty, giving None) moved by the 3×4 transform ``m`` (None: where
    they are), as ``(8, 3)`` float64."""
    if box is None:
        return None
    lo, hi = box
    c = np.array([[(lo, hi)[(k >> a) & 1][a] for a in range(3)] for k in range(8)], dtype=np.float64)
    return c if m is None else c @ m[:, :3].T + m[:, 3]


def _check_placement(v: np.ndarray, corners: np.ndarray, m: np.ndarray, iid: int, gid: int) -> None:
    """Refuse instance ``iid`` when its transform ``m`` (3×4) places a
    vertex ``v`` of geometry ``gid`` beyond the coordinates a mesh may hold,
    as :func:`_check_coordinates` refuses them, naming the instance: the
    geometry's box's placed ``corners`` (:func:`_placed_corners`) first,
    the vertices themselves only where a corner lies beyond."""
    limit = float(_raykit.MAX_COORDINATE)
    if (np.abs(corners) <= limit).all():
        return
    placed = v.astype(np.float64) @ m[:, :3].T + m[:, 3]
    far = (np.abs(placed) > limit).any(axis=1)
    if far.any():
        raise ValueError(
            f"instance {iid}: places vertex {int(np.argmax(far))} of geometry {gid} beyond ±{limit:.0e}, where "
            "the f32 products of the ray and winding-number tests overflow; move or scale the placement"
        )


#: How far from the origin, in its own sizes, a model may lie before float32
#: keeps it to more than 1/65,536 of its size (2**8 sizes: float32 has 24 bits).
_COARSE_SIZES = 256.0


def _warn_if_coarse(v: np.ndarray, what: str) -> None:
    """Warn when the engine's float32 keeps the points ``v`` (float64, in
    the coordinates they are stored in) coarsely: their box's centre lies
    more than :data:`_COARSE_SIZES` of its sizes from zero. A scene chooses
    its origin from its first geometry; one added, moved or placed far from
    it afterwards keeps only float32's precision there."""
    finite = v[np.isfinite(v).all(axis=1)]
    if not len(finite):
        return
    lo, hi = finite.min(axis=0), finite.max(axis=0)
    far, size = float(np.abs((lo + hi) / 2).max()), float((hi - lo).max())
    if size == 0.0 or far <= _COARSE_SIZES * size:
        return
    step = float(np.spacing(np.float32(far)))
    warnings.warn(
        f"{what} lies {far:.6g} from the scene's origin, {far / size:.3g} times its size: float32 keeps its "
        f"vertices {step:.3g} apart there ({step / size:.1e} of its size). Give the scene an origin near it "
        "(RaycastingScene(origin=...)) to keep its precision.",
        stacklevel=3,
    )


def _far_origin(v: np.ndarray) -> np.ndarray | None:
    """The origin a scene whose first geometry has vertices ``v`` keeps:
    None when its box's centre is within four times its size of zero or it
    has no finite vertices, else the centre rounded to a multiple of the
    largest power of two not above the size (float32 coordinates on that
    grid move by it exactly)."""
    finite = v[np.isfinite(v).all(axis=1)].astype(np.float64)
    if not len(finite):
        return None
    lo, hi = finite.min(axis=0), finite.max(axis=0)
    centre = (lo + hi) / 2
    far = float(np.abs(centre).max())
    size = max(float((hi - lo).max()), far * 2.0**-40)
    if far <= 4 * size:
        return None
    step = 2.0 ** math.floor(math.log2(size))
    return np.round(centre / step) * step


def _origin_of(origin) -> np.ndarray:
    """``origin=`` as three finite float64 coordinates, or ValueError."""
    o = np.asarray(_arrays.to_numpy(origin))
    if o.dtype.kind not in "fiu" or o.shape != (3,) or not np.isfinite(o).all():
        raise ValueError(f"origin must be three finite numbers, got {origin!r}")
    return o.astype(np.float64)


def _missed(t, g, p, uv, n):
    """The arrays of ``cast_rays`` for rays that all miss."""
    return (
        np.full_like(t, np.inf),
        np.full_like(g, INVALID_ID),
        np.full_like(p, INVALID_ID),
        np.zeros_like(uv),
        np.zeros_like(n),
    )


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


def _signature(*names: str) -> inspect.Signature:
    kind = inspect.Parameter.POSITIONAL_OR_KEYWORD
    return inspect.Signature([inspect.Parameter(n, kind) for n in names])


# Open3D's two forms of create_rays_pinhole.
_PINHOLE_MATRICES = _signature("intrinsic_matrix", "extrinsic_matrix", "width_px", "height_px")
_PINHOLE_FOV = _signature("fov_deg", "center", "eye", "up", "width_px", "height_px")


def _pinhole(*args, **kwargs) -> np.ndarray:
    by_fov = "fov_deg" in kwargs or (args and np.ndim(_arrays.to_numpy(args[0])) == 0)
    form = _PINHOLE_FOV if by_fov else _PINHOLE_MATRICES
    unknown = sorted(set(kwargs) - set(form.parameters))
    if unknown:
        raise TypeError(f"create_rays_pinhole{form}: unexpected keyword argument(s) {unknown}")
    try:
        bound = form.bind(*args, **kwargs).arguments
    except TypeError as e:
        raise TypeError(f"create_rays_pinhole{form}: {e}") from None
    if by_fov:
        width, height = int(bound["width_px"]), int(bound["height_px"])
        fov = float(bound["fov_deg"])
        if not 0.0 < fov < 180.0:
            raise ValueError(f"fov_deg must be between 0 and 180 degrees, got {fov}")
        focal = 0.5 * width / math.tan(math.radians(fov) * 0.5)
        intrinsic = np.array([[focal, 0, 0.5 * width], [0, focal, 0.5 * height], [0, 0, 1]])
        extrinsic = _look_at(bound["center"], bound["eye"], bound["up"])
    else:
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
    try:
        camera = pixels @ np.linalg.inv(intrinsic).T
    except np.linalg.LinAlgError:
        raise ValueError(f"the intrinsic matrix is singular: {intrinsic.tolist()}") from None
    directions = camera @ rotation
    rays = np.empty((height, width, 6), dtype=np.float32)
    rays[..., :3] = origin
    rays[..., 3:] = directions
    return rays
