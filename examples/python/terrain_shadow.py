"""Exact terrain shadows of a DEM at one sun position, from a GeoTIFF path
or from the arrays rasterio reads, and a rendering.

    python examples/python/terrain_shadow.py DEM.tif [OUT.png]
"""

import struct
import sys
import zlib

import numpy as np

import raykit.terrain

path = sys.argv[1]
mask = raykit.terrain.shadow(path, sun=(135, 20))
valid = mask != 255
print(f"{mask.shape[1]}x{mask.shape[0]} grid points, {(mask[valid] == 0).mean():.1%} in shadow at azimuth 135°, elevation 20°")

try:
    import rasterio
except ImportError:
    rasterio = None
if rasterio is not None:
    with rasterio.open(path) as src:
        heights, transform, nodata = src.read(1), src.transform, src.nodata
    same = raykit.terrain.shadow(heights, transform, sun=(135, 20), nodata=nodata)
    print("the same mask from rasterio's arrays:", bool(np.array_equal(same, mask)))



def write_png(out, rgb):
    """An (h, w, 3) uint8 image as an 8-bit RGB PNG (zlib only)."""
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    with open(out, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


image = raykit.terrain.render(path, width=640, height=360, sun=(135, 20))
if len(sys.argv) > 2:
    write_png(sys.argv[2], image)
    print("wrote", sys.argv[2])
