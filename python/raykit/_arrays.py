"""numpy arrays in and out: dtype and shape checks shared by every wrapper.

Inputs may be numpy arrays, nested lists, or objects with a ``.numpy()``
method (Open3D tensors). Floats of any width and integers are accepted for
coordinates and converted to float32 (no copy when they already are
contiguous float32); anything else is a ValueError naming the argument.
"""

from __future__ import annotations

import numpy as np

from . import _raykit


class Array(np.ndarray):
    """A numpy array that also answers Open3D's ``Tensor.numpy()``.

    RaycastingScene returns these so that code written for Open3D, which
    calls ``.numpy()`` on every result, runs unchanged. Everything else is
    plain numpy; ``.numpy()`` returns a plain ``numpy.ndarray`` view.
    """

    def numpy(self) -> np.ndarray:
        """This array as a plain ``numpy.ndarray`` (a view, no copy)."""
        return self.view(np.ndarray)

    # The Tensor methods Open3D's ray-casting tutorials call on results,
    # so that their follow-up code runs unchanged too.

    def isfinite(self) -> "Array":
        """Element-wise ``numpy.isfinite`` (Open3D's ``Tensor.isfinite``)."""
        return result(np.isfinite(self.numpy()))

    def isinf(self) -> "Array":
        """Element-wise ``numpy.isinf``."""
        return result(np.isinf(self.numpy()))

    def isnan(self) -> "Array":
        """Element-wise ``numpy.isnan``."""
        return result(np.isnan(self.numpy()))

    def abs(self) -> "Array":
        """Element-wise absolute value."""
        return result(np.abs(self.numpy()))

    def logical_not(self) -> "Array":
        """Element-wise logical not."""
        return result(np.logical_not(self.numpy()))

    def lt(self, other) -> "Array":
        """Element-wise ``<``."""
        return result(self.numpy() < to_numpy(other))

    def le(self, other) -> "Array":
        """Element-wise ``<=``."""
        return result(self.numpy() <= to_numpy(other))

    def gt(self, other) -> "Array":
        """Element-wise ``>``."""
        return result(self.numpy() > to_numpy(other))

    def ge(self, other) -> "Array":
        """Element-wise ``>=``."""
        return result(self.numpy() >= to_numpy(other))

    def cpu(self) -> "Array":
        """Itself: results are always in host memory."""
        return self

    def contiguous(self) -> "Array":
        """A C-contiguous array (itself when it already is)."""
        return result(np.ascontiguousarray(self.numpy()))

    def clone(self) -> "Array":
        """A copy."""
        return result(self.numpy().copy())

    def to(self, dtype, copy: bool = False) -> "Array":
        """Converted to ``dtype``: a numpy dtype, or an Open3D one such as
        ``open3d.core.float32`` (read by its name)."""
        try:
            target = np.dtype(dtype)
        except TypeError:
            target = np.dtype(str(dtype).lower())
        return result(self.numpy().astype(target, copy=copy))


def result(a: np.ndarray) -> Array:
    """``a`` viewed as :class:`Array` (no copy)."""
    return a.view(Array)


def to_numpy(a) -> np.ndarray:
    """``a`` as a numpy array: Open3D tensors through their ``.numpy()``."""
    if isinstance(a, np.ndarray):
        return a.view(np.ndarray)
    if hasattr(a, "numpy") and callable(a.numpy):
        return np.asarray(a.numpy())
    return np.asarray(a)


def _check_real(a: np.ndarray, name: str) -> None:
    if a.dtype.kind not in "fiu":
        raise ValueError(
            f"{name} must hold real numbers (float32, float64 or integers), got dtype {a.dtype}"
        )


def reals(a, name: str, last: int | None = None, min_ndim: int = 1) -> np.ndarray:
    """``a`` as a numpy array of real numbers, of any such dtype, whose last
    axis has ``last`` entries."""
    a = to_numpy(a)
    _check_real(a, name)
    if a.ndim < min_ndim:
        raise ValueError(f"{name} must have at least {min_ndim} dimensions, got shape {a.shape}")
    if last is not None and (a.ndim == 0 or a.shape[-1] != last):
        raise ValueError(f"the last dimension of {name} must be {last}, got shape {a.shape}")
    return a


def floats(
    a, name: str, last: int | None = None, min_ndim: int = 1, shift: np.ndarray | None = None
) -> np.ndarray:
    """``a`` as C-contiguous, aligned float32 whose last axis has ``last``
    entries (buffers received over a network, as Dask's, can be contiguous
    but misaligned; those are copied). With ``shift`` (three float64
    coordinates), the first three entries of the last axis are points that
    are moved by ``-shift`` in float64 before they are rounded to float32,
    so points far from the coordinates' origin keep the precision of their
    input."""
    a = reals(a, name, last, min_ndim)
    if shift is None:
        return np.require(a, dtype=np.float32, requirements=["C", "A"])
    moved = a.astype(np.float64)
    moved[..., :3] -= shift
    return np.ascontiguousarray(moved, dtype=np.float32)


def rows(
    a, name: str, width: int, min_ndim: int = 2, shift: np.ndarray | None = None
) -> tuple[np.ndarray, tuple[int, ...]]:
    """``a`` of shape ``(..., width)`` as ``(n, width)`` float32 and the
    leading shape; ``shift`` as in :func:`floats`."""
    a = floats(a, name, last=width, min_ndim=min_ndim, shift=shift)
    lead = a.shape[:-1]
    return a.reshape(-1, width), lead


_FLOAT32 = np.dtype(np.float32)
_FLOAT64 = np.dtype(np.float64)
_NO_SHIFT = (0.0, 0.0, 0.0)


def ray_rows(
    a,
    name: str,
    shift: np.ndarray | None,
    sphere: tuple[np.ndarray, float] | None,
    every_dtype: bool = False,
    threads: int = 0,
) -> tuple[np.ndarray, tuple[int, ...], np.ndarray | None]:
    """Rays ``(..., 6)`` as :func:`rows` makes them, and how far each was
    moved. Float64 rays whose origin lies more than 16 radii (the engine's
    ``FAR_RADII``) from the centre of ``sphere`` (``(centre, radius)`` in the
    shifted coordinates; None for an empty scene) are moved along
    themselves, in float64, to twice the radius before their closest
    approach to it, where no triangle lies: float32 keeps such an origin to
    a fraction of the scene's size, and rounds it by up to half a unit at
    10⁷. Returns the float32 rays, the leading shape and the distance
    ``t0`` each moved, in its direction's length (None when none moved);
    a hit's ``t`` on the moved ray plus ``t0`` is its ``t`` on the ray
    given. Rays of other dtypes are moved only with ``every_dtype`` (the
    engine's own far-ray move covers float32 rays in Möller's nearest-hit
    and occlusion structures)."""
    if (
        type(a) is np.ndarray
        and a.dtype is _FLOAT32
        and a.ndim == 2
        and a.shape[1] == 6
        and a.flags.c_contiguous
        and a.flags.aligned
        and shift is None
        and not every_dtype
    ):
        # Already the engine's rows; checked here in a fraction of the
        # general path's time, which a call on a few rays would notice.
        return a, a.shape[:1], None
    raw = reals(a, name, last=6, min_ndim=2)
    if every_dtype and raw.dtype != np.float64:
        raw = raw.astype(np.float64)
    if sphere is None or raw.dtype != np.float64 or raw.size == 0:
        flat, lead = rows(raw, name, 6, shift=shift)
        return flat, lead, None
    lead = raw.shape[:-1]
    r = raw.reshape(-1, 6)
    if not (r.dtype is _FLOAT64 and r.flags.c_contiguous and r.flags.aligned):
        r = np.array(r, dtype=np.float64, order="C")
    centre, radius = sphere
    flat, t0 = _raykit.near_rays(r, _NO_SHIFT if shift is None else shift, centre, float(radius), threads)
    return flat, lead, t0


def bounding_sphere(points: list[np.ndarray]) -> tuple[np.ndarray, float] | None:
    """The sphere around the box of the finite ``(n, 3)`` points of every
    array (None when there are none)."""
    boxes = []
    for p in points:
        p = p[np.isfinite(p).all(axis=1)]
        if len(p):
            boxes.append((p.min(axis=0).astype(np.float64), p.max(axis=0).astype(np.float64)))
    if not boxes:
        return None
    lo = np.min([b[0] for b in boxes], axis=0)
    hi = np.max([b[1] for b in boxes], axis=0)
    return (lo + hi) / 2, max(float(np.linalg.norm(hi - lo)) / 2, 1e-30)


def indices(a, name: str) -> np.ndarray:
    """Triangle corners: ``(m, 3)`` non-negative integers as C-contiguous,
    aligned uint32."""
    a = to_numpy(a)
    if a.dtype.kind not in "iu":
        raise ValueError(f"{name} must hold integers, got dtype {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (m, 3), got {a.shape}")
    if a.size and (a.min() < 0 or int(a.max()) > np.iinfo(np.uint32).max):
        raise ValueError(f"{name} must lie between 0 and {np.iinfo(np.uint32).max}")
    return np.require(a, dtype=np.uint32, requirements=["C", "A"])


#: The most threads a call may ask for (as the extension checks).
MAX_THREADS = 4096


def threads(n, name: str = "threads") -> int:
    """A thread count: 0, a negative number or None for all cores. Errors
    name the argument ``name``."""
    if type(n) is int and 0 <= n <= MAX_THREADS:
        return n
    if n is None:
        return 0
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"{name} must be an integer (0 for all cores), got {n!r}")
    if n < 0:
        # Open3D takes any non-positive count as "all cores".
        return 0
    if n > MAX_THREADS:
        raise ValueError(f"{name} must be at most {MAX_THREADS} (0 or negative for all cores), got {n}")
    return int(n)


def count(n, name: str) -> int:
    """A whole number for an unsigned 32-bit parameter: a ValueError names
    ``name`` for a bool, a non-integer, a negative number or one above
    2**32 - 1 (the extension's own checks then give the finer limits)."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"{name} must be a whole number, got {n!r}")
    if not 0 <= n <= np.iinfo(np.uint32).max:
        raise ValueError(f"{name} must be between 0 and {np.iinfo(np.uint32).max}, got {n}")
    return int(n)


def whole(n, name: str) -> int:
    """A whole number for a parameter whose range the extension checks (and
    names): a ValueError names ``name`` for a bool, a non-integer or a
    number beyond 64 bits."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"{name} must be a whole number, got {n!r}")
    if not np.iinfo(np.int64).min <= n <= np.iinfo(np.int64).max:
        raise ValueError(f"{name} {n} is beyond the 64-bit range")
    return int(n)


def max_hits(n) -> int:
    """A cap on the hits listed per ray: ``None`` for none; a ValueError
    for a bool, a non-integer or a negative number; caps beyond the
    engine's 64-bit count mean no cap."""
    limit = int(np.iinfo(np.uint64).max)
    if n is None:
        return limit
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"max_hits must be a whole number or None, got {n!r}")
    if n < 0:
        raise ValueError(f"max_hits must be >= 0, got {n}")
    return min(int(n), limit)
