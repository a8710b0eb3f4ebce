"""Closest points: raykit against FCPW (the vectorized closest-point BVH of
Sawhney et al., "fcpw") and Open3D's RaycastingScene, in one process on
the same points.

    python python/bench/bench_closest_vs_fcpw.py [MESH] [--points N] [--open3d-points N] [--reps R] [--near] [--threads 1,2]

FCPW is a library built for exactly this query, so its rate says what a
dedicated CPU implementation reaches on this machine; Open3D's is the
yardstick of issue 35's "30× Open3D". `pip install fcpw open3d` next to
the raykit wheel. Default mesh: the full Stanford dragon
(data-cache/dragon_vrip.ply.gz, from scripts/fetch-bench-data, or
RAYKIT_DRAGON). Points uniform in the mesh's box grown by 10% per side
(the other benchmark's points), or with --near within 1% of the box
diagonal of a vertex. raykit answers points in Morton order, whatever order
they come in; with --sorted every engine is handed them in that order.

FCPW's Python binding has no thread argument: a row of N threads pins the
whole process to N cores (os.sched_setaffinity), which bounds every
engine alike; raykit and Open3D are also given nthreads=N. FCPW builds its
8-wide vectorized BVH (surface-area heuristic), as its documentation
recommends for triangles. Every time is the median of R runs after a
warm-up, the engines taking turns; builds are excluded. Distances are
compared with an f64 check of raykit's answer (the nearest of all three).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import raykit
from query_points import DRAGON, query_points, timed




def morton(points):
    """30-bit Morton codes of `points` over their box."""
    lo, hi = points.min(0), points.max(0)
    cells = ((points - lo) / np.maximum(hi - lo, 1e-30) * 1023).astype(np.uint64)
    code = np.zeros(len(points), dtype=np.uint64)
    for bit in range(10):
        for axis in range(3):
            code |= ((cells[:, axis] >> np.uint64(bit)) & np.uint64(1)) << np.uint64(3 * bit + 2 - axis)
    return code


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh", nargs="?", default=DRAGON)
    ap.add_argument("--points", type=int, default=1 << 17)
    ap.add_argument("--open3d-points", type=int, default=0,
                    help="points for Open3D, which is slow: every k-th of the points (default all)")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--near", action="store_true",
                    help="points near the surface (a random vertex moved by up to 1%% of the box diagonal)")
    ap.add_argument("--sorted", action="store_true",
                    help="hand every engine the points in Morton order (raykit sorts them itself either way)")
    args = ap.parse_args()
    threads = [int(x) for x in args.threads.split(",")]

    import fcpw
    import open3d as o3d

    v, f, _ = raykit.load_mesh(args.mesh)
    lo, hi = v.min(0).astype(np.float64), v.max(0).astype(np.float64)
    diag = float(np.linalg.norm(hi - lo))
    rng = np.random.default_rng(3)
    points = query_points(v, args.points, args.near, rng)
    if args.sorted:
        points = points[np.argsort(morton(points), kind="stable")]
    print(f"{os.path.basename(args.mesh)}: {len(f):,} triangles; {args.points:,} points "
          f"({'near the surface' if args.near else 'uniform in the box grown by 10%'}"
          f"{', in Morton order' if args.sorted else ''}; "
          f"{args.open3d_points or args.points:,} for Open3D); median of {args.reps}, Open3D's of 1")

    ours = raykit.RaycastingScene()
    ours.add_triangles(v, f)
    start = time.perf_counter()
    ours.compute_distance(points[:1])
    build_ours = time.perf_counter() - start

    scene = fcpw.scene_3D()
    scene.set_object_count(1)
    scene.set_object_vertices(np.asfortranarray(v, dtype=np.float32), 0)
    scene.set_object_triangles(np.asfortranarray(f, dtype=np.int32), 0)
    start = time.perf_counter()
    scene.build(fcpw.aggregate_type.bvh_surface_area, True)
    build_fcpw = time.perf_counter() - start
    q = np.asfortranarray(points)
    radii = np.full(len(points), np.inf, dtype=np.float32)

    def fcpw_closest():
        found = fcpw.interaction_3D_list()
        scene.find_closest_points(q, radii, found)
        return found

    theirs = o3d.t.geometry.RaycastingScene()
    theirs.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(f))
    # Every k-th point, so that a sorted subset still spans the whole box.
    stride = max(1, len(points) // (args.open3d_points or len(points)))
    t_small = o3d.core.Tensor(points[::stride][: args.open3d_points or len(points)])
    theirs.compute_distance(t_small[:1])
    print(f"build: raykit {build_ours:.2f} s, FCPW {build_fcpw:.2f} s (vectorized SAH BVH)")

    all_cpus = sorted(os.sched_getaffinity(0))
    print("| threads | raykit points/s | FCPW points/s | Open3D points/s | raykit ÷ FCPW | raykit ÷ Open3D "
          "| FCPW ÷ Open3D | answers |")
    print("|--:|--:|--:|--:|--:|--:|--:|---|")
    for n in threads:
        os.sched_setaffinity(0, all_cpus[:n])
        t_ours, a_ours = timed(lambda: ours.compute_distance(points, nthreads=n), args.reps)
        t_fcpw, found = timed(fcpw_closest, args.reps)
        t_o3d, a_o3d = timed(lambda: theirs.compute_distance(t_small, nthreads=n).numpy(), 1)
        r_ours, r_fcpw = len(points) / t_ours, len(points) / t_fcpw
        r_o3d = len(a_o3d) / t_o3d
        d_fcpw = np.array([i.d for i in found], dtype=np.float64)
        a_sub = a_ours[::stride][: len(a_o3d)]
        worst = max(np.abs(a_ours - d_fcpw).max(), np.abs(a_sub - a_o3d).max()) / diag
        print(f"| {n} | {r_ours:,.0f} | {r_fcpw:,.0f} | {r_o3d:,.0f} | {r_ours / r_fcpw:.2f}× "
              f"| {r_ours / r_o3d:.1f}× | {r_fcpw / r_o3d:.1f}× | max distance difference {worst:.1e} of the diagonal |")
    os.sched_setaffinity(0, all_cpus)


if __name__ == "__main__":
    main()
