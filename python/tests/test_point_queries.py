"""Point and multi-hit ray queries of RaycastingScene and trimesh's
contains_points: against a float64 numpy brute force, against Open3D's
RaycastingScene on the same input, and where Open3D's ray parity is
wrong (a mesh with a hole, a duplicated triangle)."""

from __future__ import annotations

import numpy as np
import open3d as o3d
import pytest
import trimesh

import raykit
from conftest import rays_at


def scene_of(vertices, triangles, **kw):
    s = raykit.RaycastingScene(**kw)
    s.add_triangles(vertices, triangles)
    return s


def open3d_scene(vertices, triangles):
    s = o3d.t.geometry.RaycastingScene()
    s.add_triangles(o3d.core.Tensor(np.ascontiguousarray(vertices, np.float32)), o3d.core.Tensor(np.ascontiguousarray(triangles, np.uint32)))
    return s


def closest_brute(vertices, triangles, points):
    """Distance to the nearest triangle of each point, Ericson's closest
    point in float64 over every triangle, vectorised over triangles."""
    v = vertices.astype(np.float64)
    a, b, c = v[triangles[:, 0]], v[triangles[:, 1]], v[triangles[:, 2]]
    ab, ac = b - a, c - a
    out = np.empty(len(points))
    for k, p in enumerate(points.astype(np.float64)):
        ap, bp, cp = p - a, p - b, p - c
        d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
        d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
        d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
        va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
        with np.errstate(divide="ignore", invalid="ignore"):
            denom = va + vb + vc
            q = a + ab * (vb / denom)[:, None] + ac * (vc / denom)[:, None]
            cand = [q]
            # Edges and corners: the closest of the three segments covers them.
            for s, e in ((a, b), (a, c), (b, c)):
                d = e - s
                t = np.clip(((p - s) * d).sum(1) / (d * d).sum(1), 0, 1)
                cand.append(s + d * t[:, None])
        dist = np.stack([np.linalg.norm(x - p, axis=1) for x in cand])
        inside = (va >= 0) & (vb >= 0) & (vc >= 0) & (denom > 0)
        dist[0][~inside] = np.inf
        out[k] = np.nanmin(dist)
    return out


def sample_points(vertices, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(0), vertices.max(0)
    pad = 0.3 * (hi - lo)
    return (lo - pad + rng.random((n, 3)) * (hi - lo + 2 * pad)).astype(np.float32)


def test_closest_points_match_brute_force_and_open3d(bunny):
    v, f, _ = bunny
    pts = sample_points(v, 300, 1)
    s = scene_of(v, f)
    ans = s.compute_closest_points(pts)
    ref = closest_brute(v, f, pts)
    d = np.linalg.norm(ans["points"].astype(np.float64) - pts, axis=1)
    scale = np.ptp(v)
    np.testing.assert_allclose(d, ref, atol=1e-5 * scale)
    np.testing.assert_allclose(s.compute_distance(pts), ref, atol=1e-5 * scale)
    # The point lies on the triangle named, at the barycentrics given.
    tri = v[f[ans["primitive_ids"]].astype(np.int64)].astype(np.float64)
    uv = ans["primitive_uvs"].astype(np.float64)
    at = (1 - uv[:, :1] - uv[:, 1:]) * tri[:, 0] + uv[:, :1] * tri[:, 1] + uv[:, 1:] * tri[:, 2]
    np.testing.assert_allclose(at, ans["points"], atol=1e-5 * scale)
    assert (ans["geometry_ids"] == 0).all()
    # Open3D: same distances (ties between triangles aside, same points).
    theirs = open3d_scene(v, f).compute_closest_points(pts)
    np.testing.assert_allclose(ans["points"], theirs["points"].numpy(), atol=1e-5 * scale)
    # Points closest to an edge or corner may name either triangle there.
    same = ans["primitive_ids"] == theirs["primitive_ids"].numpy()
    assert same.mean() > 0.5
    np.testing.assert_allclose(ans["primitive_normals"][same], theirs["primitive_normals"].numpy()[same], atol=1e-4)
    np.testing.assert_allclose(ans["primitive_uvs"][same], theirs["primitive_uvs"].numpy()[same], atol=1e-4)
    for key in ("points", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"):
        assert ans[key].dtype == theirs[key].numpy().dtype, key


def test_huge_meshes_give_finite_right_answers(bunny):
    # Coordinates of 1e10 overflowed the f32 products of the closest-point
    # test (a panic) and the far field of the winding number (inf, NaN).
    v, t, _ = bunny
    big = v.astype(np.float64) * 1e10
    s = scene_of(big, t)
    pts = sample_points(big.astype(np.float32), 60, 4)
    want = closest_brute(big.astype(np.float32), t, pts)
    got = s.compute_distance(pts)
    np.testing.assert_allclose(got, want, rtol=1e-5)
    assert np.isfinite(s.compute_closest_points(pts)["points"]).all()
    # The winding number is the same at any scale.
    w_big = s.compute_winding_number(pts)
    w = scene_of(v, t).compute_winding_number((pts.astype(np.float64) / 1e10).astype(np.float32))
    assert np.isfinite(w_big).all()
    np.testing.assert_allclose(w_big, w, atol=2e-3)


def test_several_geometries_and_shapes(bunny):
    v, f, _ = bunny
    s = raykit.RaycastingScene()
    s.add_triangles(v, f)
    shift = np.float32([3 * np.ptp(v), 0, 0])
    g1 = s.add_triangles(v + shift, f)
    pts = sample_points(v, 24, 2).reshape(2, 4, 3, 3) + shift
    ans = s.compute_closest_points(pts)
    assert ans["points"].shape == (2, 4, 3, 3) and ans["primitive_uvs"].shape == (2, 4, 3, 2)
    assert (ans["geometry_ids"] == g1).all()
    assert s.compute_distance(pts).shape == (2, 4, 3)
    assert s.compute_occupancy(pts).shape == (2, 4, 3)


def test_signed_distance_and_occupancy_agree_with_open3d_on_a_closed_mesh(data):
    mesh = trimesh.creation.icosphere(subdivisions=4)
    v, f = mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32)
    pts = sample_points(v, 2000, 3)
    r = np.linalg.norm(pts, axis=1)
    clear = np.abs(r - 1) > 0.02
    mine = scene_of(v, f)
    theirs = open3d_scene(v, f)
    occ = mine.compute_occupancy(pts)
    assert occ.dtype == np.float32
    np.testing.assert_array_equal(occ[clear], (r < 1)[clear].astype(np.float32))
    np.testing.assert_array_equal(occ[clear], theirs.compute_occupancy(pts).numpy()[clear])
    sd = mine.compute_signed_distance(pts, nsamples=3)
    np.testing.assert_allclose(sd[clear], theirs.compute_signed_distance(pts).numpy()[clear], atol=1e-5)
    w = mine.compute_winding_number(pts, beta=np.inf)
    np.testing.assert_allclose(w[clear], (r < 1)[clear], atol=1e-3)


def test_open3d_parity_is_wrong_where_the_winding_number_is_right():
    # An icosphere with a cap removed (a hole), and one with a duplicated
    # face: points well inside.
    ico = trimesh.creation.icosphere(subdivisions=3)
    v = ico.vertices.astype(np.float32)
    centroids = ico.triangles_center
    holed = ico.faces[centroids[:, 2] < 0.8].astype(np.uint32)
    pts = np.random.default_rng(4).uniform(-0.3, 0.3, (500, 3)).astype(np.float32)
    mine = scene_of(v, holed)
    assert (mine.compute_occupancy(pts) == 1).all()
    assert (mine.compute_signed_distance(pts) < 0).all()
    dup = np.concatenate([ico.faces, ico.faces[:40]]).astype(np.uint32)
    assert (scene_of(v, dup).compute_occupancy(pts) == 1).all()
    # Open3D's single ray (parity) gets some of these wrong.
    wrong = [
        (open3d_scene(v, holed).compute_occupancy(pts).numpy() == 0).sum(),
        (open3d_scene(v, dup).compute_occupancy(pts).numpy() == 0).sum(),
    ]
    print("points Open3D calls outside: holed", wrong[0], "duplicated faces", wrong[1])
    assert sum(wrong) > 0


def intersections_brute(v, f, rays):
    """Every crossing (ray, triangle, t) with t >= 0, float64 Möller–Trumbore,
    and the smallest barycentric margin of each ray's crossings."""
    v = v.astype(np.float64)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    e1, e2 = b - a, c - a
    lists, margins = [], []
    for r in rays.astype(np.float64):
        o, d = r[:3], r[3:]
        p = np.cross(d, e2)
        det = (e1 * p).sum(1)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = o - a
            u = (s * p).sum(1) / det
            q = np.cross(s, e1)
            w = (q @ d) / det
            t = (e2 * q).sum(1) / det
        m = np.minimum(np.minimum(u, w), 1 - u - w)
        ok = (det != 0) & (m >= 0) & (t >= 0)
        idx = np.flatnonzero(ok)
        idx = idx[np.argsort(t[idx])]
        lists.append((idx, t[idx]))
        near = np.abs(m) < 1e-4
        margins.append(not (near & (det != 0) & (t >= 0)).any())
    return lists, np.array(margins)


def test_count_and_list_intersections_match_brute_force_and_open3d(dragon):
    v, f, _ = dragon
    rays = rays_at(v, 400, seed=5)
    s = scene_of(v, f)
    counts = s.count_intersections(rays)
    lx = s.list_intersections(rays)
    ref, clear = intersections_brute(v, f, rays)
    assert clear.mean() > 0.9
    want = np.array([len(i) for i, _ in ref])
    np.testing.assert_array_equal(counts[clear], want[clear])
    assert counts.dtype == np.int32
    splits = lx["ray_splits"]
    assert splits.shape == (len(rays) + 1,) and splits[-1] == len(lx["t_hit"])
    for k in np.flatnonzero(clear):
        a, b = splits[k], splits[k + 1]
        assert (lx["ray_ids"][a:b] == k).all()
        np.testing.assert_array_equal(np.sort(lx["primitive_ids"][a:b]), np.sort(ref[k][0]))
        np.testing.assert_allclose(lx["t_hit"][a:b], ref[k][1], rtol=1e-4)
    first2 = s.list_intersections(rays, max_hits=2)
    np.testing.assert_array_equal(np.diff(first2["ray_splits"]), np.minimum(np.diff(splits), 2))
    theirs = open3d_scene(v, f)
    o3c = theirs.count_intersections(rays).numpy()
    assert o3c.dtype == counts.dtype
    # Open3D steps past each hit, so it misses a second triangle at the same
    # t (the dragon has coincident faces); everywhere else the counts agree.
    for k in np.flatnonzero(clear & (o3c != counts)):
        t = ref[k][1]
        assert o3c[k] < counts[k] and (np.diff(t) <= 1e-6 * t[1:]).any(), (k, o3c[k], counts[k], t)
    assert (o3c[clear] == counts[clear]).mean() > 0.9
    o3l = {k: x.numpy() for k, x in theirs.list_intersections(rays).items()}
    assert set(o3l) == set(lx)
    for k in o3l:
        assert o3l[k].dtype == lx[k].dtype, k


def grid_cube(n, seed):
    """The surface of the cube [0, n]³ as a grid of unit squares, each cut
    along a random diagonal, corners at integers: a closed, outward-facing
    mesh whose
    edges and corners axis-aligned rays through integer points meet
    exactly, as they meet those of CAD and voxel models."""
    rng = np.random.default_rng(seed)
    vertices, triangles = [], []
    for axis in range(3):
        for side in (0, n):
            for i in range(n):
                for j in range(n):
                    quad = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0, 0, 0]
                        p[axis], p[(axis + 1) % 3], p[(axis + 2) % 3] = side, i + di, j + dj
                        quad.append(len(vertices))
                        vertices.append(p)
                    # Counter-clockwise seen from outside.
                    a, b, c, d = quad if side else quad[::-1]
                    triangles += [[a, b, c], [a, c, d]] if rng.integers(2) else [[a, b, d], [b, c, d]]
    return np.array(vertices, np.float32), np.array(triangles, np.int32)


def test_rays_through_shared_edges_and_corners_cross_a_closed_mesh_twice():
    n = 6
    v, f = grid_cube(n, seed=3)
    rng = np.random.default_rng(4)
    # From outside, through integer points of the cube's inside (corners
    # and edges of the faces they cross), along each axis and tilted.
    rows = []
    for _ in range(600):
        through = rng.integers(1, n, size=3).astype(np.float32)
        d = np.zeros(3, np.float32)
        d[rng.integers(3)] = rng.choice([-1, 1])
        if rng.integers(2):
            d += rng.integers(-2, 3, size=3).astype(np.float32) / 8
        rows.append(np.concatenate([through - 4 * n * d, d]))
    rays = np.array(rows, np.float32)
    s = scene_of(v, f)
    counts = s.count_intersections(rays)
    assert (counts == 2).all(), np.unique(counts, return_counts=True)
    lx = s.list_intersections(rays)
    assert (np.diff(lx["ray_splits"]) == 2).all()
    inside = s.compute_occupancy(rays[:, :3] + 4 * n * rays[:, 3:])
    assert (inside == 1).all()


def test_bad_points_and_rays_never_crash(bunny):
    v, f, _ = bunny
    s = scene_of(v, f)
    pts = np.array([[np.nan, 0, 0], [np.inf, 0, 0], [0, 0, 0]], np.float32)
    d = s.compute_distance(pts)
    assert np.isnan(d[:2]).all() and np.isfinite(d[2])
    cp = s.compute_closest_points(pts)
    assert (cp["primitive_ids"][:2] == raykit.INVALID_ID).all() and np.isnan(cp["points"][:2]).all()
    assert np.isnan(s.compute_signed_distance(pts)[:2]).all()
    assert (s.compute_occupancy(pts)[:2] == 0).all()
    rays = np.array([[np.nan, 0, 0, 1, 0, 0], [0, 0, 0, 0, 0, 0]], np.float32)
    assert (s.count_intersections(rays) == 0).all()
    assert s.list_intersections(rays)["ray_splits"].tolist() == [0, 0, 0]
    with pytest.raises(ValueError):
        s.compute_distance(np.zeros((3, 2), np.float32))
    with pytest.raises(ValueError):
        s.compute_occupancy(pts, nsamples=2)
    empty = raykit.RaycastingScene()
    assert empty.compute_distance(np.zeros((1, 3))).tolist() == [np.inf]
    assert empty.count_intersections(np.zeros((1, 6), np.float32) + [0, 0, 0, 1, 0, 0]).tolist() == [0]
    assert s.compute_distance(np.zeros((0, 3), np.float64)).shape == (0,)


def test_threads_and_float64_give_the_same_answers(bunny):
    v, f, _ = bunny
    pts = sample_points(v, 5000, 6)
    s = scene_of(v, f)
    one = s.compute_signed_distance(pts, nthreads=1)
    two = s.compute_signed_distance(pts.astype(np.float64), nthreads=2)
    np.testing.assert_array_equal(one, two)


def test_trimesh_contains_points(data):
    mesh = trimesh.load(data / "meshes" / "bunny_3674.obj", force="mesh")
    pts = sample_points(mesh.vertices.astype(np.float32), 2000, 7)
    mine = raykit.trimesh.RayMeshIntersector(mesh, threads=1).contains_points(pts)
    assert mine.dtype == bool and mine.shape == (2000,)
    w = scene_of(mesh.vertices, mesh.faces).compute_winding_number(pts, beta=np.inf)
    clear = np.abs(w - 0.5) > 0.1
    np.testing.assert_array_equal(mine[clear], (w >= 0.5)[clear])
    if mesh.is_watertight:
        ref = trimesh.ray.ray_triangle.RayMeshIntersector(mesh).contains_points(pts)
        assert (ref[clear] == mine[clear]).mean() > 0.99
    assert mine.sum() > 50


def test_a_tiny_model_answers_as_at_unit_size(bunny):
    """The bunny brought to unit size, then shrunk by 2^-30 (nanometres in
    metres) and 2^-70, exact in float32: every query gives the unit model's
    answers times the factor, bit for bit (normals to rounding), and
    distances agree with the float64 brute force on the tiny model itself.
    Without the unit scaling in the core, distances were off by up to 0.8%
    of the model from 2^-32 on and hits were lost from 2^-60."""
    v, f, _ = bunny
    v = np.asarray(v, np.float32)
    lo = v.min(0)
    unit = ((v - lo) * np.float32(2.0 ** -np.floor(np.log2(np.ptp(v, axis=0).max()))) + np.float32(1.5)).astype(np.float32)
    rays = rays_at(unit, 1500, 21)
    pts = sample_points(unit, 400, 22)

    def answers(scene, rays, pts):
        hits = scene.cast_rays(rays)
        closest = scene.compute_closest_points(pts)
        return {
            "t": hits["t_hit"],
            "prim": hits["primitive_ids"],
            "normal": hits["primitive_normals"],
            "occluded": scene.test_occlusions(rays),
            "count": scene.count_intersections(rays),
            "points": closest["points"],
            "distance": scene.compute_distance(pts),
            "signed": scene.compute_signed_distance(pts),
            "inside": scene.compute_occupancy(pts),
        }

    want = answers(scene_of(unit, f), rays, pts)
    assert np.isfinite(want["t"]).sum() > 300 and 0 < want["inside"].sum() < len(pts)
    for e in (30, 70):
        k = np.float32(2.0 ** -e)
        small_rays = rays.copy()
        small_rays[:, :3] *= k
        got = answers(scene_of(unit * k, f), small_rays, pts * k)
        for name in ("t", "points", "distance", "signed"):
            np.testing.assert_array_equal(got[name], want[name] * k, err_msg=f"{name} at 2^-{e}")
        for name in ("prim", "occluded", "count", "inside"):
            np.testing.assert_array_equal(got[name], want[name], err_msg=f"{name} at 2^-{e}")
        # Unit normals, found in float64 where float32's cross product of
        # such edges underflows: the same to rounding.
        np.testing.assert_allclose(got["normal"], want["normal"], atol=1e-6, err_msg=f"normal at 2^-{e}")
        ref = closest_brute(unit * k, f, pts[:100] * k)
        np.testing.assert_allclose(got["distance"][:100], ref, rtol=1e-5)
