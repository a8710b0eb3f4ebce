"""raykit.distributed on a LocalCluster of two worker processes (started
and stopped here): renders, ray casts and viewsheds against the same
calls in this process (bit-identical images, identical hits, masks and
counts), and a job that loses a worker process midway."""

from __future__ import annotations

import os
import signal
import tempfile

import numpy as np
import pytest

import raykit
from conftest import rays_at

distributed = pytest.importorskip("distributed")
da = pytest.importorskip("dask.array")
import dask  # noqa: E402
import rasterio  # noqa: E402
import trimesh  # noqa: E402

from raykit import distributed as rkd  # noqa: E402


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2,
        processes=True,
        threads_per_worker=1,
        dashboard_address=None,
        worker_dashboard_address=None,
    )
    c = distributed.Client(cluster)
    try:
        yield c
    finally:
        c.close()
        cluster.close()


@pytest.fixture(scope="module")
def scene(bunny):
    v, f, _ = bunny
    s = raykit.RaycastingScene()
    s.add_triangles(v, f)
    return s


def camera_of(vertices):
    lo, hi = vertices.min(0).astype(np.float64), vertices.max(0).astype(np.float64)
    centre = (lo + hi) / 2
    return centre + [0.0, 0.3 * (hi - lo)[1], 2.2 * np.linalg.norm(hi - lo)], centre


@pytest.mark.filterwarnings("ignore::rasterio.errors.NotGeoreferencedWarning")
def test_render_bands_and_frames_equal_the_in_process_render(client, scene, bunny, tmp_path):
    eye, target = camera_of(bunny[0])
    frames = rkd.orbit(3, eye, target, fov=30.0)
    w, h = 64, 45
    seen = []
    images = rkd.render(
        client,
        scene,
        w,
        h,
        frames=frames,
        tiles=4,
        samples_per_pixel=2,
        out=tmp_path / "f.png",
        progress=lambda done, total: seen.append((done, total)),
    )
    assert seen[-1] == (12, 12)
    assert len(images) == 3
    for k, (cam, img) in enumerate(zip(frames, images)):
        one = raykit.render(scene, w, h, samples_per_pixel=2, **cam)
        assert img.dtype == np.uint8 and img.shape == (h, w, 3)
        assert np.array_equal(img, one), f"frame {k}"
        # The PNG holds the same pixels (read back by GDAL).
        with rasterio.open(tmp_path / f"f.{k:04d}.png") as src:
            assert np.array_equal(np.moveaxis(src.read(), 0, -1), one)
    assert not np.array_equal(images[0], images[1])
    # One image in bands, from a mesh rather than a scene.
    v, f, _ = bunny
    single = rkd.render(client, trimesh.Trimesh(v, f, process=False), 50, 37, tiles=5, eye=eye, target=target, progress=False)
    assert np.array_equal(single, raykit.render(scene, 50, 37, eye=eye, target=target))
    with pytest.raises(ValueError, match="tiles"):
        rkd.render(client, scene, 10, 4, tiles=5, progress=False)
    # An output folder that does not exist is named before any task runs.
    seen.clear()
    missing = tmp_path / "nowhere" / "f.png"
    with pytest.raises(FileNotFoundError, match="the folder .*nowhere does not exist"):
        rkd.render(client, scene, 10, 4, out=missing, progress=lambda d, t: seen.append(d))
    assert seen == []


def test_numpy_rays_and_refused_arguments(client, scene, bunny, tmp_path):
    # A numpy array is split into dask's automatic chunks (here made small
    # enough to split 2,000 rays), with the in-process answers.
    rays = rays_at(bunny[0], 2_000, seed=8)
    with dask.config.set({"array.chunk-size": "16KiB"}):
        hits = rkd.cast_rays(client, scene, rays)
        auto = da.asarray(rays).chunks[0]
    assert len(auto) > 1 and all(h.chunks[0] == auto for h in hits.values())
    got = dict(zip(hits, dask.compute(*hits.values())))
    for name, value in scene.cast_rays(rays).items():
        assert np.array_equal(got[name], np.asarray(value)), name
    with pytest.raises(TypeError, match="client must be a distributed.Client"):
        rkd.cast_rays(None, scene, rays, workdir=tmp_path)
    # A structure without a saved form is refused by name, and the job's
    # own temporary folder does not stay behind.
    kd = raykit.RaycastingScene(accel="bvh2")
    kd.add_triangles(*bunny[:2])
    folders = set(os.listdir(tempfile.gettempdir()))
    with pytest.raises(ValueError, match="no saved form"):
        rkd.cast_rays(client, kd, rays)
    left = {f for f in set(os.listdir(tempfile.gettempdir())) - folders if f.startswith("raykit-dask-")}
    assert not left, left
    with pytest.raises(ValueError, match="window"):
        rkd.render(client, scene, 32, 24, window=(0, 0, 8, 8), progress=False)
    with pytest.raises(ValueError, match="up must be three finite numbers"):
        rkd.orbit(2, eye=(0, 0, 1), target=(0, 0, 0), up=(0, 0, 0))


def test_cast_rays_equals_the_in_process_cast_and_loads_once_per_worker(client, scene, bunny):
    rays = rays_at(bunny[0], 20_000, seed=5)
    expected = scene.cast_rays(rays)
    darr = da.from_array(rays, chunks=(3_000, 6))
    before = client.run(lambda: rkd.loads)
    hits = rkd.cast_rays(client, scene, darr)
    assert set(hits) == set(expected)
    got = dict(zip(hits, dask.compute(*hits.values())))
    for name, value in expected.items():
        assert got[name].shape == np.asarray(value).shape, name
        assert np.array_equal(got[name], np.asarray(value)), name
    assert np.isfinite(got["t_hit"]).mean() > 0.2
    # Seven chunks, but each worker loaded the saved structure at most once.
    after = client.run(lambda: rkd.loads)
    new = [after[w] - before.get(w, 0) for w in after]
    assert all(n <= 1 for n in new) and sum(new) >= 1, (before, after)


def test_viewsheds_equal_in_process_viewsheds_and_keep_the_georeferencing(client, data, tmp_path):
    dem = data / "terrain" / "lidar_dem_400.tif"
    with rasterio.open(dem) as src:
        t = src.transform
        crs = src.crs
        shape = (src.height, src.width)
    # Observers spread over the DEM, in map coordinates.
    observers = [(t.c + t.a * col, t.f + t.e * row) for col, row in [(50, 60), (200, 200), (330, 90), (120, 310), (380, 380)]]
    result = rkd.viewsheds(client, dem, observers, batch=2, observer_height=10.0, progress=False)
    masks = [raykit.terrain.viewshed(dem, observer=o, observer_height=10.0) for o in observers]
    assert np.array_equal(result["masks"], np.stack(masks))
    expected = np.sum([m == 1 for m in masks], axis=0)
    assert np.array_equal(result["count"], expected)
    assert 0 < expected.mean() < len(observers)
    # Written as GeoTIFFs on the DEM's grid and coordinate system.
    out = tmp_path / "vs"
    rkd.viewsheds(client, dem, observers, out=out, observer_height=10.0, progress=False)
    with rasterio.open(out / "count.tif") as src:
        assert src.crs == crs and src.transform == t and src.shape == shape
        assert np.array_equal(src.read(1), expected.astype(np.float32))
    for i, m in enumerate(masks):
        with rasterio.open(out / f"mask_{i:05d}.tif") as src:
            assert src.crs == crs and src.transform == t and src.nodata == 255
            assert np.array_equal(src.read(1), m)
    # A height array with its transform, sent to the workers once.
    heights = np.add.outer(np.sin(np.arange(30) / 4.0), np.cos(np.arange(40) / 5.0)).astype(np.float32) * 20
    transform = (10.0, 0.0, 1000.0, 0.0, -10.0, 5000.0)
    obs = [(1100.0, 4900.0), (1300.0, 4800.0), (1050.0, 4750.0)]
    r = rkd.viewsheds(client, heights, obs, transform=transform, progress=False)
    ref = [raykit.terrain.viewshed(heights, transform, observer=o) for o in obs]
    assert np.array_equal(r["masks"], np.stack(ref))
    assert np.array_equal(r["count"], np.sum([m == 1 for m in ref], axis=0))


def test_a_job_survives_a_killed_worker(client, scene, bunny):
    client.wait_for_workers(2)
    pids = client.run(os.getpid)
    victim = sorted(pids.values())[0]
    eye, target = camera_of(bunny[0])
    w, h = 80, 48
    killed = []

    def kill_after_two(done, total):
        if done == 2 and not killed:
            os.kill(victim, signal.SIGKILL)
            killed.append(done)

    image = rkd.render(
        client, scene, w, h, tiles=16, samples_per_pixel=8, eye=eye, target=target, progress=kill_after_two
    )
    assert killed, "the job ended before a worker was killed"
    assert np.array_equal(image, raykit.render(scene, w, h, samples_per_pixel=8, eye=eye, target=target))
    # The nanny restarted the killed process.
    client.wait_for_workers(2, timeout=60)
    assert victim not in client.run(os.getpid).values()


def test_frame_path_takes_the_paths_open_takes(tmp_path):
    # Frame k of out is STEM.kkkk.EXT beside it, as raykit render --orbit names it.
    want = os.path.join(str(tmp_path), "out.0003.png")
    for out in (tmp_path / "out.png", str(tmp_path / "out.png"), os.fsencode(tmp_path / "out.png")):
        assert rkd.frame_path(out, 3) == want
    with pytest.raises(TypeError, match="out must be a str, bytes or os.PathLike"):
        rkd.frame_path(3, 3)


def tif_files(folder) -> dict:
    """The GeoTIFFs of ``folder`` by name, with their bytes."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def test_viewsheds_out_holds_one_runs_files(client, tmp_path):
    """``out`` after runs of 3, then 2 observers, and after failed runs
    between them: each success leaves exactly its own count and masks
    (equal to the in-process viewsheds), a failure leaves the folder as it
    was; an observer the viewshed refuses is refused before any task."""
    heights = np.add.outer(np.sin(np.arange(30) / 4.0), np.cos(np.arange(40) / 5.0)).astype(np.float32) * 20
    heights[0, 0] = np.nan
    transform = (10.0, 0.0, 1000.0, 0.0, -10.0, 5000.0)
    out = tmp_path / "vs"
    (out).mkdir()
    (out / "notes.txt").write_text("not the run's")

    def run(observers, **kw):
        rkd.viewsheds(client, heights, observers, transform=transform, out=out, **kw)
        names = {f"mask_{i:05d}.tif" for i in range(len(observers))} | {"count.tif", "notes.txt"}
        assert set(os.listdir(out)) == names
        masks = [raykit.terrain.viewshed(heights, transform, observer=o) for o in observers]
        for i, m in enumerate(masks):
            with rasterio.open(out / f"mask_{i:05d}.tif") as src:
                assert np.array_equal(src.read(1), m)
        with rasterio.open(out / "count.tif") as src:
            count = np.sum([m == 1 for m in masks], axis=0).astype(np.float32)
            assert np.array_equal(src.read(1), np.where(np.isnan(heights), -1.0, count))

    run([(1100.0, 4900.0), (1300.0, 4800.0), (1050.0, 4750.0)], batch=2, progress=False)
    before = tif_files(out)
    # Outside the grid points (x 1005..1395, y 4705..4995), over no data,
    # and below the ground: refused by index before any task.
    for observers, kw, message in (
        ([(1100.0, 4900.0), (1200.0, 4800.0), (1000.0, 4800.0)], {}, r"observers\[2\]: observer: \(1000, 4800\) lies outside the DEM"),
        ([(1100.0, 4900.0), (1005.0, 4995.0)], {}, r"observers\[1\]: .*no data"),
        ([(1100.0, 4900.0)], {"observer_height": -1.0}, r"observers\[0\]: .*>= 0"),
    ):
        seen = []
        with pytest.raises(ValueError, match=message):
            rkd.viewsheds(client, heights, observers, transform=transform, out=out, progress=lambda d, t: seen.append(d), **kw)
        assert seen == []
        assert tif_files(out) == before
    # A run the workers fail (a rotated grid, which the engine refuses):
    # nothing of it reaches out.
    with pytest.raises(ValueError, match="rotated"):
        rkd.viewsheds(client, heights, [(1100.0, 4900.0)], transform=(10.0, 1.0, 1000.0, 0.0, -10.0, 5000.0), out=out, progress=False)
    assert tif_files(out) == before
    run([(1200.0, 4850.0), (1350.0, 4720.0)], progress=False)
