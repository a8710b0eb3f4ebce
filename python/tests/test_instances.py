"""Instances in RaycastingScene: geometries stored once and placed by affine
transforms, with ray masks, against the same scene flattened (every
instance's vertices moved in float64) and traced by a float64 brute force."""

from __future__ import annotations

import numpy as np
import pytest

import raykit
from conftest import brute_force, rays_at
from test_point_queries import closest_brute, intersections_brute


def random_transforms(n: int, seed: int, spread: float) -> list[np.ndarray]:
    """``n`` random (3, 4) affine maps: a rotation, a non-uniform scale
    (one of them mirroring) and a translation within ``spread``."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        scale = np.diag(rng.uniform(0.6, 1.6, 3) * (-1 if k == 1 else 1) ** np.array([1, 0, 0]))
        m = np.zeros((3, 4))
        m[:, :3] = q @ scale
        m[:, 3] = rng.uniform(-spread, spread, 3)
        out.append(m)
    return out


def moved(vertices: np.ndarray, m: np.ndarray) -> np.ndarray:
    return vertices.astype(np.float64) @ m[:, :3].T + m[:, 3]


def instanced_scene(bunny, n=10, seed=3, masks=None):
    """The bunny stored once (not placed itself) and placed ``n`` times, plus
    a small box placed where it is; and the flattened vertices, triangles,
    geometry and instance of each flattened triangle."""
    v, f, _ = bunny
    size = float(np.linalg.norm(v.max(0) - v.min(0)))
    box_v = (np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], np.float32) - 0.5) * size * 0.4
    box_f = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],
        np.uint32,
    )
    scene = raykit.RaycastingScene()
    bunny_id = scene.add_triangles(v, f, place=False)
    box_id = scene.add_triangles(box_v, box_f)
    assert (bunny_id, box_id) == (0, 1)
    flat_v, flat_f, geom, inst = [box_v.astype(np.float64)], [box_f], [np.full(len(box_f), box_id)], [np.zeros(len(box_f), int)]
    dets = [1.0]
    base = len(box_v)
    for k, m in enumerate(random_transforms(n, seed, 1.5 * size)):
        mask = 0xFFFFFFFF if masks is None else masks[k]
        iid = scene.add_instance(bunny_id, m if k % 2 else np.vstack([m, [0, 0, 0, 1]]), mask=mask)
        assert iid == k + 1
        flat_v.append(moved(v, m))
        flat_f.append(f + base)
        base += len(v)
        geom.append(np.full(len(f), bunny_id))
        inst.append(np.full(len(f), iid))
        dets.append(float(np.linalg.det(m[:, :3])))
    scene.dets = np.array(dets)  # the sign says which instances mirror
    return scene, np.concatenate(flat_v), np.concatenate(flat_f), np.concatenate(geom), np.concatenate(inst)


def test_instances_trace_as_the_flattened_scene_and_a_float64_brute_force(bunny):
    scene, fv, ff, geom, inst = instanced_scene(bunny)
    assert scene.instanced
    stats = scene.stats()
    assert stats["stored_triangles"] == len(bunny[1]) + 12
    assert stats["placed_triangles"] == len(ff)

    flat = raykit.RaycastingScene()
    flat.add_triangles(fv.astype(np.float32), ff)
    rays = rays_at(fv.astype(np.float32), 3000, seed=11)
    ours, theirs = scene.cast_rays(rays), flat.cast_rays(rays)
    hit, hit_flat = np.isfinite(ours["t_hit"]), np.isfinite(theirs["t_hit"])
    assert hit.mean() > 0.2
    assert (hit != hit_flat).sum() <= 3  # grazes decided by rounding in object space
    both = hit & hit_flat
    np.testing.assert_allclose(ours["t_hit"][both], theirs["t_hit"][both], rtol=1e-4)
    # Map our (instance, triangle-in-geometry) to the flattened triangle.
    first = {int(i): int(np.flatnonzero(inst == i)[0]) for i in np.unique(inst)}
    ours_flat = np.array([first[int(i)] + int(p) for i, p in zip(ours["instance_ids"][both], ours["primitive_ids"][both])])
    same = ours_flat == theirs["primitive_ids"][both]
    assert same.mean() > 0.99
    np.testing.assert_array_equal(ours["geometry_ids"][both], geom[ours_flat])
    # World normals: unit, and the flattened triangle's own winding's normal.
    a, b, c = (fv[ff[ours_flat[same], j]] for j in range(3))
    ref_n = np.cross(b - a, c - a)
    ref_n /= np.linalg.norm(ref_n, axis=1, keepdims=True)
    got_n = ours["primitive_normals"][both][same].astype(np.float64)
    # A mirroring instance keeps its front side: its moved triangle's
    # winding turns, so its e1 x e2 points the other way.
    side = np.sign(scene.dets[inst[ours_flat[same]]])
    assert (scene.dets < 0).any() and (scene.dets > 0).any()
    assert ((got_n * ref_n).sum(1) * side > 0.999).all()

    sub = np.flatnonzero(both)[:150]
    ref_t, ref_i = brute_force(fv, ff, rays[sub])
    np.testing.assert_allclose(ours["t_hit"][sub], ref_t, rtol=1e-4)

    # Occlusion, counts and hit lists against the flattened scene's.
    assert (scene.test_occlusions(rays) != flat.test_occlusions(rays)).sum() <= 3
    few = rays[:400]
    lists, clean = intersections_brute(fv, ff, few)
    counts = scene.count_intersections(few)
    ref_counts = np.array([len(i) for i, _ in lists])
    np.testing.assert_array_equal(counts[clean], ref_counts[clean])
    listed = scene.list_intersections(few)
    splits = listed["ray_splits"]
    for r in np.flatnonzero(clean)[:200]:
        got = listed["t_hit"][splits[r] : splits[r + 1]]
        np.testing.assert_allclose(got, lists[r][1], rtol=1e-4)
        ids = listed["instance_ids"][splits[r] : splits[r + 1]]
        np.testing.assert_array_equal(ids, inst[lists[r][0]])


def test_camera_images_trace_as_the_flattened_scene(bunny):
    # Rays shaped as an image (sides not multiples of the 4 x 4 blocks)
    # from one eye: traced by bands and instance by instance.
    scene, fv, ff, _, _ = instanced_scene(bunny)
    flat = raykit.RaycastingScene()
    flat.add_triangles(fv.astype(np.float32), ff)
    centre = (fv.min(0) + fv.max(0)) / 2
    size = float(np.linalg.norm(fv.max(0) - fv.min(0)))
    rays = raykit.RaycastingScene.create_rays_pinhole(
        fov_deg=50, center=centre, eye=centre + np.array([0.3, 0.5, 1.2]) * size, up=[0, 1, 0], width_px=70, height_px=45
    )
    ours, theirs = scene.cast_rays(rays), flat.cast_rays(rays)
    assert ours["t_hit"].shape == (45, 70)
    hit, hit_flat = np.isfinite(ours["t_hit"]), np.isfinite(theirs["t_hit"])
    assert 0.1 < hit.mean() < 1.0
    assert (hit != hit_flat).sum() <= 3  # grazes decided by rounding in object space
    both = hit & hit_flat
    np.testing.assert_allclose(ours["t_hit"][both], theirs["t_hit"][both], rtol=1e-4)
    assert (scene.test_occlusions(rays) != flat.test_occlusions(rays)).sum() <= 3


def test_masks_hide_instances_as_if_they_were_absent(bunny):
    masks = [1 if k % 3 else 2 for k in range(9)]
    scene, fv, ff, geom, inst = instanced_scene(bunny, n=9, seed=5, masks=masks)
    rays = rays_at(fv.astype(np.float32), 2000, seed=2)
    for ray_mask in (1, 2):
        # The box (instance 0) has every bit set; instance k + 1 has masks[k].
        seen = np.array([True] + [bool(m & ray_mask) for m in masks])
        keep = seen[inst]
        flat = raykit.RaycastingScene()
        flat.add_triangles(fv.astype(np.float32), ff[keep])
        ours, theirs = scene.cast_rays(rays, mask=ray_mask), flat.cast_rays(rays)
        hit, hit_flat = np.isfinite(ours["t_hit"]), np.isfinite(theirs["t_hit"])
        assert (hit != hit_flat).sum() <= 3
        assert seen[ours["instance_ids"][hit]].all()
        both = hit & hit_flat
        np.testing.assert_allclose(ours["t_hit"][both], theirs["t_hit"][both], rtol=1e-4)
        np.testing.assert_array_equal(
            scene.count_intersections(rays[:300], mask=ray_mask) > 0, scene.test_occlusions(rays[:300], mask=ray_mask)
        )
    assert not np.isfinite(scene.cast_rays(rays, mask=0)["t_hit"]).any()
    # A geometry mask hides every instance of the geometry.
    hidden = raykit.RaycastingScene()
    g = hidden.add_triangles(*bunny[:2], mask=4)
    hidden.add_instance(g, np.eye(4))
    assert hidden.test_occlusions(rays, mask=4).any()
    assert not hidden.test_occlusions(rays, mask=3).any()


def test_point_queries_cover_every_instance(bunny):
    scene, fv, ff, geom, inst = instanced_scene(bunny, n=6, seed=8)
    rng = np.random.default_rng(1)
    lo, hi = fv.min(0), fv.max(0)
    pts = (lo + rng.random((60, 3)) * (hi - lo)).astype(np.float32)
    found = scene.compute_closest_points(pts)
    ref = closest_brute(fv, ff, pts)
    got = np.linalg.norm(found["points"].astype(np.float64) - pts, axis=1)
    np.testing.assert_allclose(got, ref, rtol=1e-4, atol=1e-6 * np.linalg.norm(hi - lo))
    np.testing.assert_allclose(scene.compute_distance(pts), ref, rtol=1e-4, atol=1e-6 * np.linalg.norm(hi - lo))
    # The reported instance and triangle are one at the reported distance.
    first = {int(i): int(np.flatnonzero(inst == i)[0]) for i in np.unique(inst)}
    tri = np.array([first[int(i)] + int(p) for i, p in zip(found["instance_ids"], found["primitive_ids"])])
    np.testing.assert_array_equal(found["geometry_ids"], geom[tri])
    np.testing.assert_allclose(closest_brute(fv, ff[tri[:1]], pts[:1]), ref[:1], rtol=1e-4)


def test_an_instance_moved_by_the_identity_is_the_plain_scene(bunny):
    v, f, _ = bunny
    plain = raykit.RaycastingScene()
    plain.add_triangles(v, f)
    inst = raykit.RaycastingScene()
    g = inst.add_triangles(v, f, place=False)
    assert not plain.instanced and inst.instanced
    inst.add_instance(g, np.eye(4))
    assert inst.instanced
    rays = rays_at(v, 2000, seed=4)
    a, b = plain.cast_rays(rays), inst.cast_rays(rays)
    np.testing.assert_array_equal(np.isfinite(a["t_hit"]), np.isfinite(b["t_hit"]))
    hit = np.isfinite(a["t_hit"])
    np.testing.assert_allclose(a["t_hit"][hit], b["t_hit"][hit], rtol=1e-5)
    np.testing.assert_array_equal(b["instance_ids"][hit], 0)
    assert "instance_ids" not in a  # a plain scene keeps Open3D's keys


def test_bad_instances_are_refused_by_name(bunny):
    v, f, _ = bunny
    scene = raykit.RaycastingScene()
    g = scene.add_triangles(v, f)
    singular = np.eye(4)
    singular[2, 2] = 0
    with pytest.raises(ValueError, match=r"instance 1: .*invertible"):
        scene.add_instance(g, singular)
    nan = np.eye(4)
    nan[0, 3] = np.nan
    with pytest.raises(ValueError, match="instance 1"):
        scene.add_instance(g, nan)
    projective = np.eye(4)
    projective[3, 0] = 1
    with pytest.raises(ValueError, match="last row"):
        scene.add_instance(g, projective)
    with pytest.raises(ValueError, match="shape"):
        scene.add_instance(g, np.eye(3))
    with pytest.raises(ValueError, match="out of range"):
        scene.add_instance(5, np.eye(4))
    # Only integers name geometries: int() would take 0.7 and "0" for 0.
    for bad in (0.7, 0.0, "0", True, np.bool_(False), None):
        with pytest.raises(ValueError, match="^geometry_id must be an integer"):
            scene.add_instance(bad, np.eye(4))
        with pytest.raises(ValueError, match="^geometry_id must be an integer"):
            scene.update_vertices(bad, v)
    with pytest.raises(ValueError, match="mask"):
        scene.add_instance(g, np.eye(4), mask=-1)
    # A placement beyond the coordinates a mesh may hold is refused at
    # once, naming the instance, as the point queries would refuse its
    # vertices; one that only its box's corners would exceed is not.
    huge = np.diag([1e30, 1e30, 1e30, 1.0])
    with pytest.raises(ValueError, match=r"instance 1: places vertex \d+ of geometry 0 beyond"):
        scene.add_instance(g, huge)
    far = np.eye(4)
    far[0, 3] = 2e12
    with pytest.raises(ValueError, match="instance 1: places vertex"):
        scene.add_instance(g, far)
    with pytest.raises(ValueError, match="mask"):
        scene.cast_rays(rays_at(v, 4, 0), mask=2**32)
    # Nothing refused was added; a good instance (numpy's integers name
    # geometries too) still works, and rays with NaN miss.
    assert scene.add_instance(np.uint8(g), np.eye(4)) == 1
    rays = rays_at(v, 50, 1)
    rays[0, 0] = np.nan
    out = scene.cast_rays(rays)
    assert not np.isfinite(out["t_hit"][0]) and out["instance_ids"][0] == raykit.RaycastingScene.INVALID_ID
    with pytest.raises(ValueError, match="saved form"):
        scene.save("unused.rkb")
    with pytest.raises(ValueError, match="without instances"):
        raykit.render(scene, 16, 12)


def test_a_gltf_added_with_its_instancing_traces_as_its_flattened_load(data):
    """The engine assembly added with ``add_gltf`` (each glTF mesh once, one
    instance per node) against the same file flattened by ``load_mesh``:
    the same hits, and each hit's instance is the part the flattened
    triangle belongs to."""
    path = data / "meshes" / "2CylinderEngine.glb"
    v, t, parts = raykit.load_mesh(path)
    flat = raykit.RaycastingScene()
    flat.add_triangles(v, t)
    scene = raykit.RaycastingScene()
    ids = scene.add_gltf(path)
    geometries, instances = raykit.load_gltf_instances(path)
    assert ids == list(range(len(instances))) and len(instances) == parts.max() + 1
    assert sum(len(geometries[g][1]) for g, *_ in instances) == len(t)
    assert scene.stats()["stored_triangles"] < len(t)

    rays = rays_at(v, 20000, 11)
    a, b = flat.cast_rays(rays), scene.cast_rays(rays)
    hit_a = a["primitive_ids"] != raykit.INVALID_ID
    hit_b = b["primitive_ids"] != raykit.INVALID_ID
    assert hit_a.sum() > 5000
    assert (hit_a != hit_b).sum() <= 4
    both = hit_a & hit_b
    t_a, t_b = a["t_hit"][both], b["t_hit"][both]
    assert np.quantile(np.abs(t_a - t_b) / t_a, 0.999) < 1e-4
    same_part = parts[a["primitive_ids"][both]] == b["instance_ids"][both]
    assert same_part.mean() > 0.999


def test_a_gltf_too_large_to_flatten_loads_with_add_gltf(tmp_path):
    """A strip placed by 40,000 nodes would flatten to more memory than a
    small file should ask for; ``load_mesh`` refuses it by name (on any
    machine with less than 150 GiB free) and ``add_gltf`` stores the strip
    once."""
    import json

    n = 100_000
    xs = np.arange(n, dtype=np.float32)
    strip = np.stack([xs // 2, xs % 2, np.zeros(n, np.float32)], axis=1).astype(np.float32)
    nodes = 40_000
    gltf = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": strip.nbytes, "uri": "strip.bin"}],
        "bufferViews": [{"buffer": 0, "byteLength": strip.nbytes}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": n,
                "type": "VEC3",
                "min": strip.min(axis=0).tolist(),
                "max": strip.max(axis=0).tolist(),
            }
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 5}]}],
        "nodes": [{"mesh": 0, "translation": [0.0, 0.0, float(k)]} for k in range(nodes)],
        "scenes": [{"nodes": list(range(nodes))}],
    }
    strip.tofile(tmp_path / "strip.bin")
    path = tmp_path / "many.gltf"
    path.write_text(json.dumps(gltf))
    with pytest.raises(ValueError, match="add_gltf"):
        raykit.load_mesh(path)
    scene = raykit.RaycastingScene()
    assert len(scene.add_gltf(path)) == nodes
    assert scene.stats()["stored_triangles"] == n - 2
    rays = np.array([[10.25, 0.5, -5.0, 0.0, 0.0, 1.0], [10.25, 0.5, nodes + 5.0, 0.0, 0.0, -1.0]], np.float32)
    ans = scene.cast_rays(rays)
    assert np.allclose(ans["t_hit"], [5.0, 6.0])
    assert ans["instance_ids"].tolist() == [0, nodes - 1]


def mirrored_boxes():
    """A 1 × 2 × 3 box stored once and placed three times: mirrored in x
    (the placement's determinant -1), by a random rotation times a
    mirroring scale, and by a plain rotation; with the placed vertices of
    each instance in float64."""
    import trimesh

    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    v, f = np.asarray(box.vertices), np.asarray(box.faces)
    q, _ = np.linalg.qr(np.random.default_rng(2).normal(size=(3, 3)))
    placements = [
        np.hstack([np.diag([-1.0, 1.0, 1.0]), [[5.0], [0.0], [0.0]]]),
        np.hstack([q @ np.diag([0.8, -1.3, 1.1]), [[-4.0], [1.0], [0.5]]]),
        np.hstack([q, [[0.0], [6.0], [0.0]]]),
    ]
    if np.linalg.det(q) < 0:
        placements[2][:, 0] *= -1
    scene = raykit.RaycastingScene()
    g = scene.add_triangles(v, f, place=False)
    for m in placements:
        scene.add_instance(g, m)
    return scene, v, f, placements


def test_a_mirrored_instance_keeps_its_inside():
    """Signed distance, occupancy and winding number of instances placed by
    mirroring matrices against trimesh's ray-parity ``contains`` and a
    float64 brute-force distance on each placed box."""
    import trimesh

    scene, v, f, placements = mirrored_boxes()
    dets = [np.linalg.det(m[:, :3]) for m in placements]
    assert dets[0] < 0 and dets[1] < 0 and dets[2] > 0
    rng = np.random.default_rng(7)
    points, inside, dist = [], [], []
    for m in placements:
        placed = moved(v, m)
        # Points around the box, sampled in its own frame and placed.
        pts = moved(rng.uniform(-1.0, 1.0, (150, 3)) * [0.8, 1.3, 1.8], m)
        d = closest_brute(placed, f, pts)
        keep = d > 0.05  # clear of the surface, where inside and outside are plain
        pts = pts[keep]
        points.append(pts)
        dist.append(d[keep])
        # Parity of rays does not depend on the faces' winding.
        inside.append(trimesh.Trimesh(placed, f, process=False).contains(pts))
    pts, inside, dist = np.concatenate(points), np.concatenate(inside), np.concatenate(dist)
    assert 50 < inside.sum() < len(pts) - 50
    np.testing.assert_array_equal(scene.compute_occupancy(pts), inside.astype(np.float32))
    np.testing.assert_allclose(scene.compute_signed_distance(pts), np.where(inside, -dist, dist), rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(scene.compute_winding_number(pts, beta=np.inf), inside.astype(np.float32), atol=1e-3)


def placed_corners(v, f, placements, inst, prim) -> np.ndarray:
    """``(k, 3, 3)``: the corners of triangle ``prim[j]`` of instance
    ``inst[j]``, placed in float64, in the order the geometry lists them."""
    return np.stack([moved(v[f[p]], placements[i]) for i, p in zip(inst, prim)])


def own_normals(corners, placements, inst) -> np.ndarray:
    """The unit normals of the placed triangles by their winding, reversed
    where the placement mirrors."""
    e = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    side = np.sign([np.linalg.det(placements[i][:, :3]) for i in inst])
    return e / np.linalg.norm(e, axis=1, keepdims=True) * side[:, None]


def test_a_mirrored_instance_reports_its_outward_normals_and_own_barycentrics():
    """Ray hits and closest points on mirrored instances: the normal is the
    placed triangle's with its winding reversed (outward: away from the
    box's centre), the barycentrics rebuild the point from the geometry's
    own corners, in the order the geometry lists them."""
    scene, v, f, placements = mirrored_boxes()
    rng = np.random.default_rng(3)
    centres = np.array([moved(v, m).mean(0) for m in placements])
    k = rng.integers(0, len(placements), 400)
    aim = centres[k] + rng.uniform(-0.3, 0.3, (400, 3))
    u = rng.normal(size=(400, 3))
    origins = aim + 8.0 * u / np.linalg.norm(u, axis=1, keepdims=True)
    rays = np.hstack([origins, aim - origins]).astype(np.float32)
    hits = scene.cast_rays(rays)
    hit = np.isfinite(hits["t_hit"])
    assert hit.mean() > 0.9
    inst, prim = hits["instance_ids"][hit], hits["primitive_ids"][hit]
    points = rays[hit, :3].astype(np.float64) + hits["t_hit"][hit, None] * rays[hit, 3:]
    n = hits["primitive_normals"][hit].astype(np.float64)
    outward = points - centres[inst]
    assert ((n * outward).sum(1) > 0).all()
    corners = placed_corners(v, f, placements, inst, prim)
    np.testing.assert_allclose(n, own_normals(corners, placements, inst), atol=1e-4)
    uv = hits["primitive_uvs"][hit].astype(np.float64)
    rebuilt = (1 - uv.sum(1))[:, None] * corners[:, 0] + uv[:, :1] * corners[:, 1] + uv[:, 1:] * corners[:, 2]
    np.testing.assert_allclose(rebuilt, points, atol=1e-4)

    queries = centres[k[:200]] + rng.uniform(-2.0, 2.0, (200, 3))
    near = scene.compute_closest_points(queries)
    inst, prim = near["instance_ids"], near["primitive_ids"]
    corners = placed_corners(v, f, placements, inst, prim)
    uv = near["primitive_uvs"].astype(np.float64)
    rebuilt = (1 - uv.sum(1))[:, None] * corners[:, 0] + uv[:, :1] * corners[:, 1] + uv[:, 1:] * corners[:, 2]
    np.testing.assert_allclose(rebuilt, near["points"], atol=1e-4)
    np.testing.assert_allclose(near["primitive_normals"], own_normals(corners, placements, inst), atol=1e-4)


def test_a_gltf_node_with_a_mirroring_scale_keeps_its_inside(tmp_path):
    """A box placed by a glTF node scaled by (-1, 1, 1) and rotated: the
    point queries of ``add_gltf`` (the mesh stored once, the node as an
    instance) against the same file flattened by ``load_mesh``, whose
    loader reverses the winding of mirrored nodes."""
    import base64
    import json

    import trimesh

    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    v = np.asarray(box.vertices, np.float32)
    idx = np.asarray(box.faces, np.uint32).ravel()
    buf = v.tobytes() + idx.tobytes()
    gltf = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": v.nbytes},
            {"buffer": 0, "byteOffset": v.nbytes, "byteLength": idx.nbytes},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(v), "type": "VEC3", "min": v.min(0).tolist(), "max": v.max(0).tolist()},
            {"bufferView": 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [
            {"mesh": 0, "scale": [-1, 1, 1], "translation": [5, 0, 0], "rotation": [0.0, 0.38268343, 0.0, 0.92387953]},
            {"mesh": 0, "translation": [-5, 0, 0]},
        ],
        "scenes": [{"nodes": [0, 1]}],
        "scene": 0,
    }
    path = tmp_path / "mirrored.gltf"
    path.write_text(json.dumps(gltf))
    scene = raykit.RaycastingScene()
    assert scene.add_gltf(path) == [0, 1]
    fv, ft, _ = raykit.load_mesh(path)
    flat = raykit.RaycastingScene()
    flat.add_triangles(fv, ft)
    rng = np.random.default_rng(5)
    pts = np.concatenate([c + rng.uniform(-1.0, 1.0, (200, 3)) * [1.2, 1.3, 1.8] for c in ([5.0, 0, 0], [-5.0, 0, 0])]).astype(np.float32)
    occ = scene.compute_occupancy(pts)
    assert occ[:200].sum() > 30 and occ[200:].sum() > 30 and occ.sum() < len(pts) - 100
    np.testing.assert_array_equal(occ, flat.compute_occupancy(pts))
    np.testing.assert_allclose(scene.compute_signed_distance(pts), flat.compute_signed_distance(pts), atol=1e-5)
    np.testing.assert_allclose(scene.compute_winding_number(pts), flat.compute_winding_number(pts), atol=1e-4)
