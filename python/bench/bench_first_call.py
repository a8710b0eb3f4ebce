"""The time from a new scene to its first answer (add_triangles, the build
the query needs, the query), raykit against Open3D's RaycastingScene, in one
process on the same input: what a script that asks one question of a mesh
waits for. The other benchmarks time warm scenes, with the builds left out.

    python python/bench/bench_first_call.py [MESH] [--n 10000,100000] [--threads 2] [--reps 2]

Default mesh: the full Stanford dragon (data-cache/dragon_vrip.ply.gz, or
RAYKIT_DRAGON). Rays are incoherent (from a sphere around the mesh towards
random points of its box); points uniform in the box grown by 10% per side.
Each cell is the fastest of ``--reps`` fresh scenes, the engines taking
turns.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from query_points import DRAGON, query_points

import raykit

QUERIES = [
    "cast_rays",
    "test_occlusions",
    "count_intersections",
    "list_intersections",
    "compute_closest_points",
    "compute_distance",
    "compute_signed_distance",
    "compute_occupancy",
]


def rays_towards(lo: np.ndarray, hi: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` float32 rays from a sphere around the box towards its points."""
    centre, radius = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2
    u = rng.normal(size=(n, 3))
    origins = centre + 2 * radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    d = lo + rng.random((n, 3)) * (hi - lo) - origins
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.concatenate([origins, d], axis=1).astype(np.float32)


def first_answer(engine: str, v, f, query: str, arg, threads: int) -> float:
    """Seconds from a new scene to the answer of ``query`` on ``arg``."""
    start = time.perf_counter()
    if engine == "raykit":
        scene = raykit.RaycastingScene()
        scene.add_triangles(v, f)
        getattr(scene, query)(arg, nthreads=threads)
    else:
        import open3d as o3d

        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(f))
        getattr(scene, query)(o3d.core.Tensor(arg), nthreads=threads)
    return time.perf_counter() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh", nargs="?", default=DRAGON)
    ap.add_argument("--n", default="10000,100000", help="rays or points per query (comma-separated)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=2)
    args = ap.parse_args()
    v, f, _ = raykit.load_mesh(args.mesh)
    v = np.ascontiguousarray(v, dtype=np.float32)
    lo, hi = v.min(0).astype(np.float64), v.max(0).astype(np.float64)
    rng = np.random.default_rng(3)
    print(f"{os.path.basename(args.mesh)}: {len(f):,} triangles, {args.threads} threads, best of {args.reps}")
    print("| n | query | raykit ms | Open3D ms | raykit ÷ Open3D (speed) |")
    print("|--:|---|--:|--:|--:|")
    for n in [int(x) for x in args.n.split(",")]:
        points = query_points(v, n, False, rng)
        rays = rays_towards(lo, hi, n, rng)
        for query in QUERIES:
            arg = points if query.startswith("compute") else rays
            best = {"raykit": np.inf, "open3d": np.inf}
            for _ in range(args.reps):
                for engine in best:
                    best[engine] = min(best[engine], first_answer(engine, v, f, query, arg, args.threads))
            ours, theirs = best["raykit"] * 1e3, best["open3d"] * 1e3
            print(f"| {n:,} | {query} | {ours:.0f} | {theirs:.0f} | {theirs / ours:.2f}× |", flush=True)


if __name__ == "__main__":
    main()
