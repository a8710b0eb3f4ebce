"""A scene with instances against the same mesh without, from Python.

    python python/bench/bench_instanced.py [MESH] [--reps R]

The mesh (default: the full dragon in data-cache/dragon_vrip.ply.gz) is
added once to a plain RaycastingScene, and once to a second scene that also
places it again ten bounding radii away (add_instance), which makes that
scene instanced (a two-level BVH). Both cast the same rays: `primary`, a
1024 × 1024 pinhole camera on the mesh (one eye), and `incoherent`, from a
sphere around the mesh towards random points of its box. Printed: Mrays/s
of each (best of R), 1 and 2 threads, and where the hit distances are not
equal: they may differ only where a ray misses the mesh and goes on to
the far copy.
"""

import argparse
import time

import numpy as np

import raykit


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mesh", nargs="?", default="data-cache/dragon_vrip.ply.gz")
    parser.add_argument("--reps", type=int, default=3)
    args = parser.parse_args()
    v, f, *_ = raykit.load_mesh(args.mesh)
    v = np.asarray(v, np.float32)
    f = np.asarray(f, np.uint32)
    lo, hi = v.min(0), v.max(0)
    c = (lo + hi) / 2
    r = float(np.linalg.norm(hi - lo)) / 2
    n = 1024
    eye = c + np.array([0, 0, 3 * r], np.float32)
    ys, xs = np.mgrid[0:n, 0:n].astype(np.float32)
    half = np.tan(np.arcsin(1 / 3))
    d = np.stack([(xs / n * 2 - 1) * half, (ys / n * 2 - 1) * half, -np.ones_like(xs)], -1)
    d = d.reshape(-1, 3)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    primary = np.concatenate([np.broadcast_to(eye, d.shape), d], 1).astype(np.float32)
    rng = np.random.default_rng(1)
    o = c + rng.normal(size=(n * n, 3)).astype(np.float32) * r * 2
    d = lo + rng.random((n * n, 3)).astype(np.float32) * (hi - lo) - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    incoherent = np.concatenate([o, d], 1).astype(np.float32)

    plain = raykit.RaycastingScene()
    plain.add_triangles(v, f)
    instanced = raykit.RaycastingScene()
    g = instanced.add_triangles(v, f)
    far = np.eye(4)
    far[0, 3] = 10 * r
    instanced.add_instance(g, far)
    for threads in (1, 2):
        for name, rays in (("primary", primary), ("incoherent", incoherent)):
            rates, t_hits = [], []
            for scene in (plain, instanced):
                best = float("inf")
                for _ in range(args.reps):
                    t0 = time.perf_counter()
                    a = scene.cast_rays(rays, nthreads=threads)
                    best = min(best, time.perf_counter() - t0)
                rates.append(len(rays) / best / 1e6)
                t_hits.append(a["t_hit"])
            differ = t_hits[0] != t_hits[1]
            # Only rays that miss the mesh may reach the far copy.
            only_far = bool(np.all(np.isinf(t_hits[0][differ])))
            print(
                f"{threads} thread(s), {name}: plain {rates[0]:.2f}, "
                f"instanced {rates[1]:.2f} Mrays/s; t differs on {int(differ.sum())} rays, "
                f"all misses of the plain scene: {only_far}"
            )


if __name__ == "__main__":
    main()
