"""render and cull: images of a scene, and culling of an assembly whose
hidden part is known by construction."""

from __future__ import annotations

import os

import numpy as np
import pytest
import trimesh

import raykit
from conftest import rays_at


def box(centre, half):
    b = trimesh.creation.box(extents=np.full(3, 2 * half))
    return b.vertices + centre, b.faces


def test_render_shows_the_mesh_where_rays_hit(bunny):
    v, f, _ = bunny
    scene = raykit.RaycastingScene()
    scene.add_triangles(v, f)
    image = raykit.render(scene, 96, 64)
    assert image.shape == (64, 96, 3) and image.dtype == np.uint8
    # The same picture from a mesh, and from one thread.
    np.testing.assert_array_equal(raykit.render(trimesh.Trimesh(v, f, process=False), 96, 64, threads=1), image)
    # A camera looking away sees only the background.
    centre = (v.min(0) + v.max(0)) / 2
    away = raykit.render(scene, 32, 24, eye=centre + [0, 0, 1], target=centre + [0, 0, 2])
    assert (away == away[0, 0]).all()
    # Pixels differ from the background where the mesh is.
    looking = raykit.render(scene, 32, 24, eye=centre + [0, 0, 1], target=centre, shadows=False)
    assert (looking != looking[0, 0]).any(axis=-1).mean() > 0.2
    with pytest.raises(ValueError, match="no triangles"):
        raykit.render(raykit.RaycastingScene())
    with pytest.raises(ValueError, match="fov"):
        raykit.render(scene, fov=0)
    with pytest.raises(ValueError, match="width and height"):
        raykit.render(scene, 0, 10)
    # Negative, huge and non-integer counts are ValueErrors naming the
    # argument, not the OverflowError of the conversion to unsigned.
    # Out of range, the message gives the range that holds.
    for kwargs, name in [
        (dict(width=-1), "width and height must be between 1 and 16384, got -1"),
        (dict(height=2**40), "height"),
        (dict(height=2**70), "height"),
        (dict(samples_per_pixel=-1), "samples_per_pixel must be between 1 and 4096, got -1"),
        (dict(window=(-1, 0, 4, 4)), "window"),
        (dict(width=32.5), "width"),
    ]:
        with pytest.raises(ValueError, match=name):
            raykit.render(scene, **kwargs)


def test_cull_removes_a_box_sealed_inside_another():
    outer_v, outer_f = box(np.zeros(3), 1.0)
    inner_v, inner_f = box(np.zeros(3), 0.3)
    v = np.concatenate([outer_v, inner_v])
    f = np.concatenate([outer_f, inner_f + len(outer_v)])
    parts = np.repeat([0, 1], [len(outer_f), len(inner_f)])
    for conservative in (True, False):
        result = raykit.cull(v, f, parts, resolution=32, conservative=conservative)
        np.testing.assert_array_equal(result.keep, np.repeat([True, False], [len(outer_f), len(inner_f)]))
        np.testing.assert_array_equal(result.part_keep, [True, False])
        assert result.stats["triangles_removed"] == len(inner_f)
    # A box beside the first instead of inside it stays.
    beside = np.concatenate([outer_v, inner_v + [3.0, 0, 0]])
    assert raykit.cull(beside, f, resolution=32).keep.all()
    for resolution in (1, -1, 2**70):
        with pytest.raises(ValueError, match="resolution"):
            raykit.cull(v, f, resolution=resolution)
    with pytest.raises(ValueError, match="resolution must be between 4 and 2048 grid points, got -1"):
        raykit.cull(v, f, resolution=-1)
    with pytest.raises(ValueError, match="one per triangle"):
        raykit.cull(v, f, parts[:3])
    with pytest.raises(ValueError, match="refers to vertex"):
        raykit.cull(v[:4], f)
    nan = v.copy()
    nan[0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        raykit.cull(nan, f)
    empty = raykit.cull(np.zeros((0, 3)), np.zeros((0, 3), np.int32))
    assert empty.keep.shape == (0,)


def test_cull_a_mesh_file(data):
    result = raykit.cull(data / "meshes" / "2CylinderEngine.glb", resolution=48)
    v, f, parts = raykit.load_mesh(data / "meshes" / "2CylinderEngine.glb")
    assert result.keep.shape == (len(f),) and result.part_keep.shape == (parts.max() + 1,)
    assert 0 < result.keep.mean() <= 1
    # A bytes path names the same file.
    from_bytes = raykit.cull(os.fsencode(data / "meshes" / "2CylinderEngine.glb"), resolution=48)
    np.testing.assert_array_equal(from_bytes.keep, result.keep)


def test_cull_refuses_part_ids_it_cannot_hold():
    outer_v, outer_f = box(np.zeros(3), 1.0)
    inner_v, inner_f = box(np.zeros(3), 0.3)
    v = np.concatenate([outer_v, inner_v])
    f = np.concatenate([outer_f, inner_f + len(outer_v)])
    m = len(f)
    # Ids may skip numbers: parts 0 and 7 are parts 0 and 7 of eight.
    sparse = raykit.cull(v, f, np.repeat([0, 7], [len(outer_f), len(inner_f)]), resolution=32)
    np.testing.assert_array_equal(sparse.keep, np.repeat([True, False], [len(outer_f), len(inner_f)]))
    assert sparse.part_keep.shape == (8,) and sparse.part_keep[0] and not sparse.part_keep[7]
    # An id past the bound is refused, naming it, rather than allocating a
    # part per id up to it; one past uint32 rather than wrapped round.
    for big in (2**31, 2**20 + 5):
        with pytest.raises(ValueError, match=f"largest part id is {big}"):
            raykit.cull(v, f, np.full(m, big, np.int64), resolution=32)
    with pytest.raises(ValueError, match=f"largest part id is {2**32 + 5}"):
        raykit.cull(v, f, np.full(m, 2**32 + 5, np.int64), resolution=32)


def test_render_refuses_a_camera_without_a_direction(bunny):
    v, f, _ = bunny
    scene = raykit.RaycastingScene()
    scene.add_triangles(v, f)
    centre = (v.min(0) + v.max(0)) / 2
    eye = centre + [0.0, 0.0, 1.0]
    image = raykit.render(scene, 24, 16, eye=eye, target=centre)
    # up is a direction: its length does not matter.
    np.testing.assert_array_equal(raykit.render(scene, 24, 16, eye=eye, target=centre, up=(0, 3, 0)), image)
    for bad in (np.nan, np.inf, 1e300):
        with pytest.raises(ValueError, match="up must be three finite numbers"):
            raykit.render(scene, 24, 16, eye=eye, target=centre, up=(bad, 1, 0))
        with pytest.raises(ValueError, match="eye .* and target .* must be finite"):
            raykit.render(scene, 24, 16, eye=(bad, 0, 1), target=centre)
        with pytest.raises(ValueError, match="eye .* and target .* must be finite"):
            raykit.render(scene, 24, 16, eye=eye, target=(0, bad, 0))
    with pytest.raises(ValueError, match="must be finite and differ"):
        raykit.render(scene, 24, 16, eye=centre, target=centre)


@pytest.mark.filterwarnings("ignore::rasterio.errors.NotGeoreferencedWarning")
def test_up_is_checked_as_the_command_line_checks_it(tmp_path):
    """``up`` zero, not finite, or along the view is refused naming ``up``,
    where ``raykit render --up`` refuses it (the default up too, with an
    eye above the box's centre); ``up`` without ``eye`` is refused rather
    than ignored; an ``up`` across the view turns the image: ``-up`` shows
    it upside down (a hand-made camera: the same rays, pixels mirrored)."""
    import subprocess

    from conftest import raykit_cli

    v, f = box(np.array([0.5, 0.0, -0.25]), 1.0)
    v = v * [1.0, 1.5, 0.7]
    scene = raykit.RaycastingScene()
    scene.add_triangles(v, f)
    centre = (v.min(0) + v.max(0)) / 2
    above = centre + [0.0, 6.0, 0.0]
    cases = [
        (dict(eye=above), True),  # the default up (0, 1, 0) along the view
        (dict(eye=above, up=(0, -2, 0)), True),
        (dict(eye=above, target=centre + [0, 0, 3e-5], up=(0, 1, 0)), True),  # 5e-6 rad off: within the CLI's 1e-4
        (dict(eye=above, up=(0, 0, 0)), True),
        (dict(eye=above, up=(0, 0, 1)), False),
        (dict(eye=above, target=centre + [0, 0, 0.01], up=(0, 1, 0)), False),
        (dict(eye=centre + [3.0, 2.0, 4.0]), False),
    ]
    cli = raykit_cli()
    obj = tmp_path / "box.obj"
    trimesh.Trimesh(v, f, process=False).export(obj)
    for kw, refused in cases:
        flags = [f"--{k}={','.join(repr(float(c)) for c in x)}" for k, x in kw.items()]
        run = subprocess.run(
            [cli, "render", "--scene", str(obj), "--width", "8", "--height", "6", "--out", str(tmp_path / "r.png"), *flags],
            capture_output=True, text=True,
        )
        assert (run.returncode != 0) == refused, (kw, run.stderr)
        if refused:
            assert "--up" in run.stderr
            with pytest.raises(ValueError, match="^up "):
                raykit.render(scene, 8, 6, **kw)
        else:
            assert raykit.render(scene, 8, 6, **kw).shape == (6, 8, 3)
    for up in ((0, 0, 1), (np.nan, 0, 1), (0, 0, 0)):
        with pytest.raises(ValueError, match="^up "):
            raykit.render(scene, 8, 6, up=up)
    eye = centre + [3.0, 2.0, 4.0]
    across = np.cross(centre - eye, [1.0, 0.0, 0.0])
    one = raykit.render(scene, 40, 30, eye=eye, up=across, shadows=False)
    turned = raykit.render(scene, 40, 30, eye=eye, up=-across, shadows=False)
    assert (one != one[0, 0]).any(axis=-1).mean() > 0.1
    assert np.abs(turned.astype(int) - one[::-1, ::-1]).max() <= 1
