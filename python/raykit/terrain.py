"""Terrain: shadow masks, viewsheds and ray-cast images of height grids
(raykit-terrain).

A height grid is either a path to a DEM file (GeoTIFF, Esri ASCII grid
``.asc``, SRTM ``.hgt``, Terragen ``.ter``, 16-bit PNG, ``.r16``/``.r32``;
its georeferencing is read from the file) or a ``(rows, cols)`` numpy array of heights in
metres, row 0 to the north, with an affine ``transform`` in rasterio's
convention: ``Affine(a, b, c, d, e, f)`` (or any sequence of those six
numbers) maps a pixel corner (col, row) to map coordinates
``x = a·col + b·row + c``, ``y = d·col + e·row + f``. A north-up raster
has ``b = d = 0``, ``a > 0``, ``e < 0``; rotated rasters are refused.

A south-up raster (``e > 0``) or one whose columns run east to west
(``a < 0``), given as a file or as an array with its transform, is
flipped to north-up as it is read (its rows, or columns, reversed and its
transform with them): every result (masks, counts, :func:`cast`'s
``row``/``col``) is on the north-up grid, row 0 to the north and column
0 to the west, so rows (or columns) come reversed relative to the array
given or to rasterio's ``read`` of the file.

Without a transform, pixels are 1 m squares with the top-left corner at
(0, 0). ``geographic=True`` says that map units are degrees of
longitude/latitude (as for SRTM); heights are metres either way. NaN
heights (or those equal to ``nodata``, or masked in a numpy masked array
such as rasterio's ``read(masked=True)`` gives) are no data; infinite ones (or
float64 ones beyond the float32 range) are refused with ``ValueError``, as
are cells smaller than 1e-9 m or larger than 1e9 m.

The surface is raykit's declared one: the grid points joined as two
triangles per cell, split along the cell's north-west to south-east
diagonal, so the answers are exact for it.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from . import _arrays, _raykit
from .files import PATH_TYPES, fspath


def _transform(t) -> tuple[float, float, float, float, float, float]:
    if t is None:
        return (1.0, 0.0, 0.0, 0.0, -1.0, 0.0)
    terms = [float(x) for x in tuple(t)]
    if len(terms) == 9:  # rasterio's Affine iterates over all nine terms
        if terms[6:] != [0.0, 0.0, 1.0]:
            raise ValueError(f"transform: the last row must be (0, 0, 1), got {terms[6:]}")
        terms = terms[:6]
    if len(terms) != 6:
        raise ValueError(f"transform must be rasterio's Affine(a, b, c, d, e, f), got {len(terms)} terms")
    return tuple(terms)


def _naming_the_file(f):
    """``f`` with its ``ValueError``s about a DEM given as a path (a
    rotated transform, too few samples, no valid height…) starting with
    that path, as the loader's own errors do."""

    @functools.wraps(f)
    def named(heights, *args, **kwargs):
        try:
            return f(heights, *args, **kwargs)
        except ValueError as e:
            if isinstance(heights, PATH_TYPES):
                path = fspath(heights, "heights")
                if not str(e).startswith(path):
                    raise ValueError(f"{path}: {e}") from None
            raise

    return named


def _north_up(h: np.ndarray, t) -> tuple[np.ndarray, tuple]:
    """A south-up (``e > 0``) or east-to-west (``a < 0``) grid and its
    transform flipped to north-up, as the DEM loader flips such files; a
    rotated or not finite transform, or a north-up one, as given (the
    engine refuses the first two by name)."""
    a, b, c, d, e, f = t
    if b != 0.0 or d != 0.0 or not all(math.isfinite(x) for x in t):
        return h, t
    if e > 0.0:
        h, f, e = h[::-1], f + e * h.shape[0], -e
    if a < 0.0:
        h, c, a = h[:, ::-1], c + a * h.shape[1], -a
    return h, (a, b, c, d, e, f)


def grid(heights, transform=None, geographic: bool = False, nodata=None):
    """``(heights float32 (rows, cols) with NaN for no data, transform,
    geographic)`` of a DEM path or an array with its transform, north-up
    (see the module's note on south-up rasters)."""
    if isinstance(heights, PATH_TYPES):
        if transform is not None:
            raise ValueError("a DEM file carries its own transform; pass transform only with an array")
        h, t, geo, _ = _raykit.load_dem(fspath(heights, "heights"))
        return h, t, geo
    # A masked array (rasterio's ``read(masked=True)``): its masked cells
    # are no data, whatever value fills them.
    masked = np.ma.getmaskarray(heights) if np.ma.isMaskedArray(heights) else None
    if masked is not None:
        heights = np.ma.getdata(heights)
    with np.errstate(over="ignore"):
        h = _arrays.floats(heights, "heights")
    if h.ndim != 2:
        raise ValueError(f"heights must have shape (rows, cols), got {h.shape}")
    if masked is not None and masked.any():
        h = np.where(masked, np.float32(np.nan), h)
    if nodata is not None:
        h = np.where(h == np.float32(nodata), np.float32(np.nan), h)
    inf = np.isinf(h)
    if inf.any():
        r, c = (int(i) for i in np.argwhere(inf)[0])
        given = _arrays.to_numpy(heights)[r, c]
        beyond = " (beyond the float32 range)" if np.isfinite(given) else ""
        raise ValueError(
            f"heights: row {r}, column {c}: height {given} is not finite{beyond}; "
            "heights must be finite, or NaN for no data"
        )
    h, t = _north_up(h, _transform(transform))
    return np.ascontiguousarray(h, dtype=np.float32), t, bool(geographic)


@_naming_the_file
def shadow(
    heights,
    transform=None,
    *,
    sun=None,
    light=None,
    light_elevation: bool = False,
    method: str = "fast",
    geographic: bool = False,
    nodata=None,
    threads: int = 0,
) -> np.ndarray:
    """Where a light is visible from the ground (a terrain shadow map).

    Exactly one of ``sun=(azimuth, elevation)`` in degrees (azimuth
    clockwise from north) and ``light=(x, y, h)``: a point light at map
    position (x, y), ``h`` metres above the ground there (or at elevation
    ``h`` with ``light_elevation=True``). ``method``: ``"fast"`` (a point
    light over the grid: a horizon sweep outward from the light, with the
    segment test for the points it leaves; the sun: each segment through
    the min/max quadtree) or ``"brute"`` (each segment marched cell by
    cell); both are exact and give identical masks. A grid point is lit
    when its segment to the light neither crosses the surface nor leaves
    either end into the ground (a light with ``h = 0`` sees along slopes,
    not through the hill it stands on).

    Returns ``(rows, cols)`` uint8: 1 lit, 0 in shadow, 255 no data, as
    ``raykit terrain shadow`` writes its GeoTIFF; north-up, rows reversed
    for a south-up raster (see the module's note).
    """
    h, t, geo = grid(heights, transform, geographic, nodata)
    sun = None if sun is None else _sun(sun)
    light = None if light is None else _numbers(light, "light", "(x, y, h)")
    return _raykit.shadow(h, t, geo, sun, light, bool(light_elevation), method, _arrays.threads(threads))


def _sun(sun) -> tuple[float, float]:
    """``sun`` as (azimuth, elevation) degrees, checked as the mask checks it."""
    az, el = _numbers(sun, "sun", "(azimuth, elevation)")
    if not 0.0 <= el <= 90.0:
        raise ValueError(f"sun: the elevation must be between 0 and 90 degrees, got {el}")
    if not math.isfinite(az):
        raise ValueError(f"sun: the azimuth must be a finite number of degrees, got {az}")
    return az, el


def _numbers(given, what: str, form: str) -> tuple[float, ...]:
    """``given`` as a tuple of as many floats as ``form`` names."""
    n = form.count(",") + 1
    try:
        terms = tuple(float(x) for x in given)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be {form}, {n} numbers; got {given!r}") from None
    if len(terms) != n:
        raise ValueError(f"{what} must be {form}, {n} numbers; got {len(terms)}")
    return terms


@_naming_the_file
def viewshed(
    heights,
    transform=None,
    *,
    observer,
    observer_height: float = 1.75,
    observer_elevation: bool = False,
    geographic: bool = False,
    nodata=None,
    threads: int = 0,
) -> np.ndarray:
    """Which grid points an observer at map position ``observer = (x, y)``,
    ``observer_height`` metres above the ground there, sees (as
    gdal_viewshed's ``-ox -oy -oz`` with target height 0): the shadow mask
    of a point light at the observer's eye. Returns ``(rows, cols)`` uint8:
    1 visible, 0 hidden, 255 no data; north-up, rows reversed for a
    south-up raster (see the module's note)."""
    h, t, geo = grid(heights, transform, geographic, nodata)
    x, y = _numbers(observer, "observer", "(x, y)")
    light = (x, y, float(observer_height))
    return _raykit.shadow(
        h, t, geo, None, light, bool(observer_elevation), "fast", _arrays.threads(threads), observer=True
    )


@_naming_the_file
def cast(
    heights,
    transform=None,
    *,
    eye,
    target,
    width: int = 1600,
    height: int = 900,
    fov: float = 50.0,
    caster: str = "boxes",
    tau: float = 16.0,
    geographic: bool = False,
    nodata=None,
    threads: int = 0,
) -> dict:
    """One ray per pixel of a pinhole camera at map position ``eye`` looking
    at ``target`` (x, y in map units, z in metres), cast exactly on the
    surface with ``caster``: ``"boxes"`` (per-frame quadtree boxes with
    LOD ``tau``), ``"maxmip"`` (maximum mipmap, Tevs et al. 2008) or
    ``"march"`` (cell by cell); all three give the same hits. ``width``
    and ``height``: 1 to 8192 pixels.

    Returns a dict of ``t`` ``(height, width)`` float64 (metres from the
    eye, inf on a miss), ``col``/``row`` int64 (the hit cell of the
    north-up grid, -1 on a miss; see the module's note on south-up
    rasters),
    ``steps`` uint32 (cells and nodes visited per ray), ``directions``
    ``(height, width, 3)`` (unit, x east, y north, z up), ``eye`` (world
    metres from grid point (0, 0)) and ``cell_size`` (metres).
    """
    h, t, geo = grid(heights, transform, geographic, nodata)
    eye = list(_numbers(eye, "eye", "(x, y, z)"))
    target = list(_numbers(target, "target", "(x, y, z)"))
    width, height = _arrays.count(width, "width"), _arrays.count(height, "height")
    return _raykit.cast(h, t, eye, target, geo, float(fov), width, height, caster, float(tau), _arrays.threads(threads))


# Shading of `render`: the constants of `raykit terrain render`.
_AMBIENT, _DIFFUSE, _SPECULAR, _SHININESS = 0.22, 0.85, 0.12, 24
_ZENITH = np.array([0.20, 0.38, 0.78])
_HORIZON = np.array([0.72, 0.80, 0.90])
_NADIR = np.array([0.55, 0.60, 0.66])
_RAMP = np.array(
    [
        (0.00, 0.16, 0.40, 0.20),
        (0.15, 0.33, 0.55, 0.27),
        (0.35, 0.63, 0.66, 0.38),
        (0.55, 0.60, 0.47, 0.31),
        (0.72, 0.46, 0.36, 0.28),
        (0.87, 0.62, 0.61, 0.60),
        (1.00, 0.98, 0.98, 0.98),
    ]
)


@_naming_the_file
def render(
    heights,
    transform=None,
    *,
    width: int = 1600,
    height: int = 900,
    fov: float = 50.0,
    eye=None,
    target=None,
    sun=(135.0, 35.0),
    light=None,
    shadows: bool = True,
    caster: str = "boxes",
    tau: float = 16.0,
    geographic: bool = False,
    nodata=None,
    threads: int = 0,
) -> np.ndarray:
    """The terrain seen from ``eye`` towards ``target`` (map x, y; z in
    metres), lit by
    the ``sun=(azimuth, elevation)`` or a point ``light=(x, y, h)`` h metres
    above the ground, with exact shadows: Phong shading of the hit
    triangle's normal times the shadow mask (bilinear over the hit cell's
    corners), a hypsometric colour ramp over the DEM's heights and a sky
    gradient where rays miss. Returns ``(height, width, 3)`` uint8 sRGB.

    The camera is the command line's (``raykit terrain render``): without
    ``eye``, its default view, the eye 3/4 of the way from the DEM's
    centre to its south-west grid point, above the highest point, looking
    towards the centre 20° below the horizontal (``target`` given, it
    looks there instead); with ``eye`` and no ``target``, it looks at the
    surface point at the DEM's centre grid position.
    """
    h, t, geo = grid(heights, transform, geographic, nodata)
    if light is None:
        sun = _sun(sun)
    else:
        light = _numbers(light, "light", "(x, y, h)")
        if not all(math.isfinite(v) for v in light):
            raise ValueError(f"light {light}: expected finite numbers")
    if np.isnan(h).all():
        raise ValueError("the DEM has no valid height (every sample is no-data)")
    # The declared surface: no-data samples at the lowest height.
    filled = np.where(np.isnan(h), np.nanmin(h), h)
    if eye is None or target is None:
        default_eye, default_target, centre = _raykit.default_views(h, t, geo)
        if eye is None:
            eye = default_eye
            target = default_target if target is None else target
        else:
            target = centre
    out = cast(h, t, eye=eye, target=target, width=width, height=height, fov=fov, caster=caster, tau=tau, geographic=geo, threads=threads)
    mask = None
    if shadows:
        mask = shadow(h, t, sun=None if light is not None else sun, light=light, geographic=geo, threads=threads)
        mask = (mask == 1).astype(np.float64)
    return _shade(out, filled.astype(np.float64), t, mask, sun, light)


def _shade(out, z, t, mask, sun, light) -> np.ndarray:
    d = out["directions"]
    dist = out["t"]
    hit = np.isfinite(dist)
    sx, sy = out["cell_size"]
    eye = np.asarray(out["eye"])
    p = eye + np.where(hit, dist, 0.0)[..., None] * d
    col = np.clip(out["col"], 0, z.shape[1] - 2)
    row = np.clip(out["row"], 0, z.shape[0] - 2)
    u = np.clip(p[..., 0] / sx - col, 0.0, 1.0)
    v = np.clip(-p[..., 1] / sy - row, 0.0, 1.0)
    z00, z10 = z[row, col], z[row, col + 1]
    z01, z11 = z[row + 1, col], z[row + 1, col + 1]
    upper = u >= v
    du = np.where(upper, z10 - z00, z11 - z01)
    dv = np.where(upper, z11 - z10, z01 - z00)
    n = np.stack([-du / sx, dv / sy, np.ones_like(du)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    n = np.where((np.sum(n * d, axis=-1) > 0)[..., None], -n, n)
    if light is None:
        az, el = (math.radians(float(a)) for a in sun)
        l = np.broadcast_to(np.array([math.sin(az) * math.cos(el), math.cos(az) * math.cos(el), math.sin(el)]), p.shape)
    else:
        a, _, c, _, e, f = t
        gx, gy = (light[0] - c) / a - 0.5, (light[1] - f) / e - 0.5
        ci = int(np.clip(round(gx), 0, z.shape[1] - 1))
        ri = int(np.clip(round(gy), 0, z.shape[0] - 1))
        lw = np.array([gx * sx, -gy * sy, z[ri, ci] + float(light[2])])
        l = lw - p
        l /= np.maximum(np.linalg.norm(l, axis=-1, keepdims=True), 1e-12)
    lit = np.ones_like(u)
    if mask is not None:
        m00, m10 = mask[row, col], mask[row, col + 1]
        m01, m11 = mask[row + 1, col], mask[row + 1, col + 1]
        lit = (m00 * (1 - u) + m10 * u) * (1 - v) + (m01 * (1 - u) + m11 * u) * v
    zmin, zmax = float(z.min()), float(z.max())
    frac = np.clip((p[..., 2] - zmin) / (zmax - zmin), 0.0, 1.0) if zmax > zmin else np.zeros_like(u)
    albedo = np.stack([np.interp(frac, _RAMP[:, 0], _RAMP[:, k]) for k in (1, 2, 3)], axis=-1) ** 2.2
    ndotl = np.sum(n * l, axis=-1)
    refl = 2.0 * ndotl[..., None] * n - l
    spec = np.where(ndotl > 0, _SPECULAR * np.maximum(np.sum(refl * -d, axis=-1), 0.0) ** _SHININESS, 0.0)
    k = _AMBIENT * (0.6 + 0.4 * np.abs(n[..., 2])) + _DIFFUSE * np.maximum(ndotl, 0.0) * lit
    colour = albedo * k[..., None] + (spec * lit)[..., None]
    up = np.clip(d[..., 2], -1.0, 1.0)
    s = np.sqrt(np.abs(up))[..., None]
    sky = np.where((up >= 0)[..., None], _HORIZON + (_ZENITH - _HORIZON) * s, _HORIZON + (_NADIR - _HORIZON) * s)
    colour = np.where(hit[..., None], colour, sky)
    return (np.clip(colour, 0.0, 1.0) ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)
