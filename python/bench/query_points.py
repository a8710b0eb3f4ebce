"""What the point-query benchmarks share: the full dragon's default path,
the query points (uniform in the mesh's box grown by 10% per side, an SDF
grid's samples, or near the surface: a random vertex moved by up to 1% of
the box diagonal) and the median of timed runs after a warm-up."""

from __future__ import annotations

import os
import statistics
import time
from pathlib import Path

import numpy as np

DRAGON = os.environ.get(
    "RAYKIT_DRAGON", str(Path(__file__).resolve().parents[2] / "data-cache" / "dragon_vrip.ply.gz")
)


def query_points(v: np.ndarray, n: int, near: bool, rng: np.random.Generator) -> np.ndarray:
    """``n`` float32 points for the mesh of vertices ``v``."""
    lo, hi = v.min(0).astype(np.float64), v.max(0).astype(np.float64)
    diag = float(np.linalg.norm(hi - lo))
    pad = 0.1 * (hi - lo)
    points = (lo - pad + rng.random((n, 3)) * (hi - lo + 2 * pad)).astype(np.float32)
    if near:
        pick = v[rng.integers(0, len(v), n)].astype(np.float64)
        step = rng.normal(size=(n, 3))
        step *= 0.01 * diag * rng.random((n, 1)) / np.linalg.norm(step, axis=1, keepdims=True)
        points = (pick + step).astype(np.float32)
    return points


def timed(fn, reps: int):
    """The median seconds of ``reps`` runs of ``fn`` after one warm-up, and
    the last run's result."""
    fn()
    times = []
    out = None
    for _ in range(reps):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out
