"""Writes the DEMs in this folder from the real elevation model matplotlib ships.

matplotlib's sample data `jacksboro_fault_dem.npz` holds a 3-arc-second (about 90 m) DEM of the
Jacksboro Fault, Tennessee (USGS data, as used by matplotlib's hill-shading examples): 344 x 403
samples, 236 m to 1,076 m above sea level.

    python3 -m venv venv && venv/bin/pip install matplotlib rasterio
    venv/bin/python data/terrain/make_dem.py

jacksboro.tif      WGS84 longitude/latitude (EPSG:4326), 16-bit integers, as in the source.
jacksboro-utm.tif  a 15 km square of it warped to UTM zone 16N (EPSG:32616), 90 m pixels,
                   32-bit floats (bilinear), nodata -9999 outside the source.
"""
import os

import numpy as np
import rasterio
from matplotlib.cbook import get_sample_data
from rasterio.transform import from_origin
from rasterio.warp import Resampling, reproject

here = os.path.dirname(os.path.abspath(__file__))
d = get_sample_data("jacksboro_fault_dem.npz")
z = d["elevation"].astype(np.int16)
dx, dy = float(d["dx"]), float(d["dy"])
# The file's "ymin" is the northern edge (its rows run south), xmin the western edge.
west, north = float(d["xmin"]), float(d["ymin"])
geo = from_origin(west, north, dx, dy)
profile = dict(driver="GTiff", dtype="int16", count=1, width=z.shape[1], height=z.shape[0],
               crs="EPSG:4326", transform=geo, compress="deflate")
with rasterio.open(os.path.join(here, "jacksboro.tif"), "w", **profile) as f:
    f.write(z, 1)

# 15 km square of UTM 16N about the middle of the source.
utm = from_origin(739_000.0, 4_060_500.0, 90.0, 90.0)
n = 167
out = np.full((n, n), -9999.0, dtype=np.float32)
reproject(z.astype(np.float32), out, src_transform=geo, src_crs="EPSG:4326", dst_transform=utm,
          dst_crs="EPSG:32616", resampling=Resampling.bilinear, dst_nodata=-9999.0)
profile = dict(driver="GTiff", dtype="float32", count=1, width=n, height=n, crs="EPSG:32616",
               transform=utm, nodata=-9999.0, compress="deflate")
with rasterio.open(os.path.join(here, "jacksboro-utm.tif"), "w", **profile) as f:
    f.write(out, 1)
