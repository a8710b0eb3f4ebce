"""Visibility culling of CAD models (raykit-cull: directed distance field and front propagation)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import _arrays, _raykit
from .files import PATH_TYPES, load_mesh


class CullResult(NamedTuple):
    """What :func:`cull` found."""

    keep: np.ndarray
    """``(m,)`` bool: the triangles that can be seen from outside (or are not clearly hidden)."""
    part_keep: np.ndarray
    """``(p,)`` bool: the parts with at least one kept triangle."""
    stats: dict
    """Grid size and spacing, counts and times of the run."""


def cull(
    vertices,
    triangles=None,
    parts=None,
    *,
    resolution: int = 128,
    conservative: bool = True,
    threads: int = 0,
) -> CullResult:
    """Which triangles of a model no viewpoint outside it can see (global
    visibility culling): a directed distance field on a grid
    of ``resolution`` points along the longest axis, front propagation from
    the outside, and the triangles outside points reach.

    ``vertices`` and ``triangles``: ``(n, 3)`` floats and ``(m, 3)``
    integers, or a mesh file path (``triangles`` and ``parts`` then come
    from the file). ``parts``: ``(m,)`` integers grouping triangles into
    parts, ids below the number of triangles or 2**20, whichever is larger.
    ``conservative`` (default, as ``raykit cull``) keeps what the evidence
    does not clearly hide.

    Warning: ``conservative=False`` applies the distance-field rule alone
    (Min 2008, reference [003] of the README; ``raykit cull --mode
    paper``) and removes triangles that are visible from outside, many of
    them on real models: on 2CylinderEngine at ``resolution=128``, 10,876
    of the 23,401 triangles the ray-traced ground truth (``raykit cull
    --evaluate``) sees. Use it to study the rule, not to decide what may
    be dropped.
    """
    if isinstance(vertices, PATH_TYPES):
        if triangles is not None or parts is not None:
            raise ValueError("a mesh file carries its own triangles and parts")
        vertices, triangles, parts = load_mesh(vertices)
    if triangles is None:
        raise ValueError("cull needs triangles (or a mesh file path)")
    v = _arrays.floats(vertices, "vertices", last=3)
    if v.ndim != 2:
        raise ValueError(f"vertices must have shape (n, 3), got {v.shape}")
    t = _arrays.indices(triangles, "triangles")
    p = None
    if parts is not None:
        p = np.asarray(_arrays.to_numpy(parts))
        if p.dtype.kind not in "iu" or p.ndim != 1:
            raise ValueError(f"parts must be a 1-D integer array, got dtype {p.dtype} and shape {p.shape}")
        if p.size and p.min() < 0:
            raise ValueError("parts must not be negative")
        if p.size and int(p.max()) > np.iinfo(np.uint32).max:
            raise ValueError(f"parts: the largest part id is {int(p.max())}, above {np.iinfo(np.uint32).max}")
        p = np.ascontiguousarray(p, dtype=np.uint32)
    keep, part_keep, stats = _raykit.cull(v, t, p, _arrays.whole(resolution, "resolution"), bool(conservative), _arrays.threads(threads))
    return CullResult(keep, part_keep, stats)
