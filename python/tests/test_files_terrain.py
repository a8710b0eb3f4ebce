"""load_mesh against trimesh's loaders; terrain shadows, viewsheds and casts
against GDAL's reading of the same GeoTIFF (rasterio), the other exact
method, and a BVH over the same surface as triangles."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest
import rasterio
import trimesh
from rasterio.transform import Affine

import raykit
import raykit.terrain
from conftest import raykit_cli


def test_load_mesh_matches_trimesh(data):
    for name in ("bunny_3674.obj", "teapot_992.obj", "bearing.stl"):
        v, f, parts = raykit.load_mesh(data / "meshes" / name)
        assert v.dtype == np.float32 and f.dtype == np.uint32 and parts.dtype == np.uint32
        assert v.shape[1] == 3 and f.shape[1] == 3 and parts.shape == (len(f),)
        ref = trimesh.load(data / "meshes" / name, process=False, force="mesh")
        assert len(f) == len(ref.faces)
        # Same triangles corner by corner (STL loaders may share vertices differently).
        np.testing.assert_allclose(v[f], ref.vertices[ref.faces], rtol=1e-6, atol=1e-6 * ref.scale)
    v, f, parts = raykit.load_mesh(str(data / "meshes" / "2CylinderEngine.glb"))
    assert parts.max() > 10  # one part per glTF node
    # A bytes path, as open() takes it, gives the same mesh.
    vb, fb, pb = raykit.load_mesh(os.fsencode(data / "meshes" / "2CylinderEngine.glb"))
    assert np.array_equal(vb, v) and np.array_equal(fb, f) and np.array_equal(pb, parts)


def test_compressed_gltf_loads_as_the_mesh_it_was_made_from(data):
    """The bunny as Draco and meshopt GLBs (written by glTF-Transform and
    gltfpack; crates/io/tests/data) loads with the OBJ's triangles: the same
    count, and each triangle's surface within the encoders' quantization of
    the OBJ's surface (its corners' distances to the OBJ, by Open3D)."""
    import open3d as o3d

    obj = trimesh.load(data / "meshes" / "bunny_3674.obj", process=False, force="mesh")
    surface = o3d.t.geometry.RaycastingScene()
    surface.add_triangles(
        o3d.core.Tensor(np.asarray(obj.vertices, np.float32)), o3d.core.Tensor(np.asarray(obj.faces, np.uint32))
    )
    fixtures = Path(__file__).resolve().parents[2] / "crates" / "io" / "tests" / "data"
    step = obj.scale / 2**14
    for name in ("bunny_draco.glb", "bunny_meshopt.glb", "bunny_meshopt_exp.glb"):
        v, f, _ = raykit.load_mesh(fixtures / name)
        assert len(f) == len(obj.faces), name
        distance = surface.compute_distance(o3d.core.Tensor(v.astype(np.float32))).numpy()
        assert distance.max() <= step, f"{name}: {distance.max()} against {step}"


def test_load_mesh_errors_name_the_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="missing.obj"):
        raykit.load_mesh(tmp_path / "missing.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 abc\nf 1 2 3\n")
    with pytest.raises(ValueError, match=r"bad\.obj:3: "):
        raykit.load_mesh(bad)
    with pytest.raises(ValueError, match="unknown mesh file extension"):
        raykit.load_mesh(tmp_path / "x.xyz")
    truncated = tmp_path / "t.ply"
    truncated.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nend_header\n\x00")
    with pytest.raises(ValueError, match=r"t\.ply"):
        raykit.load_mesh(truncated)


def at(transform, col, row):
    """Map coordinates of pixel position (col, row) by rasterio's transform."""
    a, b, c, d, e, f = tuple(transform)[:6]
    return a * col + b * row + c, d * col + e * row + f


def read_with_gdal(path):
    with rasterio.open(path) as src:
        return src.read(1).astype(np.float32), src.transform, src.nodata


def test_shadow_of_a_geotiff_equals_shadow_of_gdals_arrays(data):
    path = data / "terrain" / "lidar_dem_400.tif"
    heights, transform, nodata = read_with_gdal(path)
    from_file = raykit.terrain.shadow(path, sun=(135, 8))
    from_arrays = raykit.terrain.shadow(heights, transform, sun=(135, 8), nodata=nodata)
    assert from_file.shape == heights.shape and from_file.dtype == np.uint8
    np.testing.assert_array_equal(from_file, from_arrays)
    assert 0.05 < (from_file == 0).mean() < 0.95, (from_file == 0).mean()
    # The two exact algorithms give identical masks.
    brute = raykit.terrain.shadow(heights, transform, sun=(135, 8), method="brute", threads=1)
    np.testing.assert_array_equal(brute, from_arrays)
    # A point light, and the viewshed of an observer at the same place.
    x, y = at(transform, 200.5, 150.5)
    lit = raykit.terrain.shadow(path, light=(x, y, 30.0))
    np.testing.assert_array_equal(raykit.terrain.viewshed(path, observer=(x, y), observer_height=30.0), lit)
    assert lit[150, 200] == 1


def test_an_esri_ascii_grid_shadows_as_its_arrays(data, tmp_path):
    """The lidar DEM written here by numpy as an Esri ASCII grid (every
    float32 in nine digits, the centre keywords, no data as in the GeoTIFF)
    shadows exactly as the arrays GDAL read from the GeoTIFF."""
    heights, transform, nodata = read_with_gdal(data / "terrain" / "lidar_dem_400.tif")
    rows, cols = heights.shape
    cell = transform.a
    asc = tmp_path / "lidar.asc"
    with open(asc, "w") as f:
        f.write(f"ncols {cols}\nnrows {rows}\n")
        f.write(f"xllcenter {transform.c + cell / 2!r}\nyllcenter {transform.f - rows * cell + cell / 2!r}\n")
        f.write(f"cellsize {cell!r}\nNODATA_value {nodata:.9g}\n")
        np.savetxt(f, heights, fmt="%.9g")
    from_file = raykit.terrain.shadow(asc, sun=(135, 8))
    from_arrays = raykit.terrain.shadow(heights, transform, sun=(135, 8), nodata=nodata)
    np.testing.assert_array_equal(from_file, from_arrays)
    assert 0.05 < (from_file == 0).mean() < 0.95
    # A point light places the grid: the corner from the centre keywords.
    light = (*at(transform, 200.5, 150.5), 30.0)
    np.testing.assert_array_equal(
        raykit.terrain.shadow(asc, light=light),
        raykit.terrain.shadow(heights, transform, light=light, nodata=nodata),
    )


def test_shadow_agrees_with_rays_on_the_same_triangles():
    rng = np.random.default_rng(3)
    rows, cols = 48, 64
    heights = np.cumsum(np.cumsum(rng.normal(size=(rows, cols)), axis=0), axis=1).astype(np.float32)
    transform = Affine(2.0, 0, 1000.0, 0, -3.0, 5000.0)
    mask = raykit.terrain.shadow(heights, transform, sun=(250, 25))
    # The declared surface as a mesh: grid point (c, r) at map (c·a + c0 + a/2, ...).
    c, r = np.meshgrid(np.arange(cols), np.arange(rows))
    x, y = at(transform, c + 0.5, r + 0.5)
    v = np.stack([x, y, heights], axis=-1).reshape(-1, 3)
    i = (r * cols + c)[:-1, :-1].reshape(-1)
    upper = np.stack([i, i + 1, i + cols + 1], axis=1)
    lower = np.stack([i, i + cols + 1, i + cols], axis=1)
    scene = raykit.RaycastingScene()
    scene.add_triangles(v.astype(np.float64), np.concatenate([upper, lower]))
    az, el = np.radians(250), np.radians(25)
    d = np.array([np.sin(az) * np.cos(el), np.cos(az) * np.cos(el), np.sin(el)])
    rays = np.concatenate([v, np.broadcast_to(d, v.shape)], axis=1)
    occluded = scene.test_occlusions(rays, tnear=1e-3).reshape(rows, cols)
    # A segment that leaves its point into the ground is in shadow, though it
    # may pass under the mesh to the border and meet nothing: 0.2 m along it
    # (still inside the triangle it leaves through, which this sun enters at
    # the corner (1, 0) of the cell to the west, and clear of its edges'
    # tolerance bands) it is then below the surface, which a ray straight up
    # shows.
    under = v + 0.2 * d
    up = np.concatenate([under, np.broadcast_to([0.0, 0.0, 1.0], v.shape)], axis=1)
    occluded |= scene.test_occlusions(up).reshape(rows, cols)
    differ = (occluded == (mask == 1)).sum()
    # Only grazing segments, where f32 rounding decides, may differ.
    assert differ <= 0.003 * mask.size, differ


def test_no_data_is_255_exactly_where_the_heights_are_nan():
    # A grid of several parallel chunks, no-data scattered, a point light
    # and the sun: the cells written 255 are the NaN heights, no others.
    rng = np.random.default_rng(5)
    h = rng.uniform(0.0, 30.0, (301, 257)).astype(np.float32)
    h[rng.random(h.shape) < 0.03] = np.nan
    for kw in (dict(light=(128.0, -150.0, 20.0)), dict(sun=(135.0, 25.0))):
        mask = raykit.terrain.shadow(h, (1, 0, 0, 0, -1, 0), **kw)
        np.testing.assert_array_equal(mask == 255, np.isnan(h))
        assert set(np.unique(mask[~np.isnan(h)])) <= {0, 1}
        # The same grid as rasterio's read(masked=True) gives it: the holes
        # filled with a height of 32767 and masked, answer as the NaNs.
        held = np.ma.masked_array(np.where(np.isnan(h), np.float32(32767), h), mask=np.isnan(h))
        np.testing.assert_array_equal(raykit.terrain.shadow(held, (1, 0, 0, 0, -1, 0), **kw), mask)


def test_a_light_over_no_data_needs_its_elevation():
    # Pixels of 1 m from (0, 0): grid point (row r, col c) lies at (c + ½, -r - ½).
    h = np.arange(16, dtype=np.float32).reshape(4, 4)
    h[1, 1] = np.nan
    for call in (
        lambda: raykit.terrain.shadow(h, light=(1.0, -1.0, 2.0)),
        lambda: raykit.terrain.shadow(h, light=(1.5, -1.5, 2.0)),
        lambda: raykit.terrain.viewshed(h, observer=(1.0, -1.5)),
    ):
        with pytest.raises(ValueError, match="no height at row 1, column 1"):
            call()
    with pytest.raises(ValueError, match=r"observer \(1, -1.5, 1.75\).*observer_elevation=True"):
        raykit.terrain.viewshed(h, observer=(1.0, -1.5))
    # Where the ground is known, and with an absolute elevation, the light
    # stands where it was put: the same mask as the brute-force method's.
    for kw in (dict(light=(2.5, -0.5, 2.0)), dict(light=(1.0, -1.0, 30.0), light_elevation=True)):
        fast = raykit.terrain.shadow(h, **kw)
        np.testing.assert_array_equal(fast, raykit.terrain.shadow(h, method="brute", **kw))
        assert fast[1, 1] == 255
    with pytest.raises(ValueError, match=r"light must be \(x, y, h\), 3 numbers; got 4"):
        raykit.terrain.shadow(h, light=(1, 2, 3, 4))
    with pytest.raises(ValueError, match=r"sun must be \(azimuth, elevation\), 2 numbers; got 1"):
        raykit.terrain.shadow(h, sun=(1,))
    # Cameras name the argument that is not three numbers.
    for kw, name in (
        (dict(eye=(1, -1)), "eye"),
        (dict(eye=(1, -1, 9), target=(1, -2)), "target"),
        (dict(eye="abc", target=(1, -1, 0)), "eye"),
    ):
        with pytest.raises(ValueError, match=rf"^{name} must be \(x, y, z\), 3 numbers; got"):
            raykit.terrain.render(h, width=8, height=6, **kw)
        with pytest.raises(ValueError, match=rf"^{name} must be \(x, y, z\), 3 numbers; got"):
            raykit.terrain.cast(h, width=8, height=6, **{"target": (1, -1, 0), **kw})
    with pytest.raises(ValueError, match=r"^target must be \(x, y, z\), 3 numbers; got None"):
        raykit.terrain.cast(h, eye=(1, -1, 9), target=None)


def test_render_checks_its_light_and_frames_grids_with_holes(tmp_path):
    h = np.arange(16, dtype=np.float32).reshape(4, 4)
    for kw in (dict(sun=(float("nan"), 20)), dict(sun=(135, 200)), dict(light=(1, -1, float("nan")))):
        for shadows in (True, False):
            with pytest.raises(ValueError, match="sun|light"):
                raykit.terrain.render(h, shadows=shadows, width=8, height=6, **kw)
    # The default camera over a grid whose centre has no data: the filled
    # surface's view, the same picture as the grid filled by hand.
    holed = h.copy()
    holed[1:3, 1:3] = np.nan
    filled = np.where(np.isnan(holed), np.nanmin(holed), holed)
    a = raykit.terrain.render(holed, width=16, height=12, shadows=False)
    b = raykit.terrain.render(filled, width=16, height=12, shadows=False)
    np.testing.assert_array_equal(a, b)
    # A DEM file's own faults name the file.
    path = tmp_path / "tiny.asc"
    path.write_text("ncols 3\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n")
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}: a height field needs at least 2 rows"):
        raykit.terrain.shadow(str(path), sun=(135, 20))


def test_numbers_in_terrain_errors_stay_short():
    h = np.zeros((4, 4), np.float32)
    for kw in (dict(transform=(1e300, 0, 0, 0, -1, 0)), dict(light=(1e300, -1, 2))):
        light = kw.pop("light", (1, -1, 2))
        with pytest.raises(ValueError, match="1e300") as e:
            raykit.terrain.shadow(h, light=light, **kw)
        assert len(str(e.value)) < 300, str(e.value)


def test_transforms_and_bad_grids():
    h = np.zeros((5, 6), np.float32)
    h[2, 3] = 10.0
    h[0, 0] = np.nan
    base = raykit.terrain.shadow(h, (1, 0, 0, 0, -1, 0), sun=(90, 30))
    assert base[0, 0] == 255 and base[2, 3] == 1
    np.testing.assert_array_equal(raykit.terrain.shadow(h, Affine.scale(1, -1), sun=(90, 30)), base)
    np.testing.assert_array_equal(raykit.terrain.shadow(h.astype(np.float64), sun=(90, 30)), base)
    with pytest.raises(ValueError, match="rotated or sheared"):
        raykit.terrain.shadow(h, (1, 0.1, 0, 0, -1, 0), sun=(90, 30))
    # The same cells stored south-up (rows reversed, e > 0) come back north-up.
    np.testing.assert_array_equal(raykit.terrain.shadow(h[::-1], (1, 0, 0, 0, 1, -5), sun=(90, 30)), base)
    for degenerate in ((1, 0, 0, 0, 0, 0), (0, 0, 0, 0, -1, 0), (1, 0, 0, 0, np.inf, 0)):
        with pytest.raises(ValueError, match=r"^transform \((1|0), 0, 0, 0, (0|-1|inf), 0\): expected a north-up raster"):
            raykit.terrain.shadow(h, degenerate, sun=(90, 30))
        with pytest.raises(ValueError, match=r"^transform .*: expected a north-up raster"):
            raykit.terrain.render(h, degenerate, width=8, height=6)
    with pytest.raises(ValueError, match="exactly one of sun, light"):
        raykit.terrain.shadow(h)
    with pytest.raises(ValueError, match="elevation must be between 0 and 90"):
        raykit.terrain.shadow(h, sun=(90, 95))
    # A huge number is echoed in exponent form, not as 309 digits.
    with pytest.raises(ValueError, match=r"between 0 and 90 degrees, got 1e\+?308$"):
        raykit.terrain.shadow(h, sun=(90, 1e308))
    with pytest.raises(ValueError, match="azimuth must be a finite"):
        raykit.terrain.shadow(h, sun=(np.nan, 20))
    for height in (np.nan, np.inf):
        with pytest.raises(ValueError, match="height must be a finite"):
            raykit.terrain.shadow(h, light=(2, -2, height))
        with pytest.raises(ValueError, match="height must be a finite"):
            raykit.terrain.viewshed(h, observer=(2, -2), observer_height=height, observer_elevation=True)
    with pytest.raises(ValueError, match="outside -90 to 90"):
        raykit.terrain.shadow(h, (1, 0, 1000, 0, -1, 2000), sun=(135, 20), geographic=True)
    with pytest.raises(ValueError, match="lies outside the DEM"):
        raykit.terrain.shadow(h, light=(100, 100, 5))
    with pytest.raises(ValueError, match="at least 2 rows and 2 columns"):
        raykit.terrain.shadow(h[:1], sun=(0, 10))
    with pytest.raises(ValueError, match=r"shape \(rows, cols\)"):
        raykit.terrain.shadow(h[0], sun=(0, 10))
    with pytest.raises(ValueError, match="no valid height"):
        raykit.terrain.shadow(np.full((3, 3), np.nan), sun=(0, 10))
    with pytest.raises(FileNotFoundError, match="nowhere.tif"):
        raykit.terrain.shadow("nowhere.tif", sun=(0, 10))
    with pytest.raises(ValueError, match="own transform"):
        raykit.terrain.shadow("nowhere.tif", (1, 0, 0, 0, -1, 0), sun=(0, 10))


def test_casters_agree_and_match_a_bvh(data):
    heights, transform, nodata = read_with_gdal(data / "terrain" / "lidar_dem_400.tif")
    x0, y0 = at(transform, 20, 380)
    x1, y1 = at(transform, 200, 200)
    eye, target = (x0, y0, float(np.nanmax(heights)) + 40.0), (x1, y1, float(np.nanmean(heights)))
    casts = [
        raykit.terrain.cast(heights, transform, eye=eye, target=target, width=64, height=40, caster=c)
        for c in ("march", "maxmip", "boxes")
    ]
    for other in casts[1:]:
        np.testing.assert_array_equal(other["t"], casts[0]["t"])
        np.testing.assert_array_equal(other["col"], casts[0]["col"])
    t = casts[0]["t"]
    # The same surface as triangles in world metres, through the BVH.
    rows, cols = heights.shape
    sx, sy = casts[0]["cell_size"]
    c, r = np.meshgrid(np.arange(cols), np.arange(rows))
    v = np.stack([c * sx, -r * sy, heights], axis=-1).reshape(-1, 3)
    i = (r * cols + c)[:-1, :-1].reshape(-1)
    tris = np.concatenate([np.stack([i, i + 1, i + cols + 1], 1), np.stack([i, i + cols + 1, i + cols], 1)])
    scene = raykit.RaycastingScene()
    scene.add_triangles(v.astype(np.float64), tris)
    d = casts[0]["directions"]
    rays = np.concatenate([np.broadcast_to(casts[0]["eye"], d.shape), d], axis=-1)
    t_bvh = scene.cast_rays(rays)["t_hit"]
    assert (np.isfinite(t_bvh) == np.isfinite(t)).all()
    np.testing.assert_allclose(t_bvh[np.isfinite(t)], t[np.isfinite(t)], rtol=1e-4)
    assert np.isfinite(t).mean() > 0.5 and np.isinf(t[0]).any()  # terrain and sky
    image = raykit.terrain.render(heights, transform, eye=eye, target=target, width=64, height=40)
    assert image.shape == (40, 64, 3) and image.dtype == np.uint8
    sky = np.isinf(t)
    assert image[sky].std(axis=0).max() < image[~sky].std(axis=0).max()
    default = raykit.terrain.render(data / "terrain" / "lidar_dem_400.tif", width=32, height=18, sun=(300, 20))
    assert default.shape == (18, 32, 3)


def test_a_dem_path_may_be_bytes(data):
    path = data / "terrain" / "lidar_dem_400.tif"
    heights, transform, nodata = read_with_gdal(path)
    ref = raykit.terrain.shadow(heights, transform, sun=(135, 8), nodata=nodata)
    np.testing.assert_array_equal(raykit.terrain.shadow(os.fsencode(path), sun=(135, 8)), ref)


def test_infinite_heights_and_degenerate_transforms_are_refused():
    h = np.zeros((5, 6), np.float32)
    h[2, 3] = 10.0
    base = raykit.terrain.shadow(h, sun=(90, 30))
    assert base[2, 3] == 1 and base[2, 2] == 0  # the hill's western foot is in its shadow
    eye, target = (-3.0, 3.0, 20.0), (3.0, -2.5, 0.0)
    for bad, shown in ((np.inf, "inf"), (-np.inf, "-inf")):
        z = h.copy()
        z[3, 1] = bad
        with pytest.raises(ValueError, match=f"row 3, column 1: height {shown} is not finite"):
            raykit.terrain.shadow(z, sun=(90, 30))
        with pytest.raises(ValueError, match="row 3, column 1"):
            raykit.terrain.cast(z, eye=eye, target=target, width=8, height=6)
    # float64 heights beyond float32 would become infinite.
    z = h.astype(np.float64)
    z[4, 5] = 1e300
    with pytest.raises(ValueError, match=r"row 4, column 5: height 1e\+300 is not finite \(beyond the float32"):
        raykit.terrain.viewshed(z, observer=(2, -2))
    # A value given as nodata is no data, infinite or not.
    z = h.copy()
    z[0, 0] = np.inf
    assert raykit.terrain.shadow(z, sun=(90, 30), nodata=np.inf)[0, 0] == 255
    # Pixel sizes far below or above any DEM's, or too fine to tell
    # neighbouring pixels apart at the origin.
    for t, why in (
        ((1e-200, 0, 0, 0, -1e-200, 0), "cell size must be between 1e-9 and 1e9 m"),
        ((1e-10, 0, 0, 0, -1e-10, 0), "cell size must be between 1e-9 and 1e9 m"),
        ((1e10, 0, 0, 0, -1e10, 0), "cell size must be between 1e-9 and 1e9 m"),
        ((5e-324, 0, 0, 0, -5e-324, 0), "cell size must be between 1e-9 and 1e9 m"),
        ((1e300, 0, 0, 0, -1e300, 0), "cell size must be between 1e-9 and 1e9 m"),
        ((1e308, 0, 0, 0, -1e308, 0), "grid reaches beyond the largest coordinates"),
        ((1, 0, 1e300, 0, -1, 0), "too small to tell neighbouring pixels apart"),
    ):
        with pytest.raises(ValueError, match=why):
            raykit.terrain.render(h, t, width=8, height=6)
        with pytest.raises(ValueError, match=why):
            raykit.terrain.shadow(h, t, sun=(90, 30))
    for t in ((np.nan, 0, 0, 0, -1, 0), (1, 0, 0, 0, -np.inf, 0), (0, 0, 0, 0, -1, 0)):
        with pytest.raises(ValueError, match="transform"):
            raykit.terrain.cast(h, t, eye=eye, target=target, width=8, height=6)
    # A millimetre grid is accepted and answers as the metre grid scaled.
    np.testing.assert_array_equal(raykit.terrain.shadow(h / 1000, (1e-3, 0, 0, 0, -1e-3, 0), sun=(90, 30)), base)


def test_cast_image_size_is_bounded():
    rng = np.random.default_rng(8)
    h = rng.uniform(0.0, 5.0, (40, 30)).astype(np.float32)
    eye, target = (-5.0, 5.0, 30.0), (15.0, -20.0, 0.0)
    # The largest side accepted works, and the casters agree on it.
    hit = []
    for w, hh in ((2, 8192), (8192, 2)):
        boxes = raykit.terrain.cast(h, eye=eye, target=target, width=w, height=hh)
        march = raykit.terrain.cast(h, eye=eye, target=target, width=w, height=hh, caster="march")
        np.testing.assert_array_equal(boxes["col"], march["col"])
        np.testing.assert_array_equal(boxes["row"], march["row"])
        np.testing.assert_allclose(boxes["t"], march["t"], rtol=1e-9)
        hit.append(np.isfinite(boxes["t"]).mean())
    # A tall image sweeps down across the grid; a wide one meets it only
    # in its middle.
    assert hit[0] > 0.5 and hit[1] > 0
    for w, hh in ((16384, 16384), (8193, 2), (2, 8193)):
        with pytest.raises(ValueError, match="between 1 and 8192"):
            raykit.terrain.cast(h, eye=eye, target=target, width=w, height=hh)
        with pytest.raises(ValueError, match="between 1 and 8192"):
            raykit.terrain.render(h, width=w, height=hh)
    # Negative, huge and fractional sizes are refused by name, not cut or
    # overflowed.
    for w, hh in ((-3, 8), (8, -1), (2**64, 8), (2.9, 8)):
        for call in (raykit.terrain.cast, raykit.terrain.render):
            kw = dict(eye=eye, target=target) if call is raykit.terrain.cast else {}
            with pytest.raises(ValueError, match="width|height"):
                call(h, width=w, height=hh, **kw)


def write_dem(path, heights, transform, crs, nodata=None):
    with rasterio.open(
        path, "w", driver="GTiff", width=heights.shape[1], height=heights.shape[0], count=1,
        dtype="float32", crs=crs, transform=transform, nodata=nodata,
    ) as dst:
        dst.write(heights, 1)


@pytest.mark.filterwarnings("ignore::rasterio.errors.NotGeoreferencedWarning")
@pytest.mark.parametrize("geographic", [False, True])
def test_render_cameras_are_the_command_lines(tmp_path, geographic):
    """``raykit.terrain.render`` without ``eye`` (the default view), and
    with ``eye`` but no ``target`` (looking at the surface at the DEM's
    centre), against ``raykit terrain render`` of the same GeoTIFF:
    within 1/255 per channel. Cells are not square and the rows and
    columns not of one parity, so that centre and extent are tested."""
    import subprocess

    cli = raykit_cli()
    rows, cols = 23, 30
    y, x = np.mgrid[0:rows, 0:cols]
    heights = (40 * np.sin(x / 4.0) * np.cos(y / 5.0) + 3 * x - 2 * y + 300).astype(np.float32)
    nodata = -9999.0
    heights[11:13, 14:16] = nodata  # no data where the centre's height is read
    if geographic:
        transform, crs = Affine(1 / 1200, 0, 11.0, 0, -1 / 3600, 57.5), "EPSG:4326"
    else:
        transform, crs = Affine(2.0, 0, 429_000.0, 0, -3.0, 5_150_000.0), "EPSG:32633"
    dem = tmp_path / "dem.tif"
    write_dem(dem, heights, transform, crs, nodata)
    # An eye south-west of the DEM's middle, above its highest point.
    eye = (transform.c + transform.a * cols * 0.2, transform.f + transform.e * rows * 0.9, float(heights.max()) + 60.0)
    for extra, kw in (([], {}), (["--eye", ",".join(repr(c) for c in eye)], {"eye": eye})):
        png = tmp_path / "cli.png"
        subprocess.run(
            [cli, "terrain", "render", str(dem), "--width", "96", "--height", "54", "--out", str(png), *extra],
            check=True, capture_output=True,
        )
        with rasterio.open(png) as src:
            want = src.read()[:3].transpose(1, 2, 0)
        got = raykit.terrain.render(dem, width=96, height=54, **kw)
        assert got.shape == want.shape
        diff = np.abs(got.astype(int) - want)
        assert diff.max() <= 1, (kw, int((diff > 1).sum()))
        assert len(np.unique(want.reshape(-1, 3), axis=0)) > 50  # a picture of the terrain, not of the sky


@pytest.mark.parametrize("flip", ["south-up", "east-to-west", "both"])
def test_south_up_and_east_to_west_rasters_come_north_up(tmp_path, flip):
    """A GeoTIFF whose rows run south (e > 0) or columns west (a < 0):
    the file path and the array API with rasterio's transform give the
    same north-up answers, those of the grid flipped to north-up by hand."""
    rows, cols = 21, 26
    y, x = np.mgrid[0:rows, 0:cols]
    north_up = (30 * np.sin(x / 3.0) * np.cos(y / 4.0) + x).astype(np.float32)
    north_up[3, 4] = np.nan
    a, c, e, f = 5.0, 600_000.0, -5.0, 4_200_000.0  # the north-up grid's transform
    stored, t = north_up, [a, c, e, f]
    if flip in ("south-up", "both"):
        stored, t = stored[::-1], [t[0], t[1], -t[2], t[3] + t[2] * rows]
    if flip in ("east-to-west", "both"):
        stored, t = stored[:, ::-1], [-t[0], t[1] + t[0] * cols, t[2], t[3]]
    transform = Affine(t[0], 0.0, t[1], 0.0, t[2], t[3])
    path = tmp_path / "flipped.tif"
    write_dem(path, np.ascontiguousarray(stored), transform, "EPSG:32633")
    with rasterio.open(path) as src:
        read = src.read(1)
        assert src.transform == transform
    np.testing.assert_array_equal(read, stored)
    north = Affine(a, 0.0, c, 0.0, e, f)
    observer = (c + a * 17.5, f + e * 6.5)
    light = (c + a * 9.5, f + e * 15.5, 40.0)
    calls = [
        lambda dem, tr: raykit.terrain.viewshed(dem, tr, observer=observer, observer_height=3.0),
        lambda dem, tr: raykit.terrain.shadow(dem, tr, light=light),
        lambda dem, tr: raykit.terrain.shadow(dem, tr, sun=(200.0, 12.0)),
        lambda dem, tr: raykit.terrain.cast(dem, tr, eye=(c - 40.0, f + e * rows + 40.0, 120.0), target=(c + a * cols / 2, f + e * rows / 2, 0.0), width=24, height=16)["t"],
        lambda dem, tr: raykit.terrain.render(dem, tr, width=24, height=16),
    ]
    for k, call in enumerate(calls):
        want = call(north_up, north)
        assert 0 < np.mean(want == 1) < 1 or k >= 3, k  # masks with both lit and shadowed cells
        np.testing.assert_array_equal(call(str(path), None), want, err_msg=str(k))
        np.testing.assert_array_equal(call(read, transform), want, err_msg=str(k))


def _terrain_answers(path):
    heights, transform, _ = read_with_gdal(path)
    big = np.kron(heights, np.ones((2, 2), np.float32))
    return (
        raykit.terrain.shadow(path, sun=(135, 8), threads=1),
        raykit.terrain.shadow(big, transform, sun=(135, 8), threads=1),
        raykit.terrain.render(big, transform, width=32, height=24, threads=1),
    )


def test_terrain_in_a_forked_child_after_the_parent_has_used_every_pool(data):
    # The GeoTIFF reader and the height field's passes over a grid of more
    # than 65,536 cells are parallel; in a fork child they must run on the
    # child's own pools, not wait for the parent's threads.
    import multiprocessing

    path = data / "terrain" / "lidar_dem_400.tif"
    want = _terrain_answers(path)
    assert (want[1] == 1).any() and (want[1] == 0).any()
    with multiprocessing.get_context("fork").Pool(1) as pool:
        got = pool.apply_async(_terrain_answers, (path,)).get(timeout=120)
    for g, w in zip(got, want):
        np.testing.assert_array_equal(g, w)
