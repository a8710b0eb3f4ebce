"""Pictures of a scene through raykit-render's renderer."""

from __future__ import annotations

import numpy as np

from . import _arrays, _raykit
from .raycasting import RaycastingScene


def _vec(x, name, origin=None):
    """Three numbers as a tuple, moved by ``-origin`` (the scene's, so that
    a point given in the caller's coordinates lands in the scene's)."""
    if x is None:
        return None
    a = np.asarray(_arrays.to_numpy(x), dtype=np.float64).reshape(-1)
    if a.shape != (3,):
        raise ValueError(f"{name} must be three numbers, got {x!r}")
    if origin is not None:
        a = a - origin
    return tuple(float(c) for c in a)


def render(
    scene,
    width: int = 800,
    height: int = 600,
    *,
    eye=None,
    target=None,
    up=(0.0, 1.0, 0.0),
    fov: float = 40.0,
    samples_per_pixel: int = 1,
    shadows: bool = True,
    threads: int = 0,
    window: tuple[int, int, int, int] | None = None,
) -> np.ndarray:
    """Render ``scene`` to an ``(height, width, 3)`` uint8 sRGB image.

    ``scene``: a :class:`raykit.RaycastingScene` without instances (its
    acceleration structure is reused) or any mesh
    ``RaycastingScene.add_triangles`` takes; a scene with instances is a
    ``ValueError``. The
    camera is a pinhole at ``eye`` looking at ``target`` (default: the
    bounding box centre) with ``up`` and vertical field of view ``fov``
    degrees; without ``eye`` it frames the triangles as ``raykit render``
    frames a mesh file. Shading: Blinn-Phong of the triangles' normals lit
    by one white point light above the scene, hard shadows by shadow rays
    (``shadows=False`` turns them off), ``samples_per_pixel`` jittered
    samples; the same renderer ``raykit serve`` streams.

    ``window=(x, y, w, h)`` renders only that rectangle of the
    ``width`` × ``height`` frame, as an ``(h, w, 3)`` image whose pixels
    equal the whole frame's bit for bit (so rectangles rendered apart, as
    :func:`raykit.distributed.render` does, assemble into the whole image).
    """
    if not isinstance(scene, RaycastingScene):
        mesh = scene
        scene = RaycastingScene()
        scene.add_triangles(mesh)
    if scene.instanced:
        raise ValueError(
            "render draws a scene without instances; this one has add_instance placements "
            "(render each geometry's triangles placed in one mesh instead)"
        )
    return _raykit.render(
        scene._built(),
        _arrays.whole(width, "width"),
        _arrays.whole(height, "height"),
        _vec(eye, "eye", scene.origin),
        _vec(target, "target", scene.origin),
        _vec(up, "up"),
        float(fov),
        _arrays.whole(samples_per_pixel, "samples_per_pixel"),
        bool(shadows),
        _arrays.threads(threads),
        None if window is None else tuple(_arrays.count(c, "window") for c in window),
    )
