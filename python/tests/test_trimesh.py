"""raykit.trimesh.RayMeshIntersector against trimesh's own pure-Python
engine (trimesh.ray.ray_triangle) on real meshes."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from trimesh.ray.ray_triangle import RayMeshIntersector as Reference

import raykit
import raykit.trimesh


def load(data, name):
    v, f, _ = raykit.load_mesh(data / "meshes" / name)
    return trimesh.Trimesh(v.astype(np.float64), f, process=False)


def random_rays(mesh, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = mesh.bounds
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo)
    u = rng.normal(size=(n, 3))
    origins = centre + radius * u / np.linalg.norm(u, axis=1, keepdims=True)
    return origins, lo + rng.random((n, 3)) * (hi - lo) - origins


@pytest.fixture(scope="module", params=["bunny_3674.obj", "teapot_992.obj"])
def mesh(request, data):
    return load(data, request.param)


def test_first_hits_match_trimesh(mesh):
    o, d = random_rays(mesh, 600, 1)
    ours, ref = raykit.trimesh.RayMeshIntersector(mesh), Reference(mesh)
    first, first_ref = ours.intersects_first(o, d), ref.intersects_first(o, d)
    assert first.dtype == np.int64 and first.shape == (600,)
    hit, hit_ref = first >= 0, first_ref >= 0
    assert hit.sum() > 100
    assert (hit != hit_ref).sum() <= 1  # an edge graze decided by rounding
    np.testing.assert_array_equal(ours.intersects_any(o, d), hit)
    loc, ray, tri = ours.intersects_location(o, d, multiple_hits=False)
    np.testing.assert_array_equal(ray, np.flatnonzero(hit))
    np.testing.assert_array_equal(tri, first[hit])
    both = hit & hit_ref
    loc_ref, ray_ref, _ = ref.intersects_location(o, d, multiple_hits=False)
    mine = dict(zip(ray, loc))
    theirs = {r: p for r, p in zip(ray_ref, loc_ref)}
    for r in np.flatnonzero(both):
        np.testing.assert_allclose(mine[r], theirs[r], atol=1e-5 * mesh.scale)
    same = first[both] == first_ref[both]
    assert same.mean() > 0.99  # otherwise two triangles tie at a shared edge


def test_all_hits_match_trimesh(mesh):
    o, d = random_rays(mesh, 400, 2)
    loc, ray, tri = raykit.trimesh.RayMeshIntersector(mesh).intersects_location(o, d)
    loc_ref, ray_ref, tri_ref = Reference(mesh).intersects_location(o, d)
    assert len(loc) > 400
    tol = 1e-5 * mesh.scale
    differ = 0
    for r in range(len(o)):
        mine = loc[ray == r]
        theirs = loc_ref[ray_ref == r]
        # The reference lists an edge crossing once per triangle there.
        unique = [p for i, p in enumerate(theirs) if not any(np.linalg.norm(p - q) < tol for q in theirs[:i])]
        if len(mine) != len(unique):
            differ += 1
            continue
        # Ordered by distance along the ray.
        t = (mine - o[r]) @ d[r]
        assert (np.diff(t) > 0).all()
        for p in unique:
            assert np.linalg.norm(mine - p, axis=1).min() < tol
    assert differ <= 2
    # Hit points lie on their triangles, or within the triangle tests'
    # watertightness band beyond its edges (barycentrics down to -2^-8, so
    # at most 2 · 2^-8 of the longest edge away near a corner).
    v = mesh.vertices[mesh.faces[tri]]
    closest = trimesh.triangles.closest_point(v, loc)
    longest = np.linalg.norm(v - np.roll(v, 1, axis=1), axis=2).max(axis=1)
    assert (np.linalg.norm(closest - loc, axis=1) <= tol + 2 * 2.0**-8 * longest).all()
    ids, rays = raykit.trimesh.RayMeshIntersector(mesh).intersects_id(o, d, max_hits=1)
    assert np.bincount(rays).max() == 1
    # The same crossings as RaycastingScene lists, each once.
    scene = raykit.RaycastingScene()
    scene.add_triangles(mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32))
    unit = d / np.linalg.norm(d, axis=1, keepdims=True)
    listed = scene.list_intersections(np.concatenate([o, unit], axis=1).astype(np.float32))
    np.testing.assert_array_equal(ray, listed["ray_ids"])
    np.testing.assert_array_equal(tri, listed["primitive_ids"])
    with pytest.raises(ValueError, match="max_hits"):
        raykit.trimesh.RayMeshIntersector(mesh).intersects_id(o, d, max_hits=-1)


def test_crossings_at_shared_edges_are_listed_once(data):
    """Rays through the bunny at random: each crossing is listed once, as
    many as trimesh's own float64 engine finds once its doubled edge
    crossings are merged. Repeated nearest-hit queries stepping past each
    hit by 10⁻⁶ of the mesh's size listed four of these rays' edge
    crossings twice (the triangle tests accept hits just beyond an edge,
    and at a grazing angle the neighbour's hit lies further along)."""
    mesh = load(data, "bunny_3674.obj")
    rng = np.random.default_rng(2)
    c = mesh.bounds.mean(0)
    o = c + rng.normal(size=(1500, 3)) * 10
    d = c + rng.normal(size=(1500, 3)) * 2 - o
    ours = raykit.trimesh.RayMeshIntersector(mesh).intersects_location(o, d)
    ref = Reference(mesh).intersects_location(o, d)
    tol = 1e-5 * mesh.scale
    counts = np.bincount(ours[1], minlength=len(o))
    differ = 0
    for r in range(len(o)):
        theirs = ref[0][ref[1] == r]
        unique = [p for i, p in enumerate(theirs) if not any(np.linalg.norm(p - q) < tol for q in theirs[:i])]
        differ += counts[r] != len(unique)
    assert counts.sum() > 1500
    assert differ <= 1, f"{differ} rays with another number of crossings"


def test_plugs_into_a_trimesh(data):
    mesh = load(data, "bunny_3674.obj")
    reference = mesh.ray.intersects_first
    mesh.ray = raykit.trimesh.RayMeshIntersector(mesh, threads=1)
    o, d = random_rays(mesh, 100, 3)
    assert (mesh.ray.intersects_first(o, d) >= 0).sum() == (reference(o, d) >= 0).sum()
    inside = mesh.contains([mesh.centroid, mesh.bounds[1] + 1.0])
    assert inside.tolist() == [True, False]
    # A mesh using it pickles (for multiprocessing, joblib, dask) after a
    # query, and the copy answers as the original.
    import pickle

    first = mesh.ray.intersects_first(o, d)
    copy = pickle.loads(pickle.dumps(mesh))
    assert isinstance(copy.ray, raykit.trimesh.RayMeshIntersector)
    np.testing.assert_array_equal(copy.ray.intersects_first(o, d), first)
    # A changed mesh rebuilds the structure.
    mesh.vertices = mesh.vertices + [0, 0, 1000.0]
    assert not mesh.ray.intersects_any(o, d).any()


def test_far_from_the_origin(data):
    mesh = load(data, "bunny_3674.obj")
    o, d = random_rays(mesh, 200, 4)
    shift = np.array([5e5, -3e5, 1e5])
    far = trimesh.Trimesh(mesh.vertices + shift, mesh.faces, process=False)
    loc, ray, _ = raykit.trimesh.RayMeshIntersector(mesh).intersects_location(o, d, multiple_hits=False)
    loc_far, ray_far, _ = raykit.trimesh.RayMeshIntersector(far).intersects_location(o + shift, d, multiple_hits=False)
    np.testing.assert_array_equal(ray, ray_far)
    np.testing.assert_allclose(loc_far - shift, loc, atol=1e-4 * mesh.scale)


def test_vertices_no_face_uses_may_be_nan(data):
    """trimesh keeps vertices that no face uses (after ``update_faces``, for
    one); a NaN among them changes no answer, as in trimesh's own engine."""
    mesh = load(data, "teapot_992.obj")
    o, d = random_rays(mesh, 300, 6)
    spare = np.concatenate([mesh.vertices, [[np.nan, np.nan, np.nan], [1e300, 0.0, 0.0]]])
    odd = trimesh.Trimesh(spare, mesh.faces, process=False)
    want = raykit.trimesh.RayMeshIntersector(mesh).intersects_location(o, d)
    got = raykit.trimesh.RayMeshIntersector(odd).intersects_location(o, d)
    assert len(want[0]) > 50
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
    used = trimesh.Trimesh(spare, np.concatenate([mesh.faces, [[0, 1, len(spare) - 2]]]), process=False)
    with pytest.raises(ValueError, match=f"vertex {len(spare) - 2} has a NaN"):
        raykit.trimesh.RayMeshIntersector(used).intersects_first(o, d)


def test_bad_rays(data):
    mesh = load(data, "teapot_992.obj")
    ray = raykit.trimesh.RayMeshIntersector(mesh)
    with pytest.raises(ValueError, match="same shape"):
        ray.intersects_first(np.zeros((3, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        ray.intersects_any(np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="real numbers"):
        ray.intersects_id(np.zeros((1, 3), object), np.zeros((1, 3)))
    o = np.array([[np.nan, 0, 0], [0, 0, 100], [0, 0, 100]])
    d = np.array([[0, 0, -1], [0, 0, 0], [np.inf, 0, -1]])
    assert (ray.intersects_first(o, d) == -1).all()
    assert len(ray.intersects_location(o, d)[0]) == 0
    assert ray.intersects_first(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)
