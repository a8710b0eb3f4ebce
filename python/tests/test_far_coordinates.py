"""Scenes far from the coordinates' origin, as GIS and CAD data come (UTM
metres are millions): the same model, rays and points moved there in
float64 must give the answers the model gives at the origin. The
reference is the scene near zero, where float32 holds the model to a
fraction of a micrometre; float32 at UTM northings is half a metre apart."""

from __future__ import annotations

import json
import math
import struct

import numpy as np
import pytest
from conftest import brute_force, rays_at, ties

import raykit
from raykit import distributed

#: A UTM position (zone 32N, metres) and a height.
FAR = np.array([429252.0, 5150885.0, 312.0])


@pytest.fixture(scope="module")
def model(bunny):
    """The bunny as a 100 m model with its box's corner at zero, float64."""
    v, t, _ = bunny
    v = v.astype(np.float64)
    return (v - v.min(axis=0)) / np.ptp(v, axis=0).max() * 100.0, t


def scene_of(v, t, **kwargs) -> raykit.RaycastingScene:
    s = raykit.RaycastingScene(**kwargs)
    s.add_triangles(v, t)
    return s


def assert_same_hits(near: dict, far: dict, rays: np.ndarray, what: str) -> None:
    """Hits of the far scene against the near scene's: misses and triangles
    alike but for rays that graze a shared edge (at most 1 in 2,000), and
    the hit distances within 50 micrometres for half the rays and 2 mm for
    all: both scenes round the model to float32 near zero (7.6 micrometres
    apart at 100 m), and a ray that meets the surface at a grazing angle
    moves along it by more than the rounding."""
    missed_near = near["primitive_ids"] == raykit.INVALID_ID
    missed_far = far["primitive_ids"] == raykit.INVALID_ID
    both = ~missed_near & ~missed_far
    assert both.sum() > len(rays) // 4, what
    flips = int((missed_near != missed_far).sum())
    other = int((near["primitive_ids"][both] != far["primitive_ids"][both]).sum())
    assert flips + other <= len(rays) // 2000, f"{what}: {flips} hit/miss and {other} triangle differences"
    length = np.linalg.norm(rays[both, 3:], axis=1)
    gap = np.abs(near["t_hit"][both].astype(np.float64) - far["t_hit"][both]) * length
    assert np.median(gap) <= 5e-5 and gap.max() <= 2e-3, f"{what}: distances differ by up to {gap.max()} m"


def test_a_model_at_utm_coordinates_answers_as_at_the_origin(model):
    v, t = model
    near = scene_of(v, t)
    far = scene_of(v + FAR, t)
    assert np.array_equal(near.origin, np.zeros(3))
    assert np.abs(far.origin - (FAR + 50.0)).max() <= 64.0, far.origin

    rays = rays_at(v, 20000, 1).astype(np.float64)
    moved = rays.copy()
    moved[:, :3] += FAR
    assert_same_hits(near.cast_rays(rays), far.cast_rays(moved), rays, "cast_rays")
    assert (near.count_intersections(rays) == far.count_intersections(moved)).mean() >= 0.999
    assert (near.test_occlusions(rays) == far.test_occlusions(moved)).mean() >= 0.999

    rng = np.random.default_rng(2)
    points = -10.0 + rng.random((5000, 3)) * 120.0
    close_near = near.compute_closest_points(points)
    close_far = far.compute_closest_points(points + FAR)
    assert close_far["points"].dtype == np.float64
    d_near = np.linalg.norm(close_near["points"] - points, axis=1)
    d_far = np.linalg.norm(close_far["points"] - FAR - points, axis=1)
    assert np.abs(d_near - d_far).max() <= 1e-4
    assert np.abs(near.compute_distance(points) - far.compute_distance(points + FAR)).max() <= 1e-4
    inside_near = near.compute_occupancy(points)
    assert inside_near.sum() > 100
    assert (inside_near == far.compute_occupancy(points + FAR)).mean() >= 0.999


def test_a_model_moved_far_by_update_vertices_answers_as_added_there(model):
    """A one-geometry scene built near zero and then moved to UTM
    coordinates by ``update_vertices`` chooses its origin again; a scene
    with a given origin keeps it."""
    v, t = model
    rng = np.random.default_rng(5)
    points = -10.0 + rng.random((3000, 3)) * 120.0
    rays = rays_at(v, 5000, 3).astype(np.float64)
    moved = rays.copy()
    moved[:, :3] += FAR
    near = scene_of(v, t)
    want_d = near.compute_distance(points)
    want_hits = near.cast_rays(rays)
    for query_first in (False, True):
        scene = scene_of(v, t)
        if query_first:
            scene.cast_rays(rays[:10])
        scene.update_vertices(0, v + FAR)
        assert np.abs(scene.origin - (FAR + 50.0)).max() <= 64.0, scene.origin
        assert np.abs(scene.compute_distance(points + FAR) - want_d).max() <= 1e-4
        assert_same_hits(want_hits, scene.cast_rays(moved), rays, "cast_rays after update_vertices")
        # Back near zero, the origin is zero again.
        scene.update_vertices(0, v)
        assert np.array_equal(scene.origin, np.zeros(3))
        assert np.abs(scene.compute_distance(points) - want_d).max() <= 1e-4
    given = scene_of(v, t, origin=[0.0, 0.0, 0.0])
    given.update_vertices(0, v + 1000.0)
    assert np.array_equal(given.origin, np.zeros(3))
    assert np.abs(given.compute_distance(points + 1000.0) - want_d).max() <= 1e-3


def test_float64_rays_from_far_away_hit_what_float64_brute_force_hits(bunny):
    """Rays given in float64 from 10⁴-10⁶ model sizes away, at random points
    of the model's box: raykit moves each along itself to just outside the
    model before rounding it to float32, so the nearest triangle is the one
    an f64 brute force finds (ties at shared corners aside) and ``t_hit``
    is right to float32's precision. Rounded first, an origin at 10⁶ sizes
    moves by about 0.03 sizes and most of these rays hit another triangle.
    The same for the trimesh engine, the hit lists and the counts."""
    v, t, _ = bunny
    v, t = v.astype(np.float64), t.astype(np.int64)
    lo, hi = v.min(axis=0), v.max(axis=0)
    centre, size = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
    rng = np.random.default_rng(8)
    scene = raykit.RaycastingScene()
    scene.add_triangles(v, t)

    class Mesh:
        vertices, faces, scale = v, t, size

    engine = raykit.trimesh.RayMeshIntersector(Mesh())
    for far in (1e4, 1e6):
        u = rng.normal(size=(200, 3))
        origins = centre + far * size * u / np.linalg.norm(u, axis=1, keepdims=True)
        d = lo + rng.random((200, 3)) * (hi - lo) - origins
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        rays = np.concatenate([origins, d], axis=1)
        want_t, want_i = brute_force(v, t, rays)
        hit = np.isfinite(want_t)
        assert hit.sum() > 100
        ans = scene.cast_rays(rays)
        got_i = ans["primitive_ids"].astype(np.int64)
        assert ((got_i != raykit.INVALID_ID) == hit).all(), f"{far}: hit/miss differs"
        same = ties(t, got_i[hit], want_i[hit])
        assert same.all(), f"{far}: {int((~same).sum())} rays hit another triangle"
        gap = np.abs(ans["t_hit"][hit] - want_t[hit]) / want_t[hit]
        assert gap.max() <= 2e-7, f"{far}: t_hit off by {gap.max():.1e} of t"
        first = engine.intersects_first(rays[:, :3], rays[:, 3:])
        assert ((first >= 0) == hit).all() and ties(t, first[hit], want_i[hit]).all()
        lists = scene.list_intersections(rays)
        splits = lists["ray_splits"].astype(np.int64)
        assert ((splits[1:] > splits[:-1]) == hit).all()
        firsts = splits[:-1][hit]
        assert ties(t, lists["primitive_ids"][firsts].astype(np.int64), want_i[hit]).all()
        assert (np.abs(lists["t_hit"][firsts] - want_t[hit]) / want_t[hit]).max() <= 2e-7
        counts = scene.count_intersections(rays)
        assert (counts[hit] % 2 == 0).all() and (counts[~hit] == 0).all()
        assert (scene.test_occlusions(rays) == hit).all()
        # Intervals other than [0, inf) move with each ray (every hit lies
        # beyond t = 1 here).
        assert (scene.test_occlusions(rays, tfar=1e30) == hit).all()
        assert (scene.test_occlusions(rays, tnear=1.0) == hit).all()
        # Float32 rays are the float64 rays they round to: counted alike.
        r32 = rays.astype(np.float32)
        np.testing.assert_array_equal(
            scene.count_intersections(r32), scene.count_intersections(r32.astype(np.float64))
        )
        hit32 = scene.cast_rays(r32)["primitive_ids"] != raykit.INVALID_ID
        assert (scene.count_intersections(r32)[hit32] > 0).all()


def test_rays_from_beyond_1e16_still_cross_a_unit_box_twice():
    """From about 10¹⁶ on, doubles are spaced wider than a unit box: an
    origin moved up to the box along an axis rounds by more than the box's
    size. The box's two crossings, which the axis-parallel lines through it
    make by construction, are still counted and listed."""
    box = raykit.RaycastingScene()
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    box.add_triangles(corners, np.array([tri for a, b, c, d in quads for tri in ((a, b, c), (a, c, d))]))
    rng = np.random.default_rng(21)
    for far in (1e15, 3e16, 1e17, 1e18):
        yz = rng.uniform(-0.4, 0.4, size=(50, 2))
        rays = np.column_stack([np.full(50, far), yz, np.full(50, -1.0), np.zeros((50, 2))])
        np.testing.assert_array_equal(box.count_intersections(rays), 2, err_msg=f"{far:g}")
        np.testing.assert_array_equal(np.diff(box.list_intersections(rays)["ray_splits"]), 2, err_msg=f"{far:g}")
        # t_hit is float32, as Open3D's: right to its spacing there.
        t = box.cast_rays(rays)["t_hit"].astype(np.float64)
        assert (np.abs(t - (far - 0.5)) <= np.spacing(np.float32(far))).all(), f"{far:g}: {t[:3]}"


def test_vertices_no_triangle_uses_leave_a_far_model_its_precision(bunny):
    """An unused vertex at zero (or far away) next to a model at UTM
    coordinates: the scene's origin and the trimesh engine's shift come
    from the vertices the triangles use, so the answers are the model's
    without the extra vertex."""
    v, t, _ = bunny
    v = v.astype(np.float64) * 100.0 + FAR
    rays = rays_at(v, 2000, 21).astype(np.float64)
    plain = raykit.RaycastingScene()
    plain.add_triangles(v, t)
    want = plain.cast_rays(rays)

    class Mesh:
        def __init__(self, vertices):
            self.vertices, self.faces, self.scale = vertices, t.astype(np.int64), 100.0

    first = raykit.trimesh.RayMeshIntersector(Mesh(v)).intersects_first(rays[:, :3], rays[:, 3:])
    for spare in ([0.0, 0.0, 0.0], [-1e9, 0.0, 0.0], [1e30, 0.0, 0.0]):
        with_spare = np.concatenate([v, [spare]])
        scene = raykit.RaycastingScene()
        scene.add_triangles(with_spare, t)
        np.testing.assert_array_equal(scene.origin, plain.origin)
        np.testing.assert_array_equal(scene.cast_rays(rays)["t_hit"], want["t_hit"])
        got = raykit.trimesh.RayMeshIntersector(Mesh(with_spare)).intersects_first(rays[:, :3], rays[:, 3:])
        np.testing.assert_array_equal(got, first)
    # A used vertex finite in float64 but beyond float32 is named as beyond.
    huge = v.copy()
    huge[int(t[0, 0])] = [1e40, 0.0, 0.0]
    with pytest.raises(ValueError, match=f"vertex {int(t[0, 0])} has a coordinate beyond"):
        raykit.RaycastingScene().add_triangles(huge, t)


def test_float32_input_far_away_is_stored_without_rounding(model):
    """Float32 coordinates at UTM positions are already rounded; the origin
    lies on a grid fine enough that moving them by it rounds nothing more."""
    v, t = model
    v32 = (v + FAR).astype(np.float32)
    scene = scene_of(v32, t)
    stored = scene._vertices[0].astype(np.float64) + scene.origin
    assert np.array_equal(stored, v32.astype(np.float64))


def test_instances_placed_far_away_with_a_given_origin(model):
    """A geometry near zero placed far away by instances: with ``origin=``
    its hits are those of the same placements near zero."""
    v, t = model
    lift = np.eye(4)
    lift[:3, 3] = [10.0, -20.0, 5.0]
    spin = np.array([[0.0, -1.0, 0.0, 150.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    near = raykit.RaycastingScene()
    far = raykit.RaycastingScene(origin=FAR)
    for scene, shift in ((near, np.zeros(3)), (far, FAR)):
        g = scene.add_triangles(v, t, place=False)
        for m in (lift, spin):
            placed = m.copy()
            placed[:3, 3] += shift
            scene.add_instance(g, placed)
    corners = np.concatenate([v + lift[:3, 3], v @ spin[:3, :3].T + spin[:3, 3]])
    rays = rays_at(corners, 8000, 3).astype(np.float64)
    moved = rays.copy()
    moved[:, :3] += FAR
    a, b = near.cast_rays(rays), far.cast_rays(moved)
    assert_same_hits(a, b, rays, "instances")
    hit = a["primitive_ids"] != raykit.INVALID_ID
    assert (a["instance_ids"][hit] == b["instance_ids"][hit]).mean() >= 0.999


def test_a_far_scene_saved_for_workers_loads_with_its_origin(model, tmp_path):
    v, t = model
    far = scene_of(v + FAR, t)
    path = distributed.save_scene(far, tmp_path)
    loaded = distributed.load_scene(path)
    assert np.array_equal(loaded.origin, far.origin)
    rays = rays_at(v, 4000, 4).astype(np.float64)
    rays[:, :3] += FAR
    a, b = far.cast_rays(rays), loaded.cast_rays(rays)
    assert np.array_equal(a["primitive_ids"], b["primitive_ids"])
    assert np.array_equal(a["t_hit"], b["t_hit"])


def test_a_far_scene_renders_as_near_zero(model):
    v, t = model
    eye, target = np.array([180.0, 140.0, 160.0]), np.array([50.0, 40.0, 50.0])
    near = raykit.render(scene_of(v, t), 96, 72, eye=eye, target=target)
    far = raykit.render(scene_of(v + FAR, t), 96, 72, eye=eye + FAR, target=target + FAR)
    assert near.std() > 10
    differ = (np.abs(near.astype(int) - far.astype(int)).max(axis=2) > 8).mean()
    assert differ <= 0.01, f"{differ:.2%} of the pixels differ"


def test_load_mesh_keeps_utm_coordinates_to_the_file_digits(model, tmp_path):
    """An OBJ written at UTM coordinates loads as float64 within float32's
    spacing at the model's size of what numpy reads from the same lines
    (float32 at the northing is 0.5 m apart), and near zero as float32."""
    v, t = model
    for name, shift in (("far.obj", FAR), ("near.obj", np.zeros(3))):
        path = tmp_path / name
        with open(path, "w") as f:
            for p in v + shift:
                f.write("v %r %r %r\n" % tuple(float(c) for c in p))
            for a, b, c in t + 1:
                f.write(f"f {a} {b} {c}\n")
        want = np.loadtxt(path, usecols=(1, 2, 3), max_rows=len(v))
        got, triangles, _ = raykit.load_mesh(path)
        assert np.array_equal(triangles, t)
        if name == "far.obj":
            assert got.dtype == np.float64
            assert np.abs(got - want).max() <= 1e-5
        else:
            assert got.dtype == np.float32
            assert np.array_equal(got, want.astype(np.float32))


def test_origin_must_be_three_finite_numbers():
    for bad in ([1.0, 2.0], [0.0, np.nan, 0.0], "abc"):
        with pytest.raises(ValueError, match="origin"):
            raykit.RaycastingScene(origin=bad)


def _write_placed_glb(path, local: np.ndarray, triangles: np.ndarray, translation, turn_deg: float, scale: float):
    """A GLB of the float32 model ``local`` whose root node is translated by
    ``translation`` (written with all its float64 digits) and whose child,
    holding the mesh, turns it by ``turn_deg`` about the vertical and
    scales it by ``scale``."""
    half = math.radians(turn_deg) / 2
    positions = np.ascontiguousarray(local, dtype="<f4").tobytes()
    indices = np.ascontiguousarray(triangles, dtype="<u4").tobytes()
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"translation": [float(c) for c in translation], "children": [1]},
            {"mesh": 0, "rotation": [0.0, 0.0, math.sin(half), math.cos(half)], "scale": [scale] * 3},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": len(local),
                "type": "VEC3",
                "min": local.min(axis=0).tolist(),
                "max": local.max(axis=0).tolist(),
            },
            {"bufferView": 1, "componentType": 5125, "count": triangles.size, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteLength": len(positions)},
            {"buffer": 0, "byteOffset": len(positions), "byteLength": len(indices)},
        ],
        "buffers": [{"byteLength": len(positions) + len(indices)}],
    }
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary = positions + indices
    binary += b"\0" * (-len(binary) % 4)
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + 8 + len(binary)))
        f.write(struct.pack("<II", len(text), 0x4E4F534A) + text)
        f.write(struct.pack("<II", len(binary), 0x004E4942) + binary)


def test_gltf_placed_at_utm_by_its_nodes_keeps_its_digits(model, tmp_path):
    """A glTF whose root node carries the UTM translation (as geospatial
    exporters write them): ``load_mesh`` returns float64 vertices within a
    tenth of a millimetre of the placement composed in numpy's float64, and
    ``add_gltf`` answers as the same placement does near zero; float32
    transforms would move the model by decimetres."""
    v, t = model
    local = v.astype(np.float32)
    at = FAR + np.array([0.123, 0.456, 0.789])
    path = tmp_path / "placed.glb"
    _write_placed_glb(path, local, t, at, 30.0, 1.5)
    c, s = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) * 1.5
    placed = local.astype(np.float64) @ turn.T
    want = placed + at

    got, triangles, _ = raykit.load_mesh(path)
    assert got.dtype == np.float64 and np.array_equal(triangles, t)
    assert np.abs(got - want).max() <= 1e-4, np.abs(got - want).max()
    assert np.abs(want.astype(np.float32) - want).max() > 0.05

    (geometry, matrix, node, _), = raykit.load_gltf_instances(path)[1]
    assert node == 1 and np.abs(matrix[:, 3] - at).max() == 0.0

    far = raykit.RaycastingScene()
    far.add_gltf(path)
    assert np.abs(far.origin - at).max() <= 256.0, far.origin
    near = scene_of(placed, t)
    rays = rays_at(placed, 8000, 5).astype(np.float64)
    moved = rays.copy()
    moved[:, :3] += at
    assert_same_hits(near.cast_rays(rays), far.cast_rays(moved), rays, "add_gltf")


def test_a_geometry_added_moved_or_placed_far_from_the_origin_is_warned_about(model):
    """float32 at UTM metres is half a metre apart: a model added, moved or
    placed there in a scene whose origin lies elsewhere is warned about,
    with the spacing it is kept to; near the origin, or with an origin
    chosen or given near it, nothing is said."""
    import warnings

    v, t = model
    scene = scene_of(v, t)
    step = float(np.spacing(np.float32(FAR.max())))
    with pytest.warns(UserWarning, match=f"geometry 1 lies .* {step:.3g} apart"):
        scene.add_triangles(v + FAR, t)
    with pytest.warns(UserWarning, match="instance 2 lies"):
        scene.add_instance(0, np.hstack([np.eye(3), FAR[:, None]]))
    with pytest.warns(UserWarning, match="geometry 0 lies"):
        scene.update_vertices(0, v + FAR)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        near = raykit.RaycastingScene(origin=FAR)
        near.add_triangles(v + FAR, t)
        near.add_triangles(v + FAR + 500.0, t)
        near.add_instance(0, np.hstack([np.eye(3), [[700.0], [0.0], [0.0]]]))
        alone = scene_of(v, t)
        alone.add_triangles(v + 1000.0, t)
        chosen = scene_of(v + FAR, t)
        chosen.update_vertices(0, v + FAR + 10.0)
        single = scene_of(v, t)
        single.update_vertices(0, v + FAR)
