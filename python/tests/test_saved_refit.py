"""RaycastingScene.save / load_structure (a saved BVH loaded instead of
built) and update_vertices (the BVH refit to moved vertices): a loaded
scene answers as the built one and as Open3D, a damaged file, a missing
file and a file saved for another mesh are refused, and a refit scene
answers as a scene built on the moved mesh."""

from __future__ import annotations

import os

import numpy as np
import open3d as o3d
import pytest

import raykit
from conftest import rays_at, ties


def scene_of(*meshes, **kw):
    s = raykit.RaycastingScene(**kw)
    for v, f in meshes:
        s.add_triangles(v, f)
    return s


def assert_same_answers(a: dict, b: dict) -> None:
    """Every output of two cast_rays calls equal, bit for bit."""
    assert set(a) == set(b)
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def displaced(v: np.ndarray, amount: float, seed: int) -> np.ndarray:
    """``v`` moved by a smooth wave of ``amount`` times the mesh's size,
    as a deforming surface moves."""
    rng = np.random.default_rng(seed)
    size = float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))
    k = rng.normal(size=(3, 3)) * 6.0 / size
    phase = rng.uniform(0, 2 * np.pi, size=3)
    wave = np.sin(v.astype(np.float64) @ k + phase)
    return (v + amount * size * wave).astype(np.float32)


@pytest.mark.parametrize("accel", ["bvh8", "bvh4"])
def test_a_loaded_structure_answers_as_the_built_one_and_open3d(dragon, tmp_path, accel):
    v, f, _ = dragon
    rays = rays_at(v, 20000, seed=31)
    built = scene_of((v, f), accel=accel)
    path = tmp_path / f"dragon.{accel}"
    built.save(path)
    loaded = scene_of((v, f))
    loaded.load_structure(path)
    assert loaded.accel == accel and loaded.test == built.test
    assert loaded.stats() == built.stats()
    mine = loaded.cast_rays(rays)
    assert_same_answers(mine, built.cast_rays(rays))
    np.testing.assert_array_equal(loaded.test_occlusions(rays), built.test_occlusions(rays))
    # And Open3D's answers, within edge ties.
    theirs = o3d.t.geometry.RaycastingScene()
    theirs.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(f))
    b = {k: x.numpy() for k, x in theirs.cast_rays(o3d.core.Tensor(rays)).items()}
    hit_a, hit_b = np.isfinite(mine["t_hit"]), np.isfinite(b["t_hit"])
    assert hit_a.sum() > 2000 and (hit_a != hit_b).sum() <= 2
    both = hit_a & hit_b
    close = np.isclose(mine["t_hit"][both], b["t_hit"][both], rtol=1e-4)
    assert (~close).sum() <= 2
    assert ties(f, mine["primitive_ids"][both][close], b["primitive_ids"][both][close]).all()


def test_a_loaded_structure_keeps_geometry_ids(bunny, dragon, tmp_path):
    (bv, bf, _), (dv, df, _) = bunny, dragon
    rays = np.concatenate([rays_at(bv, 3000, seed=32), rays_at(dv, 3000, seed=33)])
    built = scene_of((bv, bf), (dv, df))
    built.save(str(tmp_path / "two.bvh"))
    loaded = scene_of((bv, bf), (dv, df))
    loaded.load_structure(str(tmp_path / "two.bvh"))
    a = loaded.cast_rays(rays)
    assert set(np.unique(a["geometry_ids"])) == {0, 1, raykit.RaycastingScene.INVALID_ID}
    assert_same_answers(a, built.cast_rays(rays))


def test_a_damaged_file_is_refused_with_value_error(bunny, tmp_path):
    v, f, _ = bunny
    path = tmp_path / "bunny.bvh"
    scene_of((v, f)).save(path)
    data = bytearray(path.read_bytes())
    # One flipped bit at several places: header, nodes, leaves, the end.
    for at in (20, len(data) // 3, len(data) // 2, len(data) - 1):
        damaged = bytearray(data)
        damaged[at] ^= 0x10
        bad = tmp_path / f"damaged_{at}.bvh"
        bad.write_bytes(bytes(damaged))
        with pytest.raises(ValueError, match="offset"):
            scene_of((v, f)).load_structure(bad)
    truncated = tmp_path / "truncated.bvh"
    truncated.write_bytes(bytes(data[: len(data) // 2]))
    with pytest.raises(ValueError, match="truncated.bvh"):
        scene_of((v, f)).load_structure(truncated)


def test_a_missing_file_is_an_os_error(bunny, tmp_path):
    v, f, _ = bunny
    with pytest.raises(FileNotFoundError, match="absent.bvh"):
        scene_of((v, f)).load_structure(tmp_path / "absent.bvh")
    with pytest.raises(OSError):
        scene_of((v, f)).save(tmp_path / "no_such_folder" / "x.bvh")


def test_a_file_for_another_mesh_is_refused(bunny, dragon, tmp_path):
    (bv, bf, _), (dv, df, _) = bunny, dragon
    path = tmp_path / "bunny.bvh"
    scene_of((bv, bf)).save(path)
    with pytest.raises(ValueError, match="bunny.bvh"):
        scene_of((dv, df)).load_structure(path)
    # The same triangles with one vertex moved: another mesh too.
    moved = bv.copy()
    moved[7, 1] += 1e-3
    with pytest.raises(ValueError, match="bunny.bvh"):
        scene_of((moved, bf)).load_structure(path)
    # The refused load leaves the scene able to build its own structure.
    s = scene_of((moved, bf))
    with pytest.raises(ValueError):
        s.load_structure(path)
    rays = rays_at(moved, 500, seed=34)
    assert_same_answers(s.cast_rays(rays), scene_of((moved, bf)).cast_rays(rays))


def test_structures_without_a_saved_form_refuse_to_save(bunny, tmp_path):
    v, f, _ = bunny
    with pytest.raises(ValueError, match="no saved form"):
        scene_of((v, f), accel="kd-stack").save(tmp_path / "kd.bvh")
    with pytest.raises(ValueError, match="no triangles"):
        raykit.RaycastingScene().save(tmp_path / "empty.bvh")


@pytest.mark.parametrize("accel", ["bvh8", "bvh4", "kd-ropes"])
def test_update_vertices_answers_as_a_fresh_build(dragon, accel):
    v, f, _ = dragon
    moved = displaced(v, 0.03, seed=35)
    rays = rays_at(moved, 20000, seed=36)
    scene = scene_of((v, f), accel=accel)
    scene.cast_rays(rays[:10])  # build the structure over the first mesh
    report = scene.update_vertices(0, moved)
    assert report is not None
    if accel == "kd-ropes":  # no refit: rebuilt
        assert report["rebuilt"] and np.isnan(report["degradation"])
    else:
        assert not report["rebuilt"] and report["degradation"] >= 1.0
    fresh = scene_of((moved, f), accel=accel)
    a, b = scene.cast_rays(rays), fresh.cast_rays(rays)
    hit = np.isfinite(b["t_hit"])
    assert hit.sum() > 2000
    # The same triangles are tested ray for ray; only the order differs, so
    # distances agree exactly and triangles up to ties at the same distance
    # (neighbours near their shared edge, where both tests hit).
    np.testing.assert_array_equal(a["t_hit"], b["t_hit"])
    diff = a["primitive_ids"] != b["primitive_ids"]
    assert diff.sum() <= 0.005 * hit.sum()
    assert ties(f, a["primitive_ids"][diff], b["primitive_ids"][diff]).all()
    np.testing.assert_array_equal(scene.test_occlusions(rays), fresh.test_occlusions(rays))


def test_update_vertices_of_one_geometry_and_point_queries(bunny, dragon):
    (bv, bf, _), (dv, df, _) = bunny, dragon
    moved = displaced(dv, 0.05, seed=37)
    scene = scene_of((bv, bf), (dv, df))
    points = rays_at(moved, 2000, seed=38)[:, :3] * 0.5
    before = scene.compute_distance(points)  # builds the point-query BVH
    scene.update_vertices(1, moved)
    fresh = scene_of((bv, bf), (moved, df))
    after = scene.compute_distance(points)
    np.testing.assert_array_equal(after, fresh.compute_distance(points))
    assert (after != before).any()
    rays = np.concatenate([rays_at(bv, 2000, seed=39), rays_at(moved, 2000, seed=40)])
    a, b = scene.cast_rays(rays), fresh.cast_rays(rays)
    np.testing.assert_array_equal(a["t_hit"], b["t_hit"])
    np.testing.assert_array_equal(a["geometry_ids"], b["geometry_ids"])


def test_update_vertices_before_any_ray_query(dragon):
    """A scene asked only point queries has no ray structure yet: moving its
    vertices refits nothing (``None``), and the first ray query builds the
    structure from the new vertices, answering as a fresh scene."""
    v, f, _ = dragon
    moved = displaced(v, 0.03, seed=43)
    points = rays_at(moved, 2000, seed=44)[:, :3] * 0.5
    scene = scene_of((v, f))
    scene.compute_distance(points)
    assert scene.update_vertices(0, moved) is None
    fresh = scene_of((moved, f))
    rays = rays_at(moved, 5000, seed=45)
    a, b = scene.cast_rays(rays), fresh.cast_rays(rays)
    assert np.isfinite(b["t_hit"]).sum() > 1000
    np.testing.assert_array_equal(a["t_hit"], b["t_hit"])
    np.testing.assert_array_equal(a["primitive_ids"], b["primitive_ids"])
    np.testing.assert_array_equal(scene.compute_distance(points), fresh.compute_distance(points))


def test_update_vertices_rebuilds_past_the_degradation_limit(bunny):
    v, f, _ = bunny
    # Vertices scattered at random: the refit boxes overlap everywhere.
    scrambled = np.random.default_rng(41).permutation(v)
    scene = scene_of((v, f))
    scene.stats()
    report = scene.update_vertices(0, scrambled)
    assert report["rebuilt"] and report["degradation"] > 1.5
    rays = rays_at(scrambled, 3000, seed=42)
    fresh = scene_of((scrambled, f))
    assert scene.stats() == fresh.stats()
    np.testing.assert_array_equal(scene.cast_rays(rays)["t_hit"], fresh.cast_rays(rays)["t_hit"])
    # A limit of infinity keeps the refit tree, which answers the same.
    kept = scene_of((v, f))
    kept.stats()
    report = kept.update_vertices(0, scrambled, max_degradation=float("inf"))
    assert not report["rebuilt"] and report["degradation"] > 1.5
    np.testing.assert_array_equal(kept.cast_rays(rays)["t_hit"], fresh.cast_rays(rays)["t_hit"])
    with pytest.raises(ValueError, match="max_degradation"):
        kept.update_vertices(0, v, max_degradation=0.5)


@pytest.mark.parametrize("test", ["plucker", "projection"])
def test_a_model_moved_far_is_rebuilt_for_the_tests_that_need_it_near(bunny, test):
    """The Plücker and projection tests multiply coordinates: a model moved
    far from where its structure was built is rebuilt rather than refit
    (a refit kept the build's placement and gave other triangles and
    barycentrics). A scene of two geometries keeps its origin, so once both
    are moved the model really lies far; the answers are then a fresh
    scene's, bit for bit."""
    v, f, _ = bunny
    v = v.astype(np.float64)
    size = float(np.ptp(v, axis=0).max())
    other = v + np.array([2.0, 0.0, 0.0]) * size
    away = np.array([3e4, -2e4, 1e4]) * size
    scene = scene_of((v, f), (other, f), test=test)
    scene.stats()
    # The first moved geometry and the other span the way between: a build
    # over them would not move them either, so they refit. Both now lie far
    # from the scene's origin, which the scene warns about.
    with pytest.warns(UserWarning, match="lies .* from the scene's origin"):
        assert not scene.update_vertices(0, v + away)["rebuilt"]
        assert scene.update_vertices(1, other + away)["rebuilt"]
        # Made with the first scene's origin (zero), the fresh scene holds
        # the same float32 vertices.
        fresh = scene_of((v + away, f), (other + away, f), test=test, origin=[0.0, 0.0, 0.0])
    rays = rays_at(np.concatenate([v, other]) + away, 3000, seed=46).astype(np.float64)
    a, b = scene.cast_rays(rays), fresh.cast_rays(rays)
    assert np.isfinite(b["t_hit"]).sum() > 1000
    assert_same_answers(a, b)
    # Deformed in place, the same scene refits.
    with pytest.warns(UserWarning, match="lies"):
        assert not scene.update_vertices(1, other + away + 1e-3 * size)["rebuilt"]


def test_update_vertices_before_a_build_and_bad_input(bunny):
    v, f, _ = bunny
    moved = displaced(v, 0.02, seed=43)
    scene = scene_of((v, f))
    assert scene.update_vertices(0, moved) is None  # built at the next query
    rays = rays_at(moved, 1000, seed=44)
    assert_same_answers(scene.cast_rays(rays), scene_of((moved, f)).cast_rays(rays))
    with pytest.raises(ValueError, match="geometry_id"):
        scene.update_vertices(1, moved)
    with pytest.raises(ValueError, match="shape"):
        scene.update_vertices(0, moved[:-1])
    nan = moved.copy()
    nan[5, 2] = np.nan
    with pytest.raises(ValueError, match="vertex 5"):
        scene.update_vertices(0, nan)
    far = moved.astype(np.float64)
    far[6, 0] = 1e14
    with pytest.raises(ValueError, match="vertex 6 has a coordinate beyond"):
        scene.update_vertices(0, far)
    with pytest.raises(ValueError, match="vertex 6 has a coordinate beyond"):
        scene_of((v, f)).update_vertices(0, far)
    # A refused update leaves the scene as it was.
    assert_same_answers(scene.cast_rays(rays), scene_of((moved, f)).cast_rays(rays))


def test_save_and_load_take_the_paths_open_takes(bunny, tmp_path):
    v, f, _ = bunny
    rays = rays_at(v, 300, 4)
    built = scene_of((v, f))
    ref = built.cast_rays(rays)
    for kind, to_path in (("str", str), ("bytes", os.fsencode), ("PathLike", lambda p: p)):
        path = tmp_path / f"{kind}.bvh"
        built.save(to_path(path))
        assert path.stat().st_size > 0, kind
        loaded = scene_of((v, f))
        loaded.load_structure(to_path(path))
        assert_same_answers(loaded.cast_rays(rays), ref)
    with pytest.raises(TypeError, match="path must be a str, bytes or os.PathLike"):
        built.save(3)
