"""8-bit RGB PNG output in pure Python (zlib), written atomically: a
temporary file beside the destination, renamed over it when complete."""

from __future__ import annotations

import os
import struct
import tempfile
import zlib

import numpy as np

from .files import fspath


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def write_png(path: str | bytes | os.PathLike, rgb: np.ndarray) -> None:
    """Write ``rgb``, an ``(h, w, 3)`` uint8 array, as a PNG at ``path``."""
    path = fspath(path)
    a = np.ascontiguousarray(rgb)
    if a.dtype != np.uint8 or a.ndim != 3 or a.shape[2] != 3 or 0 in a.shape[:2]:
        raise ValueError(f"{path}: expected a non-empty (h, w, 3) uint8 image, got {a.dtype} {a.shape}")
    h, w = a.shape[:2]
    # Filter type 0 (none) before each row.
    raw = np.concatenate([np.zeros((h, 1), np.uint8), a.reshape(h, w * 3)], axis=1).tobytes()
    data = (
        b"\x89PNG\r\n\x1a\n"
        + _chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
        + _chunk(b"IDAT", zlib.compress(raw, 6))
        + _chunk(b"IEND", b"")
    )
    write_atomic(path, data)


def write_atomic(path: str | bytes | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename."""
    path = fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
