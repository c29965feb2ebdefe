//! `skyplan plan --terrain DEM --alt-agl-m H`: over a real DEM (the bundled Jacksboro Fault
//! GeoTIFFs), every point of the route, sampled each metre between waypoints, is at least H above
//! the ground as rasterio (GDAL, PROJ) interpolates it from the same file — the issue asks for
//! H − 1.5 m; the climbs and descents stay within the vehicle's rates; `waypoints_lla` carries
//! heights above mean sea level. Bad requests are refused naming what is wrong.

use serde_json::Value;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
mod common;
use common::{assert_no_waypoints, fails_with, ok_json, python, rows};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(name)
}

/// rasterio's ground: `ground(d, a, lat, lon)` is the DEM `d` (its band `a`) interpolated
/// bilinearly between pixel centres at points, metres above sea level.
const GROUND: &str = r#"
import json, sys
import numpy as np
import rasterio
from rasterio.warp import transform
def ground(d, a, lat, lon):
    if d.crs.to_epsg() == 4326:
        x, y = lon, lat
    else:
        x, y = transform("EPSG:4326", d.crs, list(lon), list(lat))
    h, w = a.shape
    col, row = ~d.transform * (np.asarray(x), np.asarray(y))
    cx, ry = col - 0.5, row - 0.5
    c0 = np.clip(np.floor(cx).astype(int), 0, w - 2)
    r0 = np.clip(np.floor(ry).astype(int), 0, h - 2)
    fx, fy = cx - c0, ry - r0
    return (a[r0, c0] * (1 - fx) + a[r0, c0 + 1] * fx) * (1 - fy) + \
        (a[r0 + 1, c0] * (1 - fx) + a[r0 + 1, c0 + 1] * fx) * fy
"#;

/// With [`GROUND`]: the height above the ground under the route (stdin: `[lat, lon, amsl]`
/// rows), sampled each metre; prints the smallest, median and largest.
const CLEARANCE: &str = r#"
path = sys.argv[1]
lla = np.array(json.load(sys.stdin))
with rasterio.open(path) as d:
    a = d.read(1).astype(float)
    out = []
    for p, q in zip(lla[:-1], lla[1:]):
        # Metres between the two waypoints (equirectangular is plenty for a step count).
        dn = (q[0] - p[0]) * 111_000.0
        de = (q[1] - p[1]) * 111_000.0 * np.cos(np.radians(p[0]))
        n = max(1, int(np.ceil(np.hypot(dn, de))))
        t = np.linspace(0.0, 1.0, n + 1)
        lat, lon, amsl = (p[None, :] + t[:, None] * (q - p)[None, :]).T
        out.append(amsl - ground(d, a, lat, lon))
    c = np.concatenate(out)
    print(json.dumps([float(c.min()), float(np.median(c)), float(c.max())]))
"#;

/// With [`GROUND`]: the height above the ground of flown positions (stdin: `{"home": [lat,
/// lon], "rows": [[lat, lon, metres above the home's ground]…]}`); prints the smallest,
/// median and largest.
const FLOWN: &str = r#"
path = sys.argv[1]
q = json.load(sys.stdin)
rows = np.array(q["rows"])
with rasterio.open(path) as d:
    a = d.read(1).astype(float)
    home = ground(d, a, np.array([q["home"][0]]), np.array([q["home"][1]]))[0]
    c = rows[:, 2] + home - ground(d, a, rows[:, 0], rows[:, 1])
    print(json.dumps([float(c.min()), float(np.median(c)), float(c.max())]))
"#;

/// Runs `script` (after [`GROUND`]) on `dem` with `input` on stdin; its JSON answer.
fn by_rasterio(script: &str, dem: &Path, input: &Value) -> [f64; 3] {
    let mut child = Command::new(python())
        .args(["-c", &format!("{GROUND}{script}"), dem.to_str().unwrap()])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.to_string().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn clearance_by_rasterio(dem: &Path, lla: &Value) -> [f64; 3] {
    by_rasterio(CLEARANCE, dem, lla)
}

/// Slopes of the route: each leg's altitude change over its horizontal length.
fn slopes(wps: &[[f64; 4]]) -> Vec<f64> {
    wps.windows(2)
        .filter_map(|w| {
            let len = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
            (len > 1e-6).then(|| (w[1][2] - w[0][2]) / len)
        })
        .collect()
}

/// A one-box colliders map on the DEM's hills, `hills.csv` in `dir`.
fn write_hills(dir: &Path) {
    std::fs::write(
        dir.join("hills.csv"),
        "lat0 36.56, lon0 -84.28\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n50,50,10,5,5,10\n",
    )
    .unwrap();
}

/// Zones need a map at an altitude: a colliders map on the hills, two posts marking the corners
/// of 3 km square (`posts.csv` in `dir`).
fn write_posts(dir: &Path) {
    std::fs::write(
        dir.join("posts.csv"),
        "lat0 36.56, lon0 -84.28\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n-20,-20,5,1,1,5\n3020,3020,5,1,1,5\n",
    )
    .unwrap();
}

/// Smallest horizontal distance from `c` to the route (metres).
fn distance_to_route(rows: &[[f64; 4]], c: [f64; 2]) -> f64 {
    rows.windows(2)
        .map(|w| skyplan_testkit::distance_to_segment(c, [w[0][0], w[0][1]], [w[1][0], w[1][1]]))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn zones_over_terrain_apply_by_their_bands_above_sea_level() {
    use skyplan_frames::{Lla, LocalFrame};
    let dir = tempfile::tempdir().unwrap();
    let tif = data("terrain/jacksboro.tif");
    write_posts(dir.path());
    let base = format!(
        "plan --json --map posts.csv --terrain {} --alt-agl-m 30 --start-ne 100,100 --goal-ne 2900,2800",
        tif.display()
    );
    let plain = ok_json(dir.path(), &base);
    // A circle of 80 m on the plain route's middle, and the lowest ground around it (AMSL).
    let frame = LocalFrame::new(Lla {
        lat_deg: 36.56,
        lon_deg: -84.28,
        alt_m: 0.0,
    })
    .unwrap();
    let dem =
        skyplan_map::terrain::parse_dem("jacksboro.tif", &std::fs::read(&tif).unwrap()).unwrap();
    let terrain = skyplan_map::terrain::Terrain::new(dem, frame).unwrap();
    let w = rows(&plain);
    let mid = w[w.len() / 2];
    let c = [mid[0], mid[1]];
    let (r, margin) = (80.0, 5.0);
    let ground_amsl = terrain
        .min_ground_m_in(
            [c[0] - r - margin, c[0] + r + margin],
            [c[1] - r - margin, c[1] + r + margin],
        )
        .unwrap()
        + terrain.home_ground_amsl_m();
    let centre = frame
        .lla_from_ned(skyplan_frames::Ned {
            north_m: c[0],
            east_m: c[1],
            down_m: 0.0,
        })
        .unwrap();
    let zone = |ceiling_amsl: f64| {
        format!(
            r#"{{"type": "FeatureCollection", "features": [{{"type": "Feature", "properties": {{"radius_m": {r}, "floor_m": 0, "ceiling_m": {ceiling_amsl}, "reference": "amsl"}}, "geometry": {{"type": "Point", "coordinates": [{}, {}]}}}}]}}"#,
            centre.lon_deg, centre.lat_deg
        )
    };
    assert!(distance_to_route(&w, c) < 1.0);
    // Below the route wherever it can be (ceiling + margin under ground + 30 m): flown over.
    std::fs::write(
        dir.path().join("low.geojson"),
        zone(ground_amsl + 30.0 - margin - 10.0),
    )
    .unwrap();
    let low = ok_json(dir.path(), &format!("{base} --no-fly low.geojson"));
    assert_eq!(rows(&low), w);
    // Reaching above the lowest the route can be there: gone around, by the margin.
    std::fs::write(
        dir.path().join("high.geojson"),
        zone(ground_amsl + 30.0 + 20.0),
    )
    .unwrap();
    let high = ok_json(dir.path(), &format!("{base} --no-fly high.geojson"));
    let d = distance_to_route(&rows(&high), c);
    assert!(d >= r + margin - 1e-6, "{d}");
    high["terrain"]["alt_agl_m"].as_f64().unwrap();
}

/// An inclusion boundary over terrain: the route stays inside it (less the margin) at every
/// altitude, sampled each metre; a ceiling the ground forces the route above is no path,
/// naming the boundary.
#[test]
fn inclusion_boundaries_over_terrain_hold_the_route_and_their_band() {
    use skyplan_frames::{Lla, LocalFrame, Ned};
    let dir = tempfile::tempdir().unwrap();
    let tif = data("terrain/jacksboro.tif");
    write_posts(dir.path());
    let frame = LocalFrame::new(Lla {
        lat_deg: 36.56,
        lon_deg: -84.28,
        alt_m: 0.0,
    })
    .unwrap();
    // An L: north up the western strip, then east along the northern one.
    let ring_ne = [
        [0.0, 0.0],
        [0.0, 400.0],
        [2500.0, 400.0],
        [2500.0, 3000.0],
        [3000.0, 3000.0],
        [3000.0, 0.0],
    ];
    let zone = |ceiling_amsl: f64| {
        let coords: Vec<String> = ring_ne
            .iter()
            .chain(std::iter::once(&ring_ne[0]))
            .map(|p| {
                let l = frame
                    .lla_from_ned(Ned {
                        north_m: p[0],
                        east_m: p[1],
                        down_m: 0.0,
                    })
                    .unwrap();
                format!("[{}, {}]", l.lon_deg, l.lat_deg)
            })
            .collect();
        format!(
            r#"{{"type": "FeatureCollection", "features": [{{"type": "Feature", "properties": {{"inclusion": true, "floor_m": 0, "ceiling_m": {ceiling_amsl}, "reference": "amsl"}}, "geometry": {{"type": "Polygon", "coordinates": [[{}]]}}}}]}}"#,
            coords.join(", ")
        )
    };
    std::fs::write(dir.path().join("inside.geojson"), zone(3000.0)).unwrap();
    let base = format!(
        "plan --json --map posts.csv --terrain {} --alt-agl-m 30 --start-ne 100,100 --goal-ne 2900,2800",
        tif.display()
    );
    let v = ok_json(dir.path(), &format!("{base} --no-fly inside.geojson"));
    let w = rows(&v);
    let margin = 5.0;
    let inside = |p: [f64; 2]| {
        let mut odd = false;
        for k in 0..ring_ne.len() {
            let (a, b) = (ring_ne[k], ring_ne[(k + 1) % ring_ne.len()]);
            if (a[0] > p[0]) != (b[0] > p[0])
                && p[1] < (b[1] - a[1]) * (p[0] - a[0]) / (b[0] - a[0]) + a[1]
            {
                odd = !odd;
            }
        }
        let edge = (0..ring_ne.len())
            .map(|k| {
                skyplan_testkit::distance_to_segment(
                    p,
                    ring_ne[k],
                    ring_ne[(k + 1) % ring_ne.len()],
                )
            })
            .fold(f64::INFINITY, f64::min);
        odd && edge >= margin - 1e-6
    };
    for l in w.windows(2) {
        let len = (l[1][0] - l[0][0]).hypot(l[1][1] - l[0][1]);
        let n = len.ceil().max(1.0) as usize;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let p = [
                l[0][0] + (l[1][0] - l[0][0]) * t,
                l[0][1] + (l[1][1] - l[0][1]) * t,
            ];
            assert!(
                inside(p),
                "route point {p:?} outside the boundary less the margin"
            );
        }
    }
    // The straight line leaves the L: the route turns the corner.
    assert!(w.iter().any(|p| p[0] > 2400.0 && p[1] < 500.0), "{w:?}");
    // A ceiling 150 m above the ground under home: the hills lift the route through it.
    let ground = v["terrain"]["home_ground_amsl_m"].as_f64().unwrap();
    std::fs::write(dir.path().join("low.geojson"), zone(ground + 150.0)).unwrap();
    fails_with(
        dir.path(),
        &format!("{base} --no-fly low.geojson"),
        3,
        &["feature 0", "inclusion boundary", "--alt-agl-m"],
    );
}

fn over(dem: &str, home: &str, goal: &str, agl: f64) -> (PathBuf, Value) {
    let dir = tempfile::tempdir().unwrap();
    let path = data(dem);
    let v = ok_json(
        dir.path(),
        &format!(
            "plan --json --random 3000x3000 --density 0.0002 --home {home} --terrain {} --alt-agl-m {agl} --start-ne 100,100 --goal-ne {goal}",
            path.display()
        ),
    );
    (path, v)
}

#[test]
#[ignore = "needs rasterio (pip)"]
fn routes_keep_the_height_above_the_ground_by_rasterio() {
    for (dem, home, goal, agl) in [
        ("terrain/jacksboro.tif", "36.56,-84.28", "2900,2800", 30.0),
        ("terrain/jacksboro.tif", "36.62,-84.20", "2600,150", 12.0),
        (
            "terrain/jacksboro-utm.tif",
            "36.55,-84.25",
            "2900,2600",
            50.0,
        ),
    ] {
        let (path, v) = over(dem, home, goal, agl);
        let lla = &v["waypoints_lla"];
        assert_eq!(
            lla[0].as_array().unwrap().len(),
            3,
            "[lat, lon, alt_amsl_m]"
        );
        let [lo, median, hi] = clearance_by_rasterio(&path, lla);
        eprintln!(
            "{dem} {home}: clearance {lo:.2} / {median:.1} / {hi:.1} m (lowest, median, highest)"
        );
        assert!(lo >= agl - 1.5, "{dem} {home}: lowest clearance {lo} m");
        // Tight where the ground is highest under the route (it is not flying needlessly
        // high; over valleys the descent rate keeps it higher).
        assert!(lo <= agl + 2.0, "{dem} {home}: lowest clearance {lo} m");
        // Within the climb (3 m/s) and descent (1.5 m/s) rates at 10 m/s.
        for s in slopes(&rows(&v)) {
            assert!((-0.15 - 1e-9..=0.3 + 1e-9).contains(&s), "{dem}: slope {s}");
        }
        // Heights above sea level are the altitudes above home plus the ground under home.
        let ground = v["terrain"]["home_ground_amsl_m"].as_f64().unwrap();
        for (row, w) in lla.as_array().unwrap().iter().zip(rows(&v)) {
            assert!((row[2].as_f64().unwrap() - (w[2] + ground)).abs() < 1e-6);
        }
    }
}

/// The FCND city's buildings set down on the Jacksboro hills (`city.csv` in `dir`).
fn write_city_on_hills(dir: &Path) {
    let fcnd = std::fs::read_to_string(data("colliders.csv")).unwrap();
    let body = fcnd.split_once('\n').unwrap().1;
    std::fs::write(
        dir.join("city.csv"),
        format!("lat0 36.56, lon0 -84.28\n{body}"),
    )
    .unwrap();
}

/// The 3D planners treat the ground as an obstacle: every metre of their routes is at least H
/// above rasterio's ground (geographic and UTM DEMs), and they start no higher than the
/// ground's relief near the start asks.
#[test]
#[ignore = "needs rasterio (pip)"]
fn three_d_routes_keep_the_height_above_the_ground_by_rasterio() {
    let dir = tempfile::tempdir().unwrap();
    write_city_on_hills(dir.path());
    for (planner, dem, agl) in [
        ("rrt-connect", "terrain/jacksboro.tif", 30.0),
        ("voxel", "terrain/jacksboro.tif", 30.0),
        ("prm", "terrain/jacksboro-utm.tif", 25.0),
    ] {
        let path = data(dem);
        let v = ok_json(
            dir.path(),
            &format!(
                "plan --json --map city.csv --terrain {} --alt-agl-m {agl} --planner {planner} --goal-ne 500,400",
                path.display()
            ),
        );
        let lla = &v["waypoints_lla"];
        let [lo, median, hi] = clearance_by_rasterio(&path, lla);
        eprintln!(
            "{planner} on {dem}: clearance {lo:.2} / {median:.1} / {hi:.1} m (lowest, median, highest)"
        );
        // The planners' columns of ground are as high as the ground gets in them, and the
        // final check is exact: no metre is lower than H (a centimetre for the two readings).
        assert!(lo >= agl - 0.05, "{planner}: lowest clearance {lo} m");
        let w = rows(&v);
        let ground = v["terrain"]["home_ground_amsl_m"].as_f64().unwrap();
        for (row, p) in lla.as_array().unwrap().iter().zip(&w) {
            assert!((row[2].as_f64().unwrap() - (p[2] + ground)).abs() < 1e-6);
        }
        // The start (home) is H above the highest ground of the 10 m columns within the
        // margin: the ground under home is 0 m above home, and the slope there is under 1:1.
        assert!(
            w[0][2] >= agl && w[0][2] <= agl + 15.0,
            "{planner}: starts at {} m",
            w[0][2]
        );
    }
}

/// Building footprints on the hills (the sample's moved onto the DEM): the 3D planners plan among
/// them standing on the ground, every metre of the route H above rasterio's ground.
#[test]
#[ignore = "needs rasterio (pip)"]
fn three_d_routes_among_footprints_on_the_hills() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(data("footprints-sample.geojson")).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    // From San Francisco to the Jacksboro hills, every position moved by the same degrees.
    fn shift(c: &mut Value) {
        match c.as_array_mut() {
            Some(a) if a.len() == 2 && a[0].is_number() => {
                a[0] = (a[0].as_f64().unwrap() + (-84.28 + 122.3975)).into();
                a[1] = (a[1].as_f64().unwrap() + (36.56 - 37.7925)).into();
            }
            Some(a) => a.iter_mut().for_each(shift),
            None => {}
        }
    }
    for f in v["features"].as_array_mut().unwrap() {
        shift(&mut f["geometry"]["coordinates"]);
    }
    std::fs::write(dir.path().join("hills.geojson"), v.to_string()).unwrap();
    let path = data("terrain/jacksboro.tif");
    for planner in ["rrt-connect", "voxel"] {
        let v = ok_json(
            dir.path(),
            &format!(
                "plan --json --map hills.geojson --terrain {} --alt-agl-m 30 --planner {planner} --goal-ne 118,-61",
                path.display()
            ),
        );
        assert_eq!(v["obstacles"], 42, "{planner}");
        let [lo, median, hi] = clearance_by_rasterio(&path, &v["waypoints_lla"]);
        eprintln!("{planner}: clearance {lo:.2} / {median:.1} / {hi:.1} m");
        assert!(lo >= 30.0 - 0.05, "{planner}: lowest clearance {lo} m");
    }
}

/// A 3D plan's trajectory over terrain: its samples (10 Hz), put on the Earth about the map's
/// home, stay H above rasterio's ground each metre; the report says how it was made.
#[test]
#[ignore = "needs rasterio (pip)"]
fn three_d_trajectories_keep_the_height_above_the_ground_by_rasterio() {
    use skyplan_frames::{Lla, LocalFrame, Ned};
    let dir = tempfile::tempdir().unwrap();
    let path = data("terrain/jacksboro.tif");
    let agl = 30.0;
    let v = ok_json(
        dir.path(),
        &format!(
            "plan --json --map {} --terrain {} --alt-agl-m {agl} --planner voxel --start-ne 0,0 --goal-ne 550,450 --trajectory",
            data("terrain/blocks.csv").display(),
            path.display()
        ),
    );
    let tr = &v["trajectory"];
    assert!(tr["method"].is_string(), "{tr}");
    let ground = v["terrain"]["home_ground_amsl_m"].as_f64().unwrap();
    let frame = LocalFrame::new(Lla {
        lat_deg: 36.56,
        lon_deg: -84.28,
        alt_m: 0.0,
    })
    .unwrap();
    let lla: Vec<[f64; 3]> = tr["samples"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| {
            let r: Vec<f64> = row
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let p = frame
                .lla_from_ned(Ned {
                    north_m: r[1],
                    east_m: r[2],
                    down_m: 0.0,
                })
                .unwrap();
            [p.lat_deg, p.lon_deg, r[3] + ground]
        })
        .collect();
    assert!(lla.len() > 100);
    let [lo, median, hi] = clearance_by_rasterio(&path, &serde_json::json!(lla));
    eprintln!("voxel trajectory: clearance {lo:.2} / {median:.1} / {hi:.1} m");
    assert!(lo >= agl - 0.05, "lowest clearance {lo} m");
    // 2D planners lift their route after planning: no corridor knows the ground for them.
    fails_with(
        dir.path(),
        &format!(
            "plan --map {} --terrain {} --alt-agl-m {agl} --start-ne 0,0 --goal-ne 550,450 --trajectory",
            data("terrain/blocks.csv").display(),
            path.display()
        ),
        2,
        &["trajectory", "3D planner", "voxel"],
    );
}

#[test]
fn slower_climbs_start_earlier() {
    let dir = tempfile::tempdir().unwrap();
    let path = data("terrain/jacksboro.tif");
    let line = |extra: &str| {
        format!(
            "plan --json --random 3000x3000 --density 0.0002 --home 36.56,-84.28 --terrain {} --alt-agl-m 30 --start-ne 100,100 --goal-ne 2900,2800{extra}",
            path.display()
        )
    };
    let fast = ok_json(dir.path(), &line(""));
    let slow = ok_json(dir.path(), &line(" --max-climb-m-s 1"));
    let steepest = |v: &Value| slopes(&rows(v)).into_iter().fold(f64::MIN, f64::max);
    assert!(steepest(&fast) > 0.2, "{}", steepest(&fast));
    assert!(steepest(&slow) <= 0.1 + 1e-9, "{}", steepest(&slow));
    // Climbing slower means flying higher on the whole.
    // Mean altitude over the distance flown (each leg's length × its mean altitude).
    let mean_alt = |v: &Value| {
        let w = rows(v);
        let (mut area, mut total) = (0.0, 0.0);
        for l in w.windows(2) {
            let len = (l[1][0] - l[0][0]).hypot(l[1][1] - l[0][1]);
            area += len * (l[0][2] + l[1][2]) / 2.0;
            total += len;
        }
        area / total
    };
    assert!(mean_alt(&slow) > mean_alt(&fast));
}

#[test]
fn bad_terrain_requests_are_refused_naming_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let tif = data("terrain/jacksboro.tif");
    let t = tif.display();
    // The bundled city is in San Francisco; the DEM in Tennessee.
    fails_with(
        dir.path(),
        &format!("plan --terrain {t}"),
        2,
        &["jacksboro.tif", "does not cover", "the map's home"],
    );
    fails_with(
        dir.path(),
        "plan --alt-agl-m 30",
        2,
        &["--alt-agl-m", "--terrain FILE"],
    );
    let random = "plan --random 300x300 --density 0.01";
    fails_with(
        dir.path(),
        &format!("{random} --terrain {t}"),
        2,
        &["no geodetic home", "--home"],
    );
    let here = format!("{random} --home 36.56,-84.28 --terrain {t}");
    // A colliders map on the hills: over terrain the 3D planners' ends are alt_agl_m above
    // the ground, not at a given altitude.
    write_hills(dir.path());
    fails_with(
        dir.path(),
        &format!(
            "plan --map hills.csv --terrain {t} --planner rrt-connect --goal-ne 200,200 --start-alt-m 40"
        ),
        2,
        &["--start-alt-m", "--alt-agl-m", "leave"],
    );
    fails_with(
        dir.path(),
        &format!("{here} --trajectory"),
        2,
        &["trajectory", "terrain", "3D planner"],
    );
    fails_with(
        dir.path(),
        &format!("{here} --alt-agl-m 30 --alt-m 20"),
        2,
        &["--alt-agl-m 30", "--alt-m 20"],
    );
    // A route off the DEM's edge names where.
    fails_with(
        dir.path(),
        &format!(
            "plan --random 300x300 --density 0.01 --home 36.7305,-84.30 --terrain {t} --start-ne 10,10 --goal-ne 290,10"
        ),
        2,
        &["does not cover", "on the route at N"],
    );
    // Too big to be a DEM it can hold: refused from its size, before reading (a sparse file).
    let big = std::fs::File::create(dir.path().join("big.tif")).unwrap();
    big.set_len(skyplan_map::terrain::MAX_DEM_BYTES + 1)
        .unwrap();
    fails_with(
        dir.path(),
        &format!("{random} --home 36.56,-84.28 --terrain big.tif"),
        2,
        &["big.tif", "bytes is more than a DEM", "crop it"],
    );
    // Not a DEM: the file is named.
    std::fs::write(dir.path().join("junk.tif"), b"II*\0 not a tiff").unwrap();
    std::fs::remove_file(dir.path().join("hills.csv")).unwrap();
    fails_with(
        dir.path(),
        &format!("{random} --home 36.56,-84.28 --terrain junk.tif"),
        2,
        &["junk.tif"],
    );
    std::fs::write(dir.path().join("N36W085.hgt"), vec![0u8; 1000]).unwrap();
    fails_with(
        dir.path(),
        &format!("{random} --home 36.56,-84.28 --terrain N36W085.hgt"),
        2,
        &["N36W085.hgt", "1000 bytes"],
    );
    // Over terrain fly flies the planned route: going around what the map lacks waits for a
    // replanner that follows the ground.
    write_hills(dir.path());
    fails_with(
        dir.path(),
        &format!("fly --sim --map hills.csv --terrain {t} --goal-ne 200,200 --hidden-random 2"),
        2,
        &["--hidden-random over terrain", "one altitude"],
    );
    std::fs::remove_file(dir.path().join("hills.csv")).unwrap();
    assert_no_waypoints(dir.path(), "nothing is written on a refusal");
}

/// Over a DEM a `.plan` file's takeoff and waypoints are above mean sea level
/// (MAV_FRAME_GLOBAL): each item's altitude is its waypoint's `alt_amsl_m` in `waypoints_lla`,
/// and the summary says which frame.
#[test]
fn a_mission_over_terrain_is_written_above_mean_sea_level() {
    let dir = tempfile::tempdir().unwrap();
    let dem = data("terrain/jacksboro.tif");
    let line = format!(
        "plan --random 3000x3000 --density 0.0002 --home 36.56,-84.28 --terrain {} --alt-agl-m 30 --start-ne 100,100 --goal-ne 2900,2800",
        dem.display()
    );
    let v = ok_json(dir.path(), &format!("{line} --json"));
    let out = common::succeed(dir.path(), &format!("{line} --out m.plan"));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("m.plan (plan; altitudes above mean sea level, MAV_FRAME_GLOBAL)"),
        "{text}"
    );
    let plan: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("m.plan")).unwrap()).unwrap();
    let items = plan["mission"]["items"].as_array().unwrap();
    let lla = v["waypoints_lla"].as_array().unwrap();
    assert_eq!(items.len(), lla.len() + 1);
    for (item, row) in items.iter().zip(lla) {
        assert_eq!(item["frame"], 0);
        let (got, want) = (item["Altitude"].as_f64().unwrap(), row[2].as_f64().unwrap());
        assert!((got - want).abs() < 1e-6, "{got} vs {want}");
    }
}

/// `fly --sim` over the Jacksboro hills among the bundled blocks, taking off 134 m higher up
/// than the map's home and landing 100 m lower: the
/// vehicle's own altitudes are above where it stands, the run's above the map's home; the
/// flown positions (the log, every row once the first waypoint is reached) keep the route's
/// height above the ground as rasterio reads it, less the tracking error, and the vehicle lands
/// on the ground at the goal. The RTL altitude clears the ground under a straight way home.
#[test]
#[ignore = "needs rasterio (pip)"]
fn flights_over_terrain_keep_the_height_above_the_ground_by_rasterio() {
    let dir = tempfile::tempdir().unwrap();
    let dem = data("terrain/jacksboro.tif");
    let out = common::succeed(
        dir.path(),
        &format!(
            "fly --sim --speedup 40 --timeout-s 300 --map {} --terrain {} --alt-agl-m 30 --start-ne 400,100 --goal-ne -50,450 --log flight.csv",
            data("terrain/blocks.csv").display(),
            dem.display()
        ),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "terrain    the vehicle stands on ground +134.",
        "rtl        the ground under a straight way home rises to",
        "terrain    lowest ",
        "(the route keeps 30 m above it)",
        "no collision with the map's obstacles",
        "result     landed and disarmed after reaching all ",
    ] {
        assert!(stdout.contains(needle), "{needle:?} in:\n{stdout}");
    }
    assert!(!stdout.contains("GROUND STRIKE"), "{stdout}");
    let text = std::fs::read_to_string(dir.path().join("flight.csv")).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let f = |s: &str| s.parse::<f64>().unwrap();
    // Columns: time, state, north, east, alt, heading, speed, target index (from 1), …, lat, lon.
    let on_the_way: Vec<[f64; 3]> = (rows.iter())
        .filter(|r| r[1] == "WAYPOINT" && r[7].parse::<usize>().is_ok_and(|k| k >= 2))
        .map(|r| [f(r[12]), f(r[13]), f(r[4])])
        .collect();
    assert!(on_the_way.len() > 100, "{} rows", on_the_way.len());
    let input = serde_json::json!({"home": [36.56, -84.28], "rows": on_the_way});
    let [low, median, _] = by_rasterio(FLOWN, &dem, &input);
    assert!(
        low >= 30.0 - 1.5 - 1.0,
        "lowest {low:.2} m above the ground (median {median:.2})"
    );
    // It took off on the ground at the start and landed on the ground at the goal: both ends
    // of the log are at the ground's height above the map's home.
    let ends = [rows.first().unwrap(), rows.last().unwrap()];
    let ends: Vec<[f64; 3]> = ends.iter().map(|r| [f(r[12]), f(r[13]), f(r[4])]).collect();
    let input = serde_json::json!({"home": [36.56, -84.28], "rows": ends});
    let [lo, _, hi] = by_rasterio(FLOWN, &dem, &input);
    assert!(
        lo > -0.5 && hi < 0.5,
        "ends {lo:.2}..{hi:.2} m above the ground"
    );
    let [first, last] = [ends[0], ends[1]];
    assert!(
        first[2] > 100.0,
        "the start stands high above home: {first:?}"
    );
    assert!(first[2] - last[2] > 50.0, "the goal lies lower: {ends:?}");
}

/// `skyplan sim --terrain` in its own process, its vehicle 134 m up the hill (`--home`), and
/// `fly --connect` with the same DEM: the ground station finds the vehicle's ground from where
/// it reports itself, flies the profile and lands it on the ground at the goal.
#[test]
fn a_separate_simulator_stands_its_vehicle_on_the_terrain() {
    let (blocks, dem) = (data("terrain/blocks.csv"), data("terrain/jacksboro.tif"));
    let (blocks, dem) = (blocks.to_str().unwrap(), dem.to_str().unwrap());
    let sim = common::SimProcess::start(&[
        "--speedup",
        "40",
        "--duration-s",
        "200",
        "--map",
        blocks,
        "--terrain",
        dem,
        "--home",
        "36.5635765,-84.2787574",
    ]);
    let dir = tempfile::tempdir().unwrap();
    let out = common::succeed(
        dir.path(),
        &format!(
            "fly --connect {} --speedup 40 --timeout-s 200 --map {blocks} --terrain {dem} --alt-agl-m 30 --goal-ne -50,450",
            sim.address
        ),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "terrain    the vehicle stands on ground +134.",
        "result     landed and disarmed after reaching all ",
        "terrain    lowest ",
    ] {
        assert!(stdout.contains(needle), "{needle:?} in:\n{stdout}");
    }
    // It landed on the ground at the goal, 105 m below where it took off.
    let end = common::final_alt_m(&stdout);
    assert!(
        (end - 29.1).abs() < 1.0,
        "landed at {end} m above the map's home"
    );
}

/// `fly --upload` over terrain: the mission's items are above the vehicle's home (it takes off
/// 134 m above the map's home, so its first waypoint, 167 m above the map's home, is a take-off
/// to 32.7 m), and the AUTO flight keeps the route's height above the ground.
#[test]
fn an_uploaded_mission_over_terrain_is_above_the_vehicles_home() {
    let dir = tempfile::tempdir().unwrap();
    let out = common::succeed(
        dir.path(),
        &format!(
            "fly --sim --upload --speedup 40 --timeout-s 300 --map {} --terrain {} --alt-agl-m 30 --start-ne 400,100 --goal-ne -50,450",
            data("terrain/blocks.csv").display(),
            data("terrain/jacksboro.tif").display()
        ),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let takeoff_m: f64 = (stdout.split("take-off to ").nth(1))
        .and_then(|rest| rest.split(" m,").next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("no take-off altitude:\n{stdout}"));
    assert!((takeoff_m - 32.7).abs() < 0.2, "take-off to {takeoff_m} m");
    let low: f64 = (stdout.split("terrain    lowest ").nth(1))
        .and_then(|rest| rest.split(" m above").next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("no lowest height:\n{stdout}"));
    assert!(low >= 28.5, "lowest {low} m above the ground");
    assert!(
        stdout.contains("result     landed and disarmed after reaching all 8 waypoints"),
        "{stdout}"
    );
}
