"""examples/python/open3d_compat.py, a script written for Open3D's
RaycastingScene, runs unchanged on raykit (only its import differs) and
gives Open3D's answers."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

import raykit
from conftest import REPO, ties

SCRIPT = REPO / "examples" / "python" / "open3d_compat.py"


def run(mesh, out, *flags):
    # The script imports the raykit these tests import (installed or in place).
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(raykit.__file__).parents[1]), os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run(
        [sys.executable, str(SCRIPT), str(mesh), str(out), *flags], capture_output=True, text=True, env=env
    )
    assert done.returncode == 0, done.stderr
    return np.load(out), done.stdout


def test_the_open3d_script_gives_the_same_answers_on_raykit(data, tmp_path):
    mesh = data / "meshes" / "bunny_3674.obj"
    ours, text = run(mesh, tmp_path / "raykit.npz")
    theirs, text_o3d = run(mesh, tmp_path / "open3d.npz", "--open3d")
    assert "geometries 0 and 1" in text and "geometries 0 and 1" in text_o3d
    np.testing.assert_allclose(ours["rays"], theirs["rays"], rtol=1e-5, atol=1e-5)
    for key in ("t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals", "shadowed"):
        assert ours[key].shape == theirs[key].shape and ours[key].dtype == theirs[key].dtype, key
    hit, hit_o3d = np.isfinite(ours["t_hit"]), np.isfinite(theirs["t_hit"])
    assert hit.mean() > 0.1
    assert (hit != hit_o3d).sum() <= 2  # silhouette grazes decided by rounding
    both = hit & hit_o3d
    np.testing.assert_allclose(ours["t_hit"][both], theirs["t_hit"][both], rtol=1e-4)
    np.testing.assert_array_equal(ours["geometry_ids"][both], theirs["geometry_ids"][both])
    same = ours["primitive_ids"][both] == theirs["primitive_ids"][both]
    # Near a shared edge each may pick the neighbour (same OBJ order in the
    # script's reader and raykit's).
    _, triangles, _ = raykit.load_mesh(mesh)
    assert ties(triangles, ours["primitive_ids"][both], theirs["primitive_ids"][both]).all()
    np.testing.assert_allclose(ours["primitive_normals"][both][same], theirs["primitive_normals"][both][same], atol=1e-4)
    np.testing.assert_allclose(ours["primitive_uvs"][both][same], theirs["primitive_uvs"][both][same], atol=1e-3)
    # Shadow rays start from each side's own hit points.
    assert (ours["shadowed"] != theirs["shadowed"]).sum() <= 0.002 * both.sum()
