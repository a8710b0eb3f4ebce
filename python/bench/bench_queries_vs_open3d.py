"""raykit's point and multi-hit queries against Open3D's RaycastingScene, in
one process on the same input.

    python python/bench/bench_queries_vs_open3d.py [MESH] [--points N] [--rays N] [--reps R] [--threads 1,2]

Default mesh: the full Stanford dragon (871,414 triangles),
data-cache/dragon_vrip.ply.gz in the checkout, which
scripts/fetch-bench-data fetches (or RAYKIT_DRAGON). Queries:
compute_closest_points, compute_distance, compute_signed_distance and
compute_occupancy on points uniform in the mesh's bounding box grown by
10% on each side (an SDF grid's samples; with --near, points within 1% of
the box diagonal of a vertex), and count_intersections and
list_intersections on incoherent rays (from a sphere around the mesh
towards random points of its box). Open3D's timings come from fewer
points where it is slow (its rate is the same per point); raykit's from
all of them. Every time is the median of R runs after a warm-up, the
engines taking turns; the build is excluded (both build before timing).

Answers are compared: distances (max difference relative to the box
diagonal), counts (share equal), and the share of points where the inside
agrees — where they differ the script reports raykit's generalized winding
number for those points (Open3D's ray parity is wrong near the dragon's
holes and self-intersections, raykit's winding number is not).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import time

import numpy as np

import raykit
from query_points import DRAGON, query_points, timed




def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh", nargs="?", default=DRAGON)
    ap.add_argument("--points", type=int, default=1 << 18)
    ap.add_argument("--open3d-points", type=int, default=1 << 13, help="points for Open3D's slow queries")
    ap.add_argument("--rays", type=int, default=1 << 18)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--near", action="store_true",
                    help="points near the surface (a random vertex moved by up to 1%% of the box diagonal) "
                         "instead of uniform in the grown box")
    args = ap.parse_args()
    threads = [int(x) for x in args.threads.split(",")]

    import open3d as o3d

    v, f, _ = raykit.load_mesh(args.mesh)
    lo, hi = v.min(0).astype(np.float64), v.max(0).astype(np.float64)
    diag = float(np.linalg.norm(hi - lo))
    rng = np.random.default_rng(3)
    points = query_points(v, args.points, args.near, rng)
    centre, radius = (lo + hi) / 2, diag / 2
    u = rng.normal(size=(args.rays, 3))
    origins = centre + 2 * radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    d = lo + rng.random((args.rays, 3)) * (hi - lo) - origins
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    rays = np.concatenate([origins, d], axis=1).astype(np.float32)
    print(f"{os.path.basename(args.mesh)}: {len(f):,} triangles; {args.points:,} points "
          f"({'near the surface' if args.near else 'uniform in the box grown by 10%'}) "
          f"({args.open3d_points:,} for Open3D's closest/distance/signed), {args.rays:,} rays; median of {args.reps}")

    ours = raykit.RaycastingScene()
    ours.add_triangles(v, f)
    start = time.perf_counter()
    ours.compute_occupancy(points[:1])  # builds the point-query BVH and the winding moments
    build_ours = time.perf_counter() - start
    theirs = o3d.t.geometry.RaycastingScene()
    theirs.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(f))
    start = time.perf_counter()
    theirs.compute_distance(o3d.core.Tensor(points[:1]))
    build_theirs = time.perf_counter() - start
    print(f"build: raykit {build_ours:.2f} s (BVH, winding moments; all cores), Open3D {build_theirs:.2f} s")

    p_small = points[: args.open3d_points]
    t_points = o3d.core.Tensor(points)
    t_small = o3d.core.Tensor(p_small)
    t_rays = o3d.core.Tensor(rays)
    queries = [
        ("compute_closest_points", "points/s", True,
         lambda n: ours.compute_closest_points(points, nthreads=n)["points"],
         lambda n: theirs.compute_closest_points(t_small, nthreads=n)["points"].numpy()),
        ("compute_distance", "points/s", True,
         lambda n: ours.compute_distance(points, nthreads=n),
         lambda n: theirs.compute_distance(t_small, nthreads=n).numpy()),
        ("compute_signed_distance", "points/s", True,
         lambda n: ours.compute_signed_distance(points, nthreads=n),
         lambda n: theirs.compute_signed_distance(t_small, nthreads=n).numpy()),
        ("compute_occupancy", "points/s", False,
         lambda n: ours.compute_occupancy(points, nthreads=n),
         lambda n: theirs.compute_occupancy(t_points, nthreads=n).numpy()),
        ("count_intersections", "rays/s", False,
         lambda n: ours.count_intersections(rays, nthreads=n),
         lambda n: theirs.count_intersections(t_rays, nthreads=n).numpy()),
        ("list_intersections", "rays/s", False,
         lambda n: ours.list_intersections(rays, nthreads=n)["t_hit"],
         lambda n: theirs.list_intersections(t_rays, nthreads=n)["t_hit"].numpy()),
    ]
    rows = []
    for name, unit, small, mine, other in queries:
        for n in threads:
            t_mine, a_mine = timed(lambda: mine(n), args.reps)
            t_other, a_other = timed(lambda: other(n), max(1, args.reps if not small else 1))
            n_mine = len(rays) if unit == "rays/s" else len(points)
            n_other = len(p_small) if small else n_mine
            r_mine, r_other = n_mine / t_mine, n_other / t_other
            m = len(a_other)
            if name in ("compute_closest_points",):
                check = f"max |point diff| / diag {np.abs(a_mine[:m] - a_other).max() / diag:.1e}"
            elif name in ("compute_distance",):
                check = f"max |diff| / diag {np.abs(a_mine[:m] - a_other).max() / diag:.1e}"
            elif name == "compute_signed_distance":
                same = np.sign(a_mine[:m]) == np.sign(a_other)
                check = (f"|d| max diff / diag {np.abs(np.abs(a_mine[:m]) - np.abs(a_other)).max() / diag:.1e}; "
                         f"sign agrees {same.mean():.4f}")
            elif name == "compute_occupancy":
                same = a_mine == a_other
                w = ours.compute_winding_number(points[~same], beta=np.inf) if (~same).any() else np.array([])
                clear = (np.abs(w - 0.5) > 0.25).sum()
                check = (f"agrees {same.mean():.5f}; of the {(~same).sum()} others, raykit's exact winding "
                         f"number is clearly on raykit's side (|w-½| > ¼) for {clear}")
            elif name == "count_intersections":
                check = f"equal counts {(a_mine == a_other).mean():.5f}"
            else:
                check = f"hits {len(a_mine):,} vs {len(a_other):,}"
            rows.append((name, unit, n, r_mine, r_other, check))
            print(f"  {name} threads={n}: raykit {r_mine:,.0f} {unit}, Open3D {r_other:,.0f} {unit}", flush=True)
    print()
    print("| query | threads | raykit | Open3D | raykit / Open3D | answers |")
    print("|---|---|---|---|---|---|")
    for name, unit, n, r_mine, r_other, check in rows:
        print(f"| {name} | {n} | {r_mine / 1e6:.3f} M{unit} | {r_other / 1e6:.4f} M{unit} | "
              f"{r_mine / r_other:.1f}x | {check} |")
    print()
    print("uptime:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())


if __name__ == "__main__":
    main()
