"""A model at UTM coordinates against the same model near zero: how far the
answers of raykit's RaycastingScene (and, if installed, Open3D's) move.

    python python/bench/bench_far_coordinates.py [MESH] [--size METRES] [--rays N] [--points N]

The mesh (default: the repository's bunny) is scaled to SIZE metres (100)
with its box's corner at zero, and placed once more at (429252, 5150885,
312), a UTM position, in float64. The same incoherent rays and points in
and around the box, moved by the same offset in float64, go to both
scenes. The scene near zero is the reference: float32 holds the model to
micrometres there, where at UTM northings it is half a metre apart.
Open3D takes float32 only and gets the same arrays rounded.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import raykit

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python" / "tests"))
from conftest import rays_at  # noqa: E402

FAR = np.array([429252.0, 5150885.0, 312.0])


def compare(name: str, near: dict, far: dict, rays: np.ndarray, invalid: int) -> None:
    a, b = near["primitive_ids"], far["primitive_ids"]
    both = (a != invalid) & (b != invalid)
    flips = int(((a == invalid) != (b == invalid)).sum())
    other = int((a[both] != b[both]).sum())
    gap = np.abs(near["t_hit"][both].astype(np.float64) - far["t_hit"][both]) * np.linalg.norm(rays[both, 3:], axis=1)
    print(
        f"{name}: hit/miss flips {flips}, other triangle {other} of {both.sum()}, "
        f"hit distance error median {np.median(gap):.3g} m, max {gap.max():.3g} m"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh", nargs="?", default=str(REPO / "data" / "meshes" / "bunny_3674.obj"))
    ap.add_argument("--size", type=float, default=100.0)
    ap.add_argument("--rays", type=int, default=20000)
    ap.add_argument("--points", type=int, default=5000)
    args = ap.parse_args()

    v, t, _ = raykit.load_mesh(args.mesh)
    v = v.astype(np.float64)
    v = (v - v.min(axis=0)) / np.ptp(v, axis=0).max() * args.size
    rays = rays_at(v, args.rays, 1).astype(np.float64)
    moved = rays.copy()
    moved[:, :3] += FAR
    rng = np.random.default_rng(2)
    extent = np.ptp(v, axis=0)
    points = v.min(axis=0) + rng.random((args.points, 3)) * extent * 1.2 - 0.1 * extent

    near, far = raykit.RaycastingScene(), raykit.RaycastingScene()
    near.add_triangles(v, t)
    far.add_triangles(v + FAR, t)
    print(f"raykit: the far scene's origin {far.origin}")
    compare("raykit", near.cast_rays(rays), far.cast_rays(moved), rays, raykit.INVALID_ID)
    close_near = near.compute_closest_points(points)["points"]
    close_far = np.asarray(far.compute_closest_points(points + FAR)["points"], dtype=np.float64) - FAR
    err = np.linalg.norm(close_far - close_near, axis=1)
    d = np.abs(near.compute_distance(points) - far.compute_distance(points + FAR))
    occ = int((near.compute_occupancy(points) != far.compute_occupancy(points + FAR)).sum())
    print(
        f"raykit: closest point error median {np.median(err):.3g} m, max {err.max():.3g} m; "
        f"distance error max {d.max():.3g} m; occupancy flips {occ} of {len(points)}"
    )

    try:
        import open3d as o3d
    except ImportError:
        print("open3d: not installed")
        return

    def o3d_scene(vertices):
        s = o3d.t.geometry.RaycastingScene()
        s.add_triangles(o3d.core.Tensor(vertices.astype(np.float32)), o3d.core.Tensor(t.astype(np.uint32)))
        return s

    def o3d_cast(scene, r):
        ans = scene.cast_rays(o3d.core.Tensor(r.astype(np.float32)))
        return {k: ans[k].numpy() for k in ("primitive_ids", "t_hit")}

    compare("open3d", o3d_cast(o3d_scene(v), rays), o3d_cast(o3d_scene(v + FAR), moved), rays, 4294967295)


if __name__ == "__main__":
    main()
