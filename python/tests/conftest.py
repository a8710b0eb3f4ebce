"""Shared fixtures: the real meshes and DEMs of the test data folder
(``data/`` in the repository, or ``RAYKIT_SHARED_DATA``), and a
float64 brute-force ray/triangle reference."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


def shared_data() -> Path:
    root = Path(os.environ.get("RAYKIT_SHARED_DATA", REPO / "data"))
    if not (root / "meshes").is_dir():
        raise RuntimeError(
            f"the test data folder {root} is missing: it is data/ in the repository "
            "(RAYKIT_SHARED_DATA overrides it)"
        )
    return root


def raykit_cli() -> str:
    """The ``raykit`` command line, for tests that compare with it:
    ``RAYKIT_CLI``, else the repository's release or debug build, else
    ``raykit`` on the PATH. Without one the test fails, naming the build
    to run (``scripts/test`` builds it before the Python suite)."""
    given = os.environ.get("RAYKIT_CLI")
    if given:
        return given
    for build in ("release", "debug"):
        exe = REPO / "target" / build / "raykit"
        if exe.is_file() and os.access(exe, os.X_OK):
            return str(exe)
    found = shutil.which("raykit")
    if found is None:
        pytest.fail(
            "the raykit command line is not built: run `cargo build --release` in the "
            "repository, or set RAYKIT_CLI to the binary"
        )
    return found


@pytest.fixture(scope="session")
def data() -> Path:
    return shared_data()


@pytest.fixture(scope="session")
def bunny(data):
    import raykit

    return raykit.load_mesh(data / "meshes" / "bunny_3674.obj")


@pytest.fixture(scope="session")
def dragon(data):
    import raykit

    return raykit.load_mesh(data / "meshes" / "dragon_vrip_res4.ply.gz")


def rays_at(vertices: np.ndarray, n: int, seed: int) -> np.ndarray:
    """``n`` rays from a sphere around the mesh towards random points of its
    bounding box (unnormalised directions: t is in their length)."""
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(axis=0).astype(np.float64), vertices.max(axis=0).astype(np.float64)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo)
    u = rng.normal(size=(n, 3))
    origins = centre + radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    targets = lo + rng.random((n, 3)) * (hi - lo)
    dirs = (targets - origins) * rng.uniform(0.5, 2.0, size=(n, 1))
    return np.concatenate([origins, dirs], axis=1).astype(np.float32)


def brute_force(vertices, triangles, rays) -> tuple[np.ndarray, np.ndarray]:
    """Nearest ``t`` and triangle of each ray by Möller and Trumbore 1997 in
    float64 over every triangle (inf and -1 on a miss)."""
    v = vertices.astype(np.float64)
    a, b, c = v[triangles[:, 0]], v[triangles[:, 1]], v[triangles[:, 2]]
    e1, e2 = b - a, c - a
    best_t = np.full(len(rays), np.inf)
    best_i = np.full(len(rays), -1)
    for k, r in enumerate(rays.astype(np.float64)):
        o, d = r[:3], r[3:]
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            s = o - a
            u = np.einsum("ij,ij->i", s, p) * inv
            q = np.cross(s, e1)
            w = (q @ d) * inv
            t = np.einsum("ij,ij->i", e2, q) * inv
        ok = (det != 0) & (u >= 0) & (w >= 0) & (u + w <= 1) & (t >= 0)
        if ok.any():
            i = np.flatnonzero(ok)[np.argmin(t[ok])]
            best_t[k], best_i[k] = t[i], i
    return best_t, best_i


def ties(triangles, a, b) -> np.ndarray:
    """Whether triangles ``a`` and ``b`` (index arrays) are the same or share
    a corner: where two engines may each report one of them for a ray near
    the shared edge or vertex (raykit's triangle tests count a band of 2^-8
    of a triangle beyond its edges as hits, so that no ray slips between
    neighbours)."""
    ta, tb = triangles[a], triangles[b]
    return (ta[:, :, None] == tb[:, None, :]).any(axis=(1, 2))
