"""Exact terrain shadows of a DEM at one sun position, from a GeoTIFF path
or from the arrays rasterio reads, and a rendering.

    python examples/python/terrain_shadow.py DEM.tif [OUT.png]
"""

import sys

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

image = raykit.terrain.render(path, width=640, height=360, sun=(135, 20))
if len(sys.argv) > 2:
    from PIL import Image

    Image.fromarray(image).save(sys.argv[2])
    print("wrote", sys.argv[2])
