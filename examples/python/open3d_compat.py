"""Ray casting written for Open3D's RaycastingScene, run by raykit.

Only the import differs: run with ``--open3d`` to use Open3D, without it to
use raykit. Everything below the import is plain Open3D code (numpy in,
``.numpy()`` and ``.isfinite()`` on the results).

    python examples/python/open3d_compat.py MESH.obj [OUT.npz] [--open3d]
"""

import sys

import numpy as np

if "--open3d" in sys.argv:
    from open3d.t.geometry import RaycastingScene
else:
    from raykit import RaycastingScene


def read_obj(path):
    """Vertices and triangles of a triangulated OBJ file (v and f lines)."""
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if parts and parts[0] == "v":
                vertices.append([float(x) for x in parts[1:4]])
            elif parts and parts[0] == "f":
                faces.append([int(p.split("/")[0]) - 1 for p in parts[1:4]])
    return np.array(vertices, dtype=np.float32), np.array(faces, dtype=np.uint32)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    vertices, triangles = read_obj(args[0])
    out = args[1] if len(args) > 1 else None

    # Two copies of the mesh side by side: geometry ids 0 and 1.
    scene = RaycastingScene()
    width = float(np.ptp(vertices[:, 0]))
    first = scene.add_triangles(vertices, triangles)
    second = scene.add_triangles(vertices + np.array([1.2 * width, 0, 0], np.float32), triangles)
    centre = vertices.mean(axis=0) + np.array([0.6 * width, 0, 0], np.float32)

    # A pinhole camera looking at both.
    rays = RaycastingScene.create_rays_pinhole(
        fov_deg=60,
        center=centre.tolist(),
        eye=(centre + np.array([0, 0.3 * width, 2.5 * width])).tolist(),
        up=[0, 1, 0],
        width_px=160,
        height_px=120,
    )
    ans = scene.cast_rays(rays)
    t_hit = ans["t_hit"].numpy()
    geometry = ans["geometry_ids"].numpy()
    hit = ans["t_hit"].isfinite().numpy()  # as Open3D's ray-casting tutorial tests hits

    # Shadow rays towards a light above, from every hit point.
    rays_np = rays.numpy()
    points = rays_np[..., :3] + rays_np[..., 3:] * np.where(hit, t_hit, 0)[..., None]
    normals = ans["primitive_normals"].numpy()
    to_light = np.array([0.3, 1.0, 0.5], np.float32)
    to_light /= np.linalg.norm(to_light)
    shadow_rays = np.concatenate([points + 1e-4 * width * normals, np.broadcast_to(to_light, points.shape)], axis=-1)
    shadowed = scene.test_occlusions(shadow_rays.astype(np.float32)).numpy() & hit

    print(f"geometries {first} and {second}; {hit.mean():.1%} of the pixels hit, "
          f"{(geometry == first).sum()} on the first, {(geometry == second).sum()} on the second, "
          f"{shadowed.sum()} in shadow")
    if out:
        np.savez(
            out,
            t_hit=t_hit,
            geometry_ids=geometry,
            primitive_ids=ans["primitive_ids"].numpy(),
            primitive_uvs=ans["primitive_uvs"].numpy(),
            primitive_normals=normals,
            shadowed=shadowed,
            rays=rays_np,
        )


if __name__ == "__main__":
    main()
