"""Scale out on a Dask cluster (``dask.distributed``): frames and tiles of
renders, ray batches and viewsheds as tasks, with the same answers as one
machine.

Every function takes a :class:`distributed.Client` (a ``LocalCluster`` on a
laptop, ``dask-jobqueue`` on Slurm/PBS/LSF, ``dask-kubernetes`` on
Kubernetes) and splits the work into tasks whose results are merged in a
fixed order, so the output does not depend on which worker ran what, on
the number of workers, or on a worker lost mid-job (Dask reruns its tasks):

- :func:`render`: frames of a camera path (:func:`orbit`) and/or horizontal
  bands of one image, assembled bit for bit equal to :func:`raykit.render`;
- :func:`cast_rays`: a dask array of rays in, dask arrays of hits out,
  equal to :meth:`raykit.RaycastingScene.cast_rays`;
- :func:`viewsheds`: a mask per observer and the count of observers that
  see each cell, equal to :func:`raykit.terrain.viewshed`, written as
  GeoTIFFs with the DEM's georeferencing.

The scene's acceleration structure is built once, on the client, saved
(:meth:`raykit.RaycastingScene.save`) with its mesh to ``workdir``, and
loaded once per worker process (kept in a per-process cache), not rebuilt
per task; so the scene's structure must be one with a saved form (``bvh8``,
the default, or ``bvh4``). ``workdir`` must be readable by every worker: the default, a
temporary folder, suits a ``LocalCluster``; on a cluster pass a shared
file system path.

Each task runs the engine on ``threads`` threads (default 1): Dask's worker
processes and threads supply the parallelism. With one single-threaded
worker per many-core machine, pass that machine's core count.

Progress: ``progress=True`` prints ``label: done/total tasks`` to stderr as
tasks finish; a callable receives ``(done, total)`` instead.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import sys
import tempfile
import threading
import uuid
from collections import OrderedDict
from typing import Any, Callable, Iterable, Sequence, Union

import numpy as np

from . import _raykit
from ._png import write_png
from .files import PATH_TYPES, fspath
from .raycasting import RaycastingScene
from .render import render as render_image
from .terrain import grid, viewshed

Progress = Union[bool, Callable[[int, int], None], None]

# Scenes loaded in this process, most recently used last, and how many
# loads there have been (a worker loads each saved scene once while it
# stays among the last _KEEP).
_SCENES: OrderedDict[tuple[str, int, int], RaycastingScene] = OrderedDict()
_SCENES_LOCK = threading.Lock()
_KEEP = 4
loads = 0


# ---------------------------------------------------------------- scenes


def save_scene(scene, workdir: str | bytes | os.PathLike) -> str:
    """Save ``scene`` (a :class:`raykit.RaycastingScene`, built here if it
    is not yet, or any mesh ``add_triangles`` takes) to ``workdir`` for the
    workers: its structure file (``.rkstruct``) beside an ``.npz`` of its
    geometries. Returns the structure file's path, which :func:`load_scene`
    takes. Files are written to a temporary name and renamed."""
    if not isinstance(scene, RaycastingScene):
        mesh = scene
        scene = RaycastingScene()
        scene.add_triangles(mesh)
    workdir = fspath(workdir, "workdir")
    os.makedirs(workdir, exist_ok=True)
    stem = os.path.join(workdir, f"scene-{uuid.uuid4().hex}")
    path = stem + ".rkstruct"
    scene.save(path)
    arrays: dict[str, Any] = {
        "accel": np.array(scene.accel),
        "test": np.array(scene.test),
        "origin": scene.origin,
    }
    for i, (v, t) in enumerate(zip(scene._vertices, scene._triangles)):
        arrays[f"vertices{i}"] = v
        arrays[f"triangles{i}"] = t
    tmp = stem + ".npz.tmp.npz"
    np.savez(tmp, count=np.array(len(scene._vertices)), **arrays)
    os.replace(tmp, stem + ".npz")
    return path


def load_scene(path: str | bytes | os.PathLike, threads: int = 1) -> RaycastingScene:
    """The scene saved by :func:`save_scene` at ``path``, loaded once per
    process without rebuilding its structure, and kept (the last few
    scenes used, while their files are unchanged)."""
    global loads
    path = fspath(path)
    st = os.stat(path)
    key = (path, st.st_mtime_ns, st.st_size)
    with _SCENES_LOCK:
        scene = _SCENES.get(key)
        if scene is not None:
            _SCENES.move_to_end(key)
            return scene
        with np.load(path[: -len(".rkstruct")] + ".npz") as z:
            # The geometries are stored as the scene keeps them, relative to
            # its origin; moved back, they are stored again bit for bit.
            origin = z["origin"]
            scene = RaycastingScene(nthreads=threads, accel=str(z["accel"]), test=str(z["test"]), origin=origin)
            for i in range(int(z["count"])):
                scene.add_triangles(z[f"vertices{i}"].astype(np.float64) + origin, z[f"triangles{i}"])
        scene.load_structure(path)
        _SCENES[key] = scene
        loads += 1
        while len(_SCENES) > _KEEP:
            _SCENES.popitem(last=False)
        return scene


def _check_visible(client, path: str) -> None:
    """Fail early, naming ``path``, when a worker cannot read it."""
    if not callable(getattr(client, "run", None)):
        raise TypeError(f"client must be a distributed.Client, got {type(client).__name__}")
    seen = client.run(os.path.exists, path)
    blind = sorted(w for w, ok in seen.items() if not ok)
    if blind:
        raise FileNotFoundError(
            f"{path}: not readable on worker(s) {', '.join(blind)}; pass a workdir on a file system every worker shares"
        )


def _wait(client, futures: list, label: str, progress: Progress) -> list:
    """Results of ``futures`` in their order, reporting as tasks finish."""
    from distributed import as_completed

    total = len(futures)
    if progress:
        done = 0
        for _ in as_completed(futures):
            done += 1
            if callable(progress):
                progress(done, total)
            else:
                print(f"{label}: {done}/{total} tasks", file=sys.stderr, flush=True)
    return client.gather(futures)


# ---------------------------------------------------------------- render


def orbit(
    frames: int,
    eye: Sequence[float],
    target: Sequence[float],
    up: Sequence[float] = (0.0, 1.0, 0.0),
    fov: float = 40.0,
) -> list[dict[str, Any]]:
    """A camera path for :func:`render`: ``frames`` cameras turning ``eye``
    about the axis through ``target`` along ``up`` by ``360° · k / frames``
    (counter-clockwise seen from above; frame 0 is ``eye``), each a dict of
    :func:`raykit.render`'s camera arguments. Computed in float64 from the
    frame number alone (Rodrigues' rotation formula)."""
    if frames < 1:
        raise ValueError(f"frames must be at least 1, got {frames}")
    e, c = np.asarray(eye, np.float64), np.asarray(target, np.float64)
    k = np.asarray(up, np.float64)
    if k.shape != (3,) or not np.isfinite(k).all() or not np.linalg.norm(k) > 0.0:
        raise ValueError(f"up must be three finite numbers, not all zero, got {tuple(k.ravel())}")
    k = k / np.linalg.norm(k)
    v = e - c
    path = []
    for i in range(frames):
        a = 2.0 * math.pi * i / frames
        r = v * math.cos(a) + np.cross(k, v) * math.sin(a) + k * np.dot(k, v) * (1.0 - math.cos(a))
        p = e if i == 0 else c + r
        path.append(
            {"eye": tuple(float(x) for x in p), "target": tuple(float(x) for x in c), "up": tuple(float(x) for x in k), "fov": float(fov)}
        )
    return path


def bands(height: int, count: int) -> list[tuple[int, int]]:
    """Horizontal band ``i`` of ``count`` covers rows ``i·height//count``
    up to ``(i+1)·height//count``, as ``raykit render --tile i/count``;
    returns ``(first row, rows)`` per band."""
    if not 1 <= count <= height:
        raise ValueError(f"tiles must be between 1 and the image height {height}, got {count}")
    return [(i * height // count, (i + 1) * height // count - i * height // count) for i in range(count)]


def _render_task(path: str, width: int, height: int, camera: dict, band: tuple[int, int], options: dict) -> np.ndarray:
    scene = load_scene(path, options.get("threads", 1))
    y, rows = band
    return render_image(scene, width, height, window=(0, y, width, rows), **camera, **options)


def frame_path(out: str | bytes | os.PathLike, index: int) -> str:
    """Frame ``index``'s file of an animation written to ``out``:
    ``STEM.NNNN.png`` beside it, as ``raykit render --orbit`` names them."""
    stem, ext = os.path.splitext(fspath(out, "out"))
    return f"{stem}.{index:04d}{ext}"


def render(
    client,
    scene,
    width: int = 800,
    height: int = 600,
    *,
    frames: Sequence[dict[str, Any]] | None = None,
    tiles: int = 1,
    out: str | bytes | os.PathLike | None = None,
    workdir: str | bytes | os.PathLike | None = None,
    threads: int = 1,
    progress: Progress = True,
    **camera_and_options: Any,
) -> list[np.ndarray] | np.ndarray:
    """Render on the cluster: each frame of ``frames`` (camera dicts, as
    :func:`orbit` makes) split into ``tiles`` horizontal bands, one task
    per band of each frame; the bands are assembled in order. Without
    ``frames``, one image with the camera of ``camera_and_options``.

    ``camera_and_options``: :func:`raykit.render`'s keyword arguments
    (``eye``, ``target``, ``up``, ``fov``, ``samples_per_pixel``,
    ``shadows``); a frame's dict overrides them. Each image equals
    ``raykit.render(scene, width, height, **camera, **options)`` bit for bit.

    ``out``: also write PNGs — the image to ``out``, or frame ``k`` to
    :func:`frame_path(out, k) <frame_path>` — atomically. Returns the image
    (``(height, width, 3)`` uint8), or the list of frames with ``frames``.
    """
    if out is not None:
        # Checked before any task runs, as the command line checks it.
        folder = os.path.dirname(fspath(out, "out")) or "."
        if not os.path.isdir(folder):
            raise FileNotFoundError(f"cannot write {fspath(out, 'out')}: the folder {folder} does not exist")
    if "window" in camera_and_options:
        raise ValueError("window: the cluster renders whole images in bands (tiles=); crop the result instead")
    own_dir = workdir is None
    workdir = tempfile.mkdtemp(prefix="raykit-dask-") if own_dir else fspath(workdir, "workdir")
    try:
        path = save_scene(scene, workdir)
        _check_visible(client, path)
        base = dict(camera_and_options)
        options = {"threads": int(threads)}
        for key in ("samples_per_pixel", "shadows"):
            if key in base:
                options[key] = base.pop(key)
        cameras = [dict(base, **f) for f in frames] if frames is not None else [base]
        split = bands(int(height), int(tiles))
        futures = [
            client.submit(_render_task, path, int(width), int(height), cam, band, options, pure=False)
            for cam in cameras
            for band in split
        ]
        parts = _wait(client, futures, "render", progress)
        images = [np.concatenate(parts[i * len(split) : (i + 1) * len(split)], axis=0) for i in range(len(cameras))]
    finally:
        if own_dir:
            shutil.rmtree(workdir, ignore_errors=True)
    if out is not None:
        for i, img in enumerate(images):
            write_png(out if frames is None else frame_path(out, i), img)
    return images if frames is not None else images[0]


# ---------------------------------------------------------------- rays

_HIT_FIELDS = (
    ("t_hit", np.float32, ()),
    ("geometry_ids", np.uint32, ()),
    ("primitive_ids", np.uint32, ()),
    ("primitive_uvs", np.float32, (2,)),
    ("primitive_normals", np.float32, (3,)),
)


def _cast_block(path: str, rays: np.ndarray, threads: int) -> dict[str, np.ndarray]:
    hits = load_scene(path, threads).cast_rays(rays, nthreads=threads)
    return {name: np.asarray(hits[name]) for name, _, _ in _HIT_FIELDS}


def _hit_field(hits: dict[str, np.ndarray], name: str) -> np.ndarray:
    return hits[name]


def cast_rays(
    client,
    scene,
    rays,
    *,
    workdir: str | bytes | os.PathLike | None = None,
    threads: int = 1,
) -> dict[str, Any]:
    """First hits of a dask array of rays, ``(n, 6)`` rows
    ``[ox, oy, oz, dx, dy, dz]`` chunked along rows, as a dict of dask
    arrays chunked alike. A numpy array (or anything else
    ``dask.array.asarray`` takes) is split by ``dask.array.asarray`` into
    dask's automatic chunks (of ``array.chunk-size`` bytes, 128 MiB unless
    configured: one chunk up to about 5.6 million float32 rays); pass a
    dask array (``dask.array.from_array(rays, chunks=...)``) to choose the
    chunks, and with them the tasks. The arrays: ``t_hit`` ``(n,)``
    float32, ``geometry_ids`` and ``primitive_ids`` ``(n,)`` uint32,
    ``primitive_uvs`` ``(n, 2)`` and ``primitive_normals`` ``(n, 3)``
    float32, equal to
    :meth:`raykit.RaycastingScene.cast_rays` on the whole array.

    ``scene``: a :class:`raykit.RaycastingScene` whose structure has a
    saved form (``bvh8``, the default, or ``bvh4``) or a mesh; its structure is
    built once here, saved to ``workdir`` (default: a new temporary folder,
    left in place because the arrays are lazy) and loaded once per worker.
    One task per chunk casts its rays; the five arrays of a chunk come from
    the same task, so compute them together
    (``dask.compute(*hits.values())``) or persist them.
    """
    import dask
    import dask.array as da

    if not isinstance(rays, da.Array):
        rays = da.asarray(rays)
    if rays.ndim != 2 or rays.shape[1] != 6:
        raise ValueError(f"rays must have shape (n, 6), got {rays.shape}")
    own_dir = workdir is None
    workdir = tempfile.mkdtemp(prefix="raykit-dask-") if own_dir else fspath(workdir, "workdir")
    try:
        path = save_scene(scene, workdir)
        _check_visible(client, path)
    except BaseException:
        if own_dir:
            shutil.rmtree(workdir, ignore_errors=True)
        raise
    rays = rays.rechunk({1: 6})
    blocks = rays.to_delayed().ravel()
    cast = dask.delayed(_cast_block, pure=True)
    results = [cast(path, b, int(threads)) for b in blocks]
    field = dask.delayed(_hit_field, pure=True)
    out: dict[str, Any] = {}
    for name, dtype, tail in _HIT_FIELDS:
        parts = [
            da.from_delayed(field(r, name), shape=(n,) + tail, dtype=dtype)
            for r, n in zip(results, rays.chunks[0])
        ]
        out[name] = da.concatenate(parts, axis=0)
    return out


# ---------------------------------------------------------------- terrain

_DEMS: dict[tuple[str, int, int], tuple] = {}


def _dem_grid(dem) -> tuple:
    """The grid of a DEM path, loaded once per process, or the
    ``(heights, transform, geographic)`` tuple itself."""
    if isinstance(dem, str):
        st = os.stat(dem)
        key = (dem, st.st_mtime_ns, st.st_size)
        with _SCENES_LOCK:
            if key not in _DEMS:
                _DEMS[key] = grid(dem)
            return _DEMS[key]
    return dem


def _viewshed_task(dem, observers: list, height: float, elevation: bool, threads: int, mask_paths, like):
    h, t, geo = _dem_grid(dem)
    count = np.zeros(h.shape, np.uint32)
    masks = []
    for i, obs in enumerate(observers):
        m = viewshed(h, t, observer=obs, observer_height=height, observer_elevation=elevation, geographic=geo, threads=threads)
        count += m == 1
        if mask_paths is not None:
            _raykit.write_geotiff(mask_paths[i], m, t, geo, 255.0, like)
        else:
            masks.append(m)
    return count, masks


def _check_observers(h, t, geo, observers, height: float, elevation: bool) -> None:
    """Refuse, before any task runs, the first observer that
    :func:`raykit.terrain.viewshed` would refuse, with its message and
    index in ``observers``."""
    lights = [(x, y, height) for x, y in observers]
    _raykit.check_lights(h, t, lights, geo, elevation, observer=True)


#: The files a run of :func:`viewsheds` writes to ``out``.
_VIEWSHED_FILE = re.compile(r"^(count|mask_[0-9]{5,})\.tif$")


def _replace_outputs(staging: str, out: str) -> None:
    """Move every file of ``staging`` into ``out`` (replacing those of the
    same name), then remove the ``mask_NNNNN.tif`` files of earlier runs
    that this run did not write."""
    written = set(os.listdir(staging))
    for name in sorted(written):
        os.replace(os.path.join(staging, name), os.path.join(out, name))
    for name in os.listdir(out):
        if _VIEWSHED_FILE.match(name) and name not in written:
            os.remove(os.path.join(out, name))


def viewsheds(
    client,
    dem,
    observers: Iterable[Sequence[float]],
    *,
    out: str | bytes | os.PathLike | None = None,
    transform=None,
    geographic: bool = False,
    nodata=None,
    observer_height: float = 1.75,
    observer_elevation: bool = False,
    batch: int = 1,
    return_masks: bool = True,
    threads: int = 1,
    progress: Progress = True,
) -> dict[str, Any]:
    """Viewsheds of many observers on the cluster, ``batch`` observers per
    task: each mask equals :func:`raykit.terrain.viewshed` (1 visible,
    0 hidden, 255 no data) and ``count`` is, per cell, the number of
    observers that see it (the cumulative viewshed), summed in integers so
    the order of tasks does not matter.

    ``dem``: a DEM file (each worker reads it once) or a ``(rows, cols)``
    height array with ``transform`` (sent to the workers once).
    ``observers``: ``(x, y)`` map positions, as for ``viewshed``.

    ``out``: a folder (made if missing) to write ``count.tif`` (float32;
    -1 where the DEM has no data) and ``mask_NNNNN.tif`` per observer
    (uint8, nodata 255), as GeoTIFFs with the DEM's georeferencing (a DEM
    file's coordinate system too). The workers write them to a temporary
    folder inside ``out``, and they are moved into place only when every
    task has succeeded: then ``count.tif`` and the masks of this run
    replace those of earlier runs, and the ``mask_NNNNN.tif`` of an
    earlier run with more observers are removed, so that ``out`` holds
    one run's files; other files in ``out`` are left alone. When the run
    fails, ``out`` is left as it was. Returns ``{"count": (rows, cols)
    uint32, "masks": (observers, rows, cols) uint8 or None}`` (masks only
    with ``return_masks`` and without ``out``).

    Every observer is checked here before any task runs: one that
    :func:`raykit.terrain.viewshed` refuses (outside the DEM's grid
    points, or over no data without ``observer_elevation``) raises its
    ``ValueError``, naming its index in ``observers``.
    """
    obs = []
    for i, o in enumerate(observers):
        try:
            xy = tuple(float(c) for c in o)
        except (TypeError, ValueError):
            raise ValueError(f"observers[{i}] must be (x, y), 2 numbers; got {o!r}") from None
        if len(xy) != 2:
            raise ValueError(f"observers[{i}] must be (x, y), 2 numbers; got {len(xy)}")
        obs.append(xy)
    if not obs:
        raise ValueError("viewsheds needs at least one observer")
    if batch < 1:
        raise ValueError(f"batch must be at least 1, got {batch}")
    like = None
    if isinstance(dem, PATH_TYPES):
        if transform is not None:
            raise ValueError("a DEM file carries its own transform; pass transform only with an array")
        like = os.path.abspath(fspath(dem, "dem"))
        _check_visible(client, like)
        h, t, geo = grid(like)
        source: Any = like
    else:
        h, t, geo = grid(dem, transform, geographic, nodata)
    _check_observers(h, t, geo, obs, float(observer_height), bool(observer_elevation))
    if not isinstance(dem, PATH_TYPES):
        source = client.scatter([(h, t, geo)], broadcast=True)[0]
    staging = None
    if out is not None:
        out = os.path.abspath(fspath(out, "out"))
        os.makedirs(out, exist_ok=True)
        staging = tempfile.mkdtemp(prefix=".viewsheds-", dir=out)
    try:
        groups = [list(range(i, min(i + batch, len(obs)))) for i in range(0, len(obs), batch)]
        futures = []
        for g in groups:
            paths = None if staging is None else [os.path.join(staging, f"mask_{i:05d}.tif") for i in g]
            futures.append(
                client.submit(
                    _viewshed_task,
                    source,
                    [obs[i] for i in g],
                    float(observer_height),
                    bool(observer_elevation),
                    int(threads),
                    paths,
                    like,
                    pure=False,
                )
            )
        results = _wait(client, futures, "viewsheds", progress)
        count = np.zeros(h.shape, np.uint32)
        for c, _ in results:
            count += c
        masks = None
        if out is None and return_masks:
            masks = np.stack([m for _, ms in results for m in ms])
        if staging is not None:
            counts = np.where(np.isnan(h), np.float32(-1.0), count.astype(np.float32))
            _raykit.write_geotiff(os.path.join(staging, "count.tif"), counts, t, geo, -1.0, like)
            _replace_outputs(staging, out)
    finally:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
    return {"count": count, "masks": masks}


__all__ = [
    "bands",
    "cast_rays",
    "frame_path",
    "load_scene",
    "orbit",
    "render",
    "save_scene",
    "viewsheds",
]
