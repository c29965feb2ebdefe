//! DEM reading against rasterio (GDAL, PROJ): on the bundled GeoTIFFs (a real 3-arc-second DEM in
//! WGS84 longitude/latitude, and a UTM 16N warp of it) and on an SRTM `.hgt` tile written here,
//! rasterio picks random positions inside each raster and interpolates the ground there
//! bilinearly from its own reading of the file and its own projection; skyplan's
//! `elevation_amsl_m` must agree to a millimetre. Files rasterio can read but skyplan cannot place
//! (no georeferencing, Web Mercator) are refused naming the field.

use skyplan_map::terrain::{TerrainError, parse_dem};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn python() -> String {
    std::env::var("SKYPLAN_PYTHON").unwrap_or_else(|_| "python3".to_string())
}

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

/// rasterio's answer: `[lat, lon, elevation]` at `n` random positions inside `file`.
const SAMPLE: &str = r#"
import json, sys
import numpy as np
import rasterio
from rasterio.warp import transform
path, n = sys.argv[1], int(sys.argv[2])
rng = np.random.default_rng(7)
with rasterio.open(path) as d:
    a = d.read(1).astype(float)
    T = d.transform
    h, w = a.shape
    # Random pixel positions (pixel centres at integers), then to the raster's CRS and lon/lat.
    px = rng.uniform(0.0, w - 1.0, n)
    py = rng.uniform(0.0, h - 1.0, n)
    xs, ys = T * (px + 0.5, py + 0.5)
    if d.crs.to_epsg() == 4326:
        lons, lats = xs, ys
    else:
        lons, lats = transform(d.crs, "EPSG:4326", list(xs), list(ys))
    # Back from lon/lat (as skyplan goes), then bilinear from the four samples around.
    if d.crs.to_epsg() == 4326:
        bx, by = np.asarray(lons), np.asarray(lats)
    else:
        bx, by = transform("EPSG:4326", d.crs, list(lons), list(lats))
    col, row = ~T * (np.asarray(bx), np.asarray(by))
    x, y = col - 0.5, row - 0.5
    c0 = np.clip(np.floor(x).astype(int), 0, w - 2)
    r0 = np.clip(np.floor(y).astype(int), 0, h - 2)
    fx, fy = x - c0, y - r0
    z = (a[r0, c0] * (1 - fx) + a[r0, c0 + 1] * fx) * (1 - fy) + \
        (a[r0 + 1, c0] * (1 - fx) + a[r0 + 1, c0 + 1] * fx) * fy
    print(json.dumps([[float(la), float(lo), float(e)] for la, lo, e in zip(lats, lons, z)]))
"#;

fn rasterio_samples(path: &Path, n: usize) -> Vec<[f64; 3]> {
    let out = Command::new(python())
        .args(["-c", SAMPLE, path.to_str().unwrap(), &n.to_string()])
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "rasterio failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn agree(path: &Path, name: &str) {
    let bytes = std::fs::read(path).unwrap();
    let dem = parse_dem(name, &bytes).unwrap();
    let samples = rasterio_samples(path, 2000);
    let mut worst = 0.0f64;
    for [lat, lon, z] in samples {
        let got = dem.elevation_amsl_m(lat, lon).unwrap();
        worst = worst.max((got - z).abs());
    }
    assert!(worst < 1e-3, "{name}: worst difference {worst} m");
}

#[test]
#[ignore = "needs rasterio (pip)"]
fn geographic_geotiff_agrees_with_rasterio() {
    agree(&repo("data/terrain/jacksboro.tif"), "jacksboro.tif");
}

#[test]
#[ignore = "needs rasterio (pip)"]
fn utm_geotiff_agrees_with_rasterio_and_proj() {
    agree(&repo("data/terrain/jacksboro-utm.tif"), "jacksboro-utm.tif");
}

#[test]
#[ignore = "needs rasterio (pip)"]
fn srtm_hgt_tile_agrees_with_gdal() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("N36W085.hgt");
    let n = 1201usize;
    let mut bytes = Vec::with_capacity(n * n * 2);
    for r in 0..n {
        for c in 0..n {
            let v = (300.0
                + 200.0 * ((r as f64) / 97.0).sin() * ((c as f64) / 61.0).cos()
                + 0.1 * c as f64) as i16;
            bytes.extend_from_slice(&v.to_be_bytes());
        }
    }
    std::fs::File::create(&path)
        .unwrap()
        .write_all(&bytes)
        .unwrap();
    agree(&path, "N36W085.hgt");
}

/// rasterio writes `file` with the given CRS (None: no georeferencing).
const WRITE: &str = r#"
import sys
import numpy as np
import rasterio
from rasterio.transform import from_origin
path, crs = sys.argv[1], sys.argv[2]
kw = dict(driver="GTiff", dtype="int16", count=1, width=8, height=8)
if crs != "none":
    kw.update(crs=crs, transform=from_origin(1000.0, 2000.0, 10.0, 10.0))
with rasterio.open(path, "w", **kw) as f:
    f.write(np.arange(64, dtype=np.int16).reshape(8, 8), 1)
"#;

#[test]
#[ignore = "needs rasterio (pip)"]
fn rasters_that_cannot_be_placed_are_refused_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    for (crs, field) in [
        ("none", "ModelPixelScale"),
        ("EPSG:3857", "ProjectedCSTypeGeoKey"),
        ("EPSG:4269", "GeographicTypeGeoKey"),
    ] {
        let path = dir.path().join("x.tif");
        let st = Command::new(python())
            .args(["-c", WRITE, path.to_str().unwrap(), crs])
            .stdin(Stdio::null())
            .status()
            .unwrap();
        assert!(st.success());
        let e = parse_dem("x.tif", &std::fs::read(&path).unwrap()).unwrap_err();
        match &e {
            TerrainError::Format { field: f, .. } => assert_eq!(f, field, "{crs}: {e}"),
            other => panic!("{crs}: {other}"),
        }
    }
}
