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
    try:
        a = np.asarray(_arrays.to_numpy(x), dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be three numbers, got {x!r}") from None
    if a.shape != (3,):
        raise ValueError(f"{name} must be three numbers, got {x!r}")
    if origin is not None:
        a = a - origin
    return tuple(float(c) for c in a)


def _up(up, scene, eye, target) -> tuple[float, float, float]:
    """``up`` (``(0, 1, 0)`` when not given) checked as ``raykit render``
    checks ``--up``: three finite numbers, not all zero, given only with
    an eye, and with an eye not parallel to the view from ``eye`` to
    ``target`` (the bounding box centre by default)."""
    u = np.array([0.0, 1.0, 0.0]) if up is None else np.asarray(_vec(up, "up"))
    with np.errstate(over="ignore"):
        finite = np.isfinite(u.astype(np.float32)).all()  # as the engine takes it
    if not finite or not u.any():
        raise ValueError(f"up must be three finite numbers, not all zero, got {tuple(u.tolist())}")
    if eye is None:
        if up is None:
            return (0.0, 1.0, 0.0)
        raise ValueError(
            "up applies to a camera given by eye=; without eye the default view frames the scene "
            "with y up, as raykit render does (give eye, and target, with up)"
        )
    if target is None:
        v = scene._all_vertices()
        if not len(v):
            return tuple(float(c) for c in u)  # nothing to look at: the engine says so
        target = (v.min(axis=0) + v.max(axis=0)) * np.float32(0.5)
    with np.errstate(over="ignore", invalid="ignore"):
        view = np.asarray(target, np.float64) - np.asarray(eye, np.float64)
        norm = np.linalg.norm(view)
        # A camera without a direction is the engine's to refuse.
        across = np.linalg.norm(np.cross(view / norm, u / np.linalg.norm(u))) if norm > 0 and np.isfinite(norm) else 1.0
        if across < 1e-4:
            raise ValueError(
                f"up {tuple(u.tolist())} is parallel to the view direction {tuple((view / norm).tolist())}: "
                "the image's roll is undefined; give an up across the view"
            )
    return tuple(float(c) for c in u)


def render(
    scene,
    width: int = 800,
    height: int = 600,
    *,
    eye=None,
    target=None,
    up=None,
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
    bounding box centre) with vertical field of view ``fov`` degrees and
    ``up`` (default ``(0, 1, 0)``) the direction that is up in the image;
    ``up``, given or not, must be finite, not zero and not parallel to the
    view direction (the image's roll would be undefined), or
    ``ValueError``, as the command line checks ``--up``. Without
    ``eye`` it frames the triangles as ``raykit render`` frames a mesh
    file, from a direction chosen for y up, so ``up`` is refused there
    (give ``eye`` with it). Shading: Blinn-Phong of the triangles' normals lit
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
    eye, target = _vec(eye, "eye", scene.origin), _vec(target, "target", scene.origin)
    return _raykit.render(
        scene._built(),
        _arrays.whole(width, "width"),
        _arrays.whole(height, "height"),
        eye,
        target,
        _up(up, scene, eye, target),
        float(fov),
        _arrays.whole(samples_per_pixel, "samples_per_pixel"),
        bool(shadows),
        _arrays.threads(threads),
        None if window is None else tuple(_arrays.count(c, "window") for c in window),
    )
