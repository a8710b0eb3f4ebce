"""Mesh files through raykit-io's loaders."""

from __future__ import annotations

import os
import warnings

import numpy as np

from . import _raykit

#: What a path argument may be, as ``open`` takes it.
PATH_TYPES = (str, bytes, os.PathLike)


def fspath(path, name: str = "path") -> str:
    """A path argument (``str``, ``bytes`` or ``os.PathLike``, as ``open``
    takes) as ``str``: bytes decoded as ``os.fsdecode`` does, so that the
    extension gets back the same bytes."""
    if not isinstance(path, PATH_TYPES):
        raise TypeError(f"{name} must be a str, bytes or os.PathLike path, got {type(path).__name__}")
    return os.fsdecode(path)


def load_mesh(path: str | bytes | os.PathLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Load a triangle mesh: OBJ (+MTL), PLY (ASCII or binary, also
    ``.ply.gz``), STL, OFF, glTF or GLB, chosen by the extension. ``path``
    is a ``str``, ``bytes`` or ``os.PathLike``, as ``open`` takes.

    Returns ``(vertices, triangles, parts)``: ``(n, 3)`` float32 positions
    (glTF node transforms applied), ``(m, 3)`` uint32 corner indices and
    ``(m,)`` uint32 part index per triangle (glTF node, OBJ object or group;
    all 0 when the file has no parts).

    Vertices far from the coordinates' origin (a first vertex with a
    coordinate of 65,536 or more, as UTM and other projected coordinates
    are) come as float64 instead, read to the file's digits: float32 is
    half a metre apart at UTM northings. This holds for OBJ, OFF and PLY
    (ASCII, or binary ``double``), and for glTF placed far by its nodes'
    transforms (a UTM or geocentric translation on the root node, as
    geospatial exporters write), which are composed in float64 from the
    file's digits. STL, and glTF vertex data themselves, store float32.

    A file that cannot be read raises ``FileNotFoundError`` or ``OSError``;
    one whose contents are wrong raises ``ValueError``. Messages name the
    file and the line, byte offset or JSON element, as ``raykit`` prints
    them.
    """
    vertices, triangles, parts, origin = _raykit.load_mesh(fspath(path))
    if any(origin):
        vertices = vertices.astype(np.float64) + np.asarray(origin)
    return vertices, triangles, parts


def load_gltf_instances(path: str | bytes | os.PathLike) -> tuple[list, list]:
    """Load a glTF or GLB file with its instancing kept (beyond Open3D):
    each glTF mesh once, and the nodes that place them.

    Returns ``(geometries, instances)``: ``geometries`` a list of
    ``(vertices (n, 3) float32, triangles (m, 3) uint32)`` in each mesh's
    own coordinates; ``instances`` a list of ``(geometry, matrix, node,
    name)``, one per node with a mesh (and per copy of an
    ``EXT_mesh_gpu_instancing`` node), with the (3, 4) float64
    object-to-world matrix (composed in float64 from the file's digits),
    the node's index in the file and its name, in
    the order :func:`load_mesh` numbers its parts. A scene that places a
    large mesh many times, too large for :func:`load_mesh` to flatten,
    loads this way with each mesh stored once. The loader's warnings are
    issued as ``UserWarning``; errors as in :func:`load_mesh`.
    """
    geometries, instances, notes = _raykit.load_gltf_instances(fspath(path))
    for note in notes:
        warnings.warn(f"{fspath(path)}: {note}", stacklevel=2)
    return geometries, instances
