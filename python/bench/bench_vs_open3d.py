"""raykit, Open3D and embreex from Python on the same rays, in one process.

    python python/bench/bench_vs_open3d.py [MESH] [--rays N] [--reps R] [--threads 1,2]

In the environment scripts/test-python makes (raykit, Open3D):

    scripts/test-python && target/py-venv/bin/pip install embreex
    target/py-venv/bin/python python/bench/bench_vs_open3d.py

Default mesh: the full Stanford dragon (871,414 triangles) from
data-cache/dragon_vrip.ply.gz in the checkout, which
scripts/fetch-bench-data fetches (or RAYKIT_DRAGON).
Ray sets: `primary` (a 1024 × 1024 pinhole camera framing the mesh, as
Open3D's create_rays_pinhole makes them, shape (1024, 1024, 6)) and `incoherent` (from a sphere
around the mesh towards random points of its bounding box). Queries:
nearest hit (cast_rays) and occlusion (test_occlusions). Thread counts:
raykit's and Open3D's nthreads per call; embreex's run() traces in the
calling thread, so it appears in the 1-thread rows only. Every time is the
median of R runs after one warm-up, the build excluded (timed apart);
the answers are checked against each other (hit/miss agreement).

The machine's load is printed with the table (`uptime`): on a shared
machine rerun when it is quiet.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import time
from pathlib import Path

import numpy as np

import raykit

DRAGON = os.environ.get(
    "RAYKIT_DRAGON", str(Path(__file__).resolve().parents[2] / "data-cache" / "dragon_vrip.ply.gz")
)


def interleaved(engines: dict, reps: int) -> tuple[dict, dict, dict]:
    """Median wall-clock and CPU seconds (all the process's threads) of each
    engine's call and its last answer, the engines taking turns within each
    repetition (after one warm-up call each), so that a change in the
    machine's load falls on all of them. On a loaded machine the CPU time
    of a 1-thread call is the steadier measure of its work."""
    answers = {name: fn() for name, fn in engines.items()}
    wall = {name: [] for name in engines}
    cpu = {name: [] for name in engines}
    for _ in range(reps):
        for name, fn in engines.items():
            start, start_cpu = time.perf_counter(), time.process_time()
            answers[name] = fn()
            cpu[name].append(time.process_time() - start_cpu)
            wall[name].append(time.perf_counter() - start)
    median = lambda d: {name: statistics.median(t) for name, t in d.items()}  # noqa: E731
    return median(wall), median(cpu), answers


def ray_sets(vertices, n, seed=7):
    lo, hi = vertices.min(axis=0).astype(np.float64), vertices.max(axis=0).astype(np.float64)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    side = int(round(np.sqrt(n)))
    primary = raykit.RaycastingScene.create_rays_pinhole(
        fov_deg=40, center=centre.tolist(), eye=(centre + np.array([0.3, 0.4, 2.6]) * radius).tolist(),
        up=[0, 1, 0], width_px=side, height_px=side,
    ).numpy()
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    origins = centre + 2 * radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    targets = lo + rng.random((n, 3)) * (hi - lo)
    d = targets - origins
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    incoherent = np.concatenate([origins, d], axis=1).astype(np.float32)
    return {"primary": np.ascontiguousarray(primary, dtype=np.float32), "incoherent": incoherent}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh", nargs="?", default=DRAGON)
    ap.add_argument("--rays", type=int, default=1 << 20)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--no-embree", action="store_true")
    args = ap.parse_args()
    thread_counts = [int(x) for x in args.threads.split(",")]

    import open3d as o3d

    v, f, _ = raykit.load_mesh(args.mesh)
    print(f"{os.path.basename(args.mesh)}: {len(f):,} triangles, {args.rays:,} rays per set, median of {args.reps}")
    rays = ray_sets(v, args.rays)

    ours = raykit.RaycastingScene()
    ours.add_triangles(v, f)
    start = time.perf_counter()
    ours._built()
    build_ours = time.perf_counter() - start

    theirs = o3d.t.geometry.RaycastingScene()
    theirs.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(f))
    start = time.perf_counter()
    theirs.test_occlusions(o3d.core.Tensor(rays["primary"].reshape(-1, 6)[:1]))  # Open3D builds at its first query
    build_theirs = time.perf_counter() - start

    embree = None
    if not args.no_embree:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        start = time.perf_counter()
        embree = rtcore_scene.EmbreeScene()
        TriangleMesh(scene=embree, vertices=v, indices=f.astype(np.int32))
        first = rays["primary"].reshape(-1, 6)[:1]
        embree.run(first[:, :3].copy(), first[:, 3:].copy())
        build_embree = time.perf_counter() - start
    print(f"build: raykit bvh8 {build_ours:.2f} s (all cores), Open3D {build_theirs:.2f} s"
          + (f", embreex {build_embree:.2f} s" if embree else ""))

    rows = []
    for name, r in rays.items():
        tensor = o3d.core.Tensor(r)
        flat = r.reshape(-1, 6)
        o, d = np.ascontiguousarray(flat[:, :3]), np.ascontiguousarray(flat[:, 3:])
        for threads in thread_counts:
            with_embree = embree is not None and threads == 1
            cast = {
                "raykit": lambda: ours.cast_rays(r, nthreads=threads)["t_hit"],
                "open3d": lambda: theirs.cast_rays(tensor, nthreads=threads)["t_hit"].numpy(),
            }
            occlusion = {
                "raykit": lambda: ours.test_occlusions(r, nthreads=threads),
                "open3d": lambda: theirs.test_occlusions(tensor, nthreads=threads).numpy(),
            }
            if with_embree:
                cast["embreex"] = lambda: (embree.run(o, d) != -1).reshape(r.shape[:-1])
                occlusion["embreex"] = lambda: (np.asarray(embree.run(o, d, query="OCCLUDED")) != -1).reshape(r.shape[:-1])
            for query, engines in (("cast_rays", cast), ("test_occlusions", occlusion)):
                times, cpu, answers = interleaved(engines, args.reps)
                hits = {k: (np.isfinite(a) if a.dtype.kind == "f" else a) for k, a in answers.items()}
                agree = min((hits[k] == hits["raykit"]).mean() for k in hits)
                rows.append({"rays": name, "query": query, "threads": threads, "agree": agree, **times,
                             **{f"{k}_cpu": c for k, c in cpu.items()}})

    n = args.rays
    print()
    print("Mrays/s by wall-clock time (by CPU time of the whole process in brackets)")
    print()
    print("| rays | query | threads | raykit | Open3D | raykit / Open3D | embreex | hit/miss agreement |")
    print("|---|---|---|---|---|---|---|---|")
    for row in rows:
        m = rays[row["rays"]].size // 6

        def rate(k):
            return f"{m / row[k] / 1e6:.2f} ({m / max(row[k + '_cpu'], 1e-9) / 1e6:.2f})" if k in row else "–"

        ratio = f"{row['open3d'] / row['raykit']:.2f}x ({row['open3d_cpu'] / max(row['raykit_cpu'], 1e-9):.2f}x)"
        print(f"| {row['rays']} | {row['query']} | {row['threads']} | {rate('raykit')} | {rate('open3d')} | "
              f"{ratio} | {rate('embreex')} | {row['agree']:.5f} |")
    print()
    print("uptime:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())


if __name__ == "__main__":
    main()
