"""The time of one call on a few rays or points, raykit against Open3D's
RaycastingScene, in one process on the same rays: what a simulation loop
that casts a ray or a handful per step waits for per call, where the
engine's own work is a small part.

    python python/bench/bench_per_call.py [MESH] [--n 1,16,256] [--calls 20000] [--rounds 5]

Default mesh: the Stanford bunny in data/meshes. Rays are incoherent
(from a sphere around the mesh towards random points of its box), float32
rows of six, as both engines take them without a copy; points uniform in
the box grown by 10% per side. Each cell is the
median over ``--rounds`` rounds of the mean time of ``--calls`` calls, the
engines taking turns within each round, after a warm-up.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np
from bench_first_call import QUERIES, rays_towards
from query_points import query_points

import raykit

BUNNY = str(Path(__file__).resolve().parents[2] / "data" / "meshes" / "bunny_3674.obj")


def per_call_us(fn, calls: int) -> float:
    """Mean microseconds of ``calls`` calls of ``fn``."""
    start = time.perf_counter()
    for _ in range(calls):
        fn()
    return (time.perf_counter() - start) / calls * 1e6


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh", nargs="?", default=os.environ.get("RAYKIT_BUNNY", BUNNY))
    ap.add_argument("--n", default="1,16,256", help="rays per call (comma-separated)")
    ap.add_argument("--calls", type=int, default=20000, help="calls timed per round")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    import open3d as o3d

    v, f, _ = raykit.load_mesh(args.mesh)
    v = np.ascontiguousarray(v, dtype=np.float32)
    f = np.ascontiguousarray(f, dtype=np.uint32)
    ours = raykit.RaycastingScene()
    ours.add_triangles(v, f)
    theirs = o3d.t.geometry.RaycastingScene()
    theirs.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(f))
    lo, hi = v.min(0).astype(np.float64), v.max(0).astype(np.float64)
    rng = np.random.default_rng(5)
    print(
        f"{os.path.basename(args.mesh)}: {len(f):,} triangles; µs per call, median of {args.rounds} rounds "
        f"of {args.calls:,} calls"
    )
    print("| rays or points | query | nthreads | raykit µs | Open3D µs | raykit ÷ Open3D (speed) |")
    print("|--:|---|--:|--:|--:|--:|")
    for n in [int(x) for x in args.n.split(",")]:
        rays = rays_towards(lo, hi, n, rng)
        points = query_points(v, n, False, rng)
        for query in QUERIES:
            arg = points if query.startswith("compute") else rays
            tensor = o3d.core.Tensor(arg)
            for nthreads in (0, 1):
                calls = {
                    "raykit": lambda: getattr(ours, query)(arg, nthreads=nthreads),
                    "open3d": lambda: getattr(theirs, query)(tensor, nthreads=nthreads),
                }
                times = {engine: [] for engine in calls}
                for fn in calls.values():
                    fn()
                for _ in range(args.rounds):
                    for engine, fn in calls.items():
                        times[engine].append(per_call_us(fn, args.calls))
                a, b = statistics.median(times["raykit"]), statistics.median(times["open3d"])
                print(f"| {n} | {query} | {nthreads} | {a:.1f} | {b:.1f} | {b / a:.2f}× |", flush=True)


if __name__ == "__main__":
    main()
