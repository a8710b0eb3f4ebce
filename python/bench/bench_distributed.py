"""raykit.distributed on a LocalCluster of 1 and 2 worker processes (one
thread each) against the same work in this process: render (bands of one
image), cast_rays (a dask array of rays) and viewsheds (many observers on a
real DEM). Prints a Markdown table of median seconds, the spread over the
repetitions, the speed-up from 1 to 2 workers, the overhead of one
worker against the in-process call on one thread, and 2 workers against
the in-process call on 2 threads.

    python python/bench/bench_distributed.py [--reps 3]

Every distributed answer is checked against the in-process one before it
is timed (bit-identical images, identical hits, masks and counts).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python" / "tests"))

import dask  # noqa: E402
import dask.array as da  # noqa: E402
from distributed import Client, LocalCluster  # noqa: E402

import raykit  # noqa: E402
import raykit.distributed as rkd  # noqa: E402
from conftest import rays_at, shared_data  # noqa: E402


def timed(f, reps):
    out, times = None, []
    for _ in range(reps):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return out, times


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--observers", type=int, default=16)
    args = ap.parse_args()
    data = shared_data()
    v, f, _ = raykit.load_mesh(data / "meshes" / "dragon_vrip_res4.ply.gz")
    scene = raykit.RaycastingScene()
    scene.add_triangles(v, f)
    lo, hi = v.min(0).astype(np.float64), v.max(0).astype(np.float64)
    centre = (lo + hi) / 2
    cam = {"eye": tuple(centre + [0, 0.2 * (hi - lo)[1], 2.0 * np.linalg.norm(hi - lo)]), "target": tuple(centre)}
    w, h, spp, tiles = 640, 480, 4, 16
    rays = rays_at(v, args.rays, seed=1)
    dem = data / "terrain" / "lidar_dem_400.tif"
    hts, t, _ = raykit.terrain.grid(dem)
    rng = np.random.default_rng(3)
    cols, rows = rng.integers(10, 390, args.observers), rng.integers(10, 390, args.observers)
    observers = [(t[2] + t[0] * c, t[5] + t[4] * r) for c, r in zip(cols, rows)]

    work = {
        "render": (
            lambda th: raykit.render(scene, w, h, samples_per_pixel=spp, threads=th, **cam),
            lambda c: rkd.render(c, scene, w, h, tiles=tiles, samples_per_pixel=spp, progress=False, **cam),
            lambda a, b: np.array_equal(a, b),
            f"{w}×{h}, {spp} spp, {tiles} bands, dragon {len(f)} triangles",
        ),
        "cast_rays": (
            lambda th: scene.cast_rays(rays, nthreads=th),
            lambda c: dict(
                zip(
                    ("t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"),
                    dask.compute(*rkd.cast_rays(c, scene, da.from_array(rays, chunks=(len(rays) // 8, 6))).values()),
                )
            ),
            lambda a, b: all(np.array_equal(np.asarray(a[k]), b[k]) for k in b),
            f"{len(rays)} rays in 8 chunks, same dragon (save + per-worker load included)",
        ),
        "viewsheds": (
            lambda th: np.sum([raykit.terrain.viewshed(dem, observer=o, observer_height=10, threads=th) == 1 for o in observers], axis=0),
            lambda c: rkd.viewsheds(c, str(dem), observers, observer_height=10, return_masks=False, progress=False)["count"],
            lambda a, b: np.array_equal(a, b),
            f"{len(observers)} observers on lidar_dem_400.tif (400×400), one per task",
        ),
    }
    inproc, inproc2 = {}, {}
    for name, (local, _, _, _) in work.items():
        local(1)  # warm
        inproc[name] = timed(lambda: local(1), args.reps)
        inproc2[name] = timed(lambda: local(2), args.reps)
    clustered: dict[int, dict] = {}
    for n in (1, 2):
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as c:
            clustered[n] = {}
            for name, (_, remote, same, _) in work.items():
                first = remote(c)  # warm: imports and the first load on each worker
                assert same(inproc[name][0], first), f"{name}: distributed answer differs"
                clustered[n][name] = timed(lambda: remote(c), args.reps)
    load = os.getloadavg()[0]
    print(f"\nload average after the run: {load:.2f}; {os.cpu_count()} cores\n")
    print("| work | in-process, 1 thread (s) | in-process, 2 threads (s) | LocalCluster 1 worker (s) | 2 workers (s) | speed-up 1→2 workers | overhead 1 worker / in-process 1 thread | 2 workers / in-process 2 threads |")
    print("|---|---|---|---|---|---|---|---|")
    for name, (_, _, _, what) in work.items():
        def cell(ts):
            return f"{statistics.median(ts):.3f} ({min(ts):.3f}–{max(ts):.3f})"

        a, a2, b, c2 = inproc[name][1], inproc2[name][1], clustered[1][name][1], clustered[2][name][1]
        sp = statistics.median(b) / statistics.median(c2)
        sp_lo, sp_hi = min(b) / max(c2), max(b) / min(c2)
        ov = statistics.median(b) / statistics.median(a)
        ov_lo, ov_hi = min(b) / max(a), max(b) / min(a)
        r2 = statistics.median(c2) / statistics.median(a2)
        print(
            f"| {name}: {what} | {cell(a)} | {cell(a2)} | {cell(b)} | {cell(c2)} | {sp:.2f} ({sp_lo:.2f}–{sp_hi:.2f}) "
            f"| {ov:.2f} ({ov_lo:.2f}–{ov_hi:.2f}) | {r2:.2f} |"
        )


if __name__ == "__main__":
    main()
