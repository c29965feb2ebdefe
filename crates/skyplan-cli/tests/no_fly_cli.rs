//! `skyplan plan --no-fly FILE`: routes on the bundled city and on a footprint map keep the
//! margin from every zone whose band holds the altitude (distances computed here from the
//! zones as parsed), the grid has the cells the zones block, the TOML key gives the same route,
//! and bad zone files are refused naming the file, the feature and the field.

use serde_json::Value;
use skyplan_cspace::{Grid2, GridSpec};
use skyplan_map::colliders::GeodeticHome;
use skyplan_map::nofly::{Zone, ZoneShape, parse_no_fly};
use std::path::{Path, PathBuf};
mod common;
use common::{fails_with, ok_json, rows, succeed};
use skyplan_testkit::distance_to_segment;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(name)
}

/// The route's smallest distance to a zone: circles by their centre; polygons by sampling
/// every segment each 1 cm against the edges and an even-odd inside test.
fn clearance(wps: &[[f64; 4]], z: &Zone) -> f64 {
    let mut best = f64::INFINITY;
    for w in wps.windows(2) {
        let (a, b) = ([w[0][0], w[0][1]], [w[1][0], w[1][1]]);
        match &z.shape {
            ZoneShape::Circle { centre, radius_m } => {
                best = best.min(distance_to_segment(*centre, a, b) - radius_m);
            }
            ZoneShape::Polygon(rings) => {
                let n = ((a[0] - b[0]).hypot(a[1] - b[1]) / 0.01).ceil().max(1.0) as usize;
                for k in 0..=n {
                    let t = k as f64 / n as f64;
                    let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                    let mut odd = false;
                    let mut d = f64::INFINITY;
                    for ring in rings {
                        for i in 0..ring.len() {
                            let (c, e) = (ring[i], ring[(i + 1) % ring.len()]);
                            d = d.min(distance_to_segment(p, c, e));
                            if (c[0] > p[0]) != (e[0] > p[0])
                                && p[1] < c[1] + (p[0] - c[0]) / (e[0] - c[0]) * (e[1] - c[1])
                            {
                                odd = !odd;
                            }
                        }
                    }
                    best = best.min(if odd { 0.0 } else { d });
                }
            }
        }
    }
    best
}

fn zones_of(path: &Path, home: &Value) -> Vec<Zone> {
    let text = std::fs::read_to_string(path).unwrap();
    let home = GeodeticHome {
        lat_deg: home["lat_deg"].as_f64().unwrap(),
        lon_deg: home["lon_deg"].as_f64().unwrap(),
    };
    parse_no_fly(&text).unwrap().project(home, None).unwrap()
}

#[test]
fn the_default_route_goes_around_the_sample_zones() {
    let dir = tempfile::tempdir().unwrap();
    let zones_path = data("no-fly-sample.geojson");
    let plain = ok_json(dir.path(), "plan --json");
    let v = ok_json(
        dir.path(),
        &format!("plan --json --no-fly {}", zones_path.display()),
    );
    let zones = zones_of(&zones_path, &v["home"]);
    let wps = rows(&v);
    let before = rows(&plain);
    for z in zones.iter().filter(|z| z.meets_altitude(5.0, 5.0)) {
        assert!(clearance(&before, z) <= 0.0, "zone {} is across", z.feature);
        assert!(clearance(&wps, z) >= 5.0 - 1e-6, "zone {}", z.feature);
    }
    // The grid the route was planned on: the city's at 5 m with the zones blocked.
    let city = skyplan_map::colliders::parse_colliders(
        &std::fs::read_to_string(data("colliders.csv")).unwrap(),
    )
    .unwrap();
    let mut grid = Grid2::from_colliders(&city, GridSpec::default()).unwrap();
    let by_zones = grid.block_zones(&zones, GridSpec::default()).unwrap();
    assert!(by_zones > 1000, "{by_zones}");
    assert_eq!(v["grid"]["blocked_cells"], grid.blocked_count());
    assert!(v["cost_m"].as_f64() > plain["cost_m"].as_f64());
    // The same from the config file's key (relative to the config).
    std::fs::copy(&zones_path, dir.path().join("zones.geojson")).unwrap();
    std::fs::write(dir.path().join("c.toml"), "no_fly = \"zones.geojson\"\n").unwrap();
    let from_config = ok_json(dir.path(), "plan --json --config c.toml");
    assert_eq!(from_config["waypoints"], v["waypoints"]);
}

/// A 3D route's smallest distance to a zone whose band, grown by `margin_m`, meets it: each
/// segment's part within the grown band, measured by [`clearance`].
fn clearance_3d(wps: &[[f64; 4]], z: &Zone, margin_m: f64) -> f64 {
    let (lo, hi) = (z.floor_m - margin_m, z.ceiling_m + margin_m);
    let mut best = f64::INFINITY;
    for w in wps.windows(2) {
        if let Some((a, b)) = common::part_in_band(w[0], w[1], lo, hi) {
            best = best.min(clearance(
                &[[a[0], a[1], 0.0, 0.0], [b[0], b[1], 0.0, 0.0]],
                z,
            ));
        }
    }
    best
}

/// The 3D planners keep the margin from every zone (each a prism: its polygon or circle grown
/// by the margin, its band by the margin): from home to N 400, E -80 at 5 m, whose voxel route
/// without zones crosses the stadium (up to 120 m: no way over it below the ceiling).
#[test]
fn the_3d_planners_keep_out_of_the_zones() {
    let dir = tempfile::tempdir().unwrap();
    let zones_path = data("no-fly-sample.geojson");
    let plain = ok_json(dir.path(), "plan --json --planner voxel --goal-ne 400,-80");
    let zones = zones_of(&zones_path, &plain["home"]);
    assert!(
        (zones.iter()).any(|z| clearance_3d(&rows(&plain), z, 5.0) < 5.0),
        "the route without zones crosses none: the test shows nothing"
    );
    // Every 3D planner of the registry.
    let three_d = (skyplan_plan::PlannerId::ALL.iter()).filter(|p| p.info().dims == 3);
    for planner in three_d.map(|p| p.name()) {
        let v = ok_json(
            dir.path(),
            &format!(
                "plan --json --planner {planner} --goal-ne 400,-80 --time-limit-ms 3000 --no-fly {}",
                zones_path.display()
            ),
        );
        let wps = rows(&v);
        for z in &zones {
            let c = clearance_3d(&wps, z, 5.0);
            assert!(c >= 5.0 - 1e-6, "{planner}: {c} m from zone {}", z.feature);
        }
        assert_eq!(v["no_fly"]["zones"].as_array().map(Vec::len), Some(3));
    }
    // A goal in the stadium is refused naming it.
    fails_with(
        dir.path(),
        &format!(
            "plan --planner rrt-connect --goal-ne 250,-40 --no-fly {}",
            zones_path.display()
        ),
        2,
        &["goal N 250.00 m, E -40.00 m, altitude 5.00 m is within 5 m of no-fly zone 0"],
    );
    // An inclusion boundary is for the 2D planners.
    let fence = common::dir_with(&[(
        "fence.geojson",
        r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
            "properties": {"radius_m": 900, "inclusion": true},
            "geometry": {"type": "Point", "coordinates": [-122.3975, 37.7925]}}]}"#,
    )]);
    fails_with(
        fence.path(),
        "plan --planner rrt-connect --no-fly fence.geojson",
        2,
        &[
            "feature 0 is an inclusion boundary",
            "3D planners keep out of exclusion zones only",
        ],
    );
}

#[test]
fn a_circle_on_a_footprint_map_counts_only_in_its_band() {
    let dir = common::dir_with(&[(
        "circle.geojson",
        r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
            "properties": {"radius_m": 3, "floor_m": 0, "ceiling_m": 30},
            "geometry": {"type": "Point", "coordinates": [-122.3978892, 37.7930556]}}]}"#,
    )]);
    let map = data("footprints-sample.geojson");
    let line = format!("plan --json --map {} --goal-ne 118,-61", map.display());
    let plain = ok_json(dir.path(), &line);
    let v = ok_json(dir.path(), &format!("{line} --no-fly circle.geojson"));
    let zones = zones_of(&dir.path().join("circle.geojson"), &v["home"]);
    assert!(clearance(&rows(&plain), &zones[0]) < 5.0);
    let c = clearance(&rows(&v), &zones[0]);
    assert!(c >= 5.0 - 1e-6, "{c}");
    // At 40 m the 0–30 m zone (grown to 35 m) does not count: the same route as without it.
    let high = format!("{line} --alt-m 40");
    assert_eq!(
        ok_json(dir.path(), &format!("{high} --no-fly circle.geojson"))["waypoints"],
        ok_json(dir.path(), &high)["waypoints"]
    );
}

#[test]
fn bad_zone_files_name_file_feature_and_field() {
    let dir = common::dir_with(&[
        (
            "band.geojson",
            r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
                "properties": {"radius_m": 3, "floor_m": 0},
                "geometry": {"type": "Point", "coordinates": [-122.39, 37.79]}}]}"#,
        ),
        ("text.geojson", "no zones here"),
    ]);
    fails_with(
        dir.path(),
        "plan --no-fly band.geojson",
        2,
        &["band.geojson: feature 0, properties.ceiling_m: missing"],
    );
    fails_with(
        dir.path(),
        "plan --no-fly text.geojson",
        2,
        &["text.geojson: JSON: line 1, column 2: expected ident"],
    );
    fails_with(
        dir.path(),
        "plan --no-fly missing.geojson",
        2,
        &["cannot read missing.geojson"],
    );
    common::assert_no_waypoints(dir.path(), "nothing written on bad input");
}

/// `--out FILE.plan` carries the zones that hold the flight as QGroundControl's geoFence, and
/// `--no-fly FILE.plan` reads them back: the same route as from the GeoJSON.
#[test]
fn a_plan_files_geofence_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let zones_path = data("no-fly-sample.geojson");
    let from_geojson = ok_json(
        dir.path(),
        &format!(
            "plan --json --no-fly {} --out route.plan",
            zones_path.display()
        ),
    );
    let text = std::fs::read_to_string(dir.path().join("route.plan")).unwrap();
    let plan: Value = serde_json::from_str(&text).unwrap();
    let fence = &plan["geoFence"];
    assert_eq!(fence["version"], 2);
    // The stadium circle and the helipad square; the 60–120 m approach path does not hold 5 m.
    assert_eq!(fence["circles"].as_array().map(Vec::len), Some(1));
    assert_eq!(fence["polygons"].as_array().map(Vec::len), Some(1));
    let circle = &fence["circles"][0];
    assert_eq!(circle["inclusion"], false);
    assert_eq!(circle["circle"]["radius"], 30.0);
    assert_eq!(circle["circle"]["center"][0], 37.7947324); // [lat, lon]
    assert_eq!(
        fence["polygons"][0]["polygon"].as_array().map(Vec::len),
        Some(4)
    );
    let geo = parse_no_fly(&std::fs::read_to_string(&zones_path).unwrap()).unwrap();
    let back = parse_no_fly(&text).unwrap();
    assert_eq!(back.zones[0].shape, geo.zones[1].shape);
    assert_eq!(back.zones[1].shape, geo.zones[0].shape);
    let from_plan = ok_json(dir.path(), "plan --json --no-fly route.plan");
    assert_eq!(from_plan["waypoints"], from_geojson["waypoints"]);
}

#[test]
fn the_plot_draws_and_labels_every_zone_with_its_band() {
    let dir = tempfile::tempdir().unwrap();
    let zones_path = data("no-fly-sample.geojson");
    common::succeed(
        dir.path(),
        &format!("plan --no-fly {} --plot zones.svg", zones_path.display()),
    );
    let svg = std::fs::read_to_string(dir.path().join("zones.svg")).unwrap();
    // Each zone's label, the one the route flies below included; the hatching in the zones' red.
    for label in ["zone 0, 0–120 m", "zone 1, 0–120 m", "zone 2, 60–120 m"] {
        assert!(svg.contains(label), "{label:?} not in the picture");
    }
    assert!(svg.contains("#D62828"), "no zone red in the picture");
}

/// An exclusion polygon with a hole, around home (the hole holds the route) and away from it:
/// a `.plan` fence cannot carry holes, so the first is refused before anything is written (the
/// vehicle's fence would forbid the route) and the second exports the outer ring and says so.
#[test]
fn a_plan_file_refuses_a_fence_whose_dropped_hole_holds_the_route() {
    let ring = |lat0: f64, lon0: f64, half_deg: f64| {
        let c = [
            [lon0 - half_deg, lat0 - half_deg],
            [lon0 + half_deg, lat0 - half_deg],
            [lon0 + half_deg, lat0 + half_deg],
            [lon0 - half_deg, lat0 + half_deg],
            [lon0 - half_deg, lat0 - half_deg],
        ];
        serde_json::to_string(&c).unwrap()
    };
    let zone = |lat0: f64, lon0: f64| {
        format!(
            r#"{{"type": "FeatureCollection", "features": [{{"type": "Feature", "properties": {{"floor_m": 0, "ceiling_m": 50}},
            "geometry": {{"type": "Polygon", "coordinates": [{}, {}]}}}}]}}"#,
            ring(lat0, lon0, 0.003),
            ring(lat0, lon0, 0.001)
        )
    };
    // Around home (37.792480, -122.397450): the route stays in the hole.
    let dir = common::dir_with(&[
        ("around.geojson", &zone(37.79248, -122.39745)),
        ("away.geojson", &zone(37.80248, -122.39745)),
    ]);
    let line = "plan --no-fly around.geojson --goal-ne 20,-20 --out route.plan";
    fails_with(
        dir.path(),
        line,
        2,
        &[
            "the .plan file's geoFence: zone 0 is an exclusion polygon with holes, which a fence cannot carry, and the route flies through its hole 1",
        ],
    );
    assert!(!dir.path().join("route.plan").exists(), "nothing written");
    // The same zones with a JSON waypoint file: no fence, no refusal.
    ok_json(
        dir.path(),
        "plan --json --no-fly around.geojson --goal-ne 20,-20 --out route.json",
    );
    // A holed zone the route keeps out of: its outer ring goes in the fence, and the summary
    // says what is lost.
    let out = common::succeed(
        dir.path(),
        "plan --no-fly away.geojson --goal-ne 20,-20 --out away.plan",
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("geofence   zone 0: exclusion polygon of 4 vertices")
            && text.contains("its 1 hole(s)"),
        "{text}"
    );
    let plan: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("away.plan")).unwrap())
            .unwrap();
    let polygons = plan["geoFence"]["polygons"].as_array().unwrap();
    assert_eq!(polygons.len(), 1);
    assert_eq!(polygons[0]["inclusion"], false);
    assert_eq!(
        polygons[0]["polygon"][0],
        serde_json::json!([37.79948, -122.40045])
    );
}

/// The sample zones with the helipad's (feature 1) window replaced by `start`, `end`.
/// The default route's waypoints without zones.
fn early_plain_waypoints(dir: &Path) -> Value {
    ok_json(dir, "plan --json")["waypoints"].clone()
}

fn with_helipad_window(start: &str, end: &str) -> String {
    let text = std::fs::read_to_string(data("no-fly-sample.geojson")).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    let props = &mut v["features"][1]["properties"];
    props["start"] = start.into();
    props["end"] = end.into();
    v.to_string()
}

#[test]
fn a_departure_applies_only_the_zones_active_during_the_flight() {
    let dir = tempfile::tempdir().unwrap();
    let zones_path = data("no-fly-sample.geojson");
    let plan = |zones: &Path, departure: &str| {
        ok_json(
            dir.path(),
            &format!(
                "plan --json --no-fly {} --departure {departure}",
                zones.display()
            ),
        )
    };
    // The helipad (feature 1) is closed 08:00 to 20:00 on 2026-12-03.
    let early = plan(&zones_path, "2026-12-03T07:00:00Z");
    let zones = zones_of(&zones_path, &early["home"]);
    let (stadium, helipad) = (&zones[0], &zones[1]);
    assert_eq!(early["no_fly"]["outside_window"], serde_json::json!([1]));
    assert!(
        clearance(&rows(&early), helipad) < 5.0,
        "crosses the open helipad"
    );
    assert!(clearance(&rows(&early), stadium) >= 5.0 - 1e-6);
    let (dep, arrival) = (
        early["no_fly"]["departure"].as_str().unwrap().to_string(),
        early["no_fly"]["latest_arrival"]
            .as_str()
            .unwrap()
            .to_string(),
    );
    assert_eq!(dep, "2026-12-03T07:00:00Z");
    // The latest arrival bounds the flight: at least its length at 10 m/s.
    let window_s = skyplan_map::nofly::parse_rfc3339(&arrival).unwrap()
        - skyplan_map::nofly::parse_rfc3339(&dep).unwrap();
    let length_m = early["mission_length_m"].as_f64().unwrap();
    assert!(window_s as f64 > length_m / 10.0 + 60.0, "{window_s} s");
    for departure in [
        "2026-12-03T07:58:00Z",
        "2026-12-03T12:00:00Z",
        "2026-12-03T19:59:00Z",
    ] {
        let v = plan(&zones_path, departure);
        assert_eq!(v["no_fly"]["outside_window"], serde_json::json!([]));
        for z in [stadium, helipad] {
            assert!(clearance(&rows(&v), z) >= 5.0 - 1e-6, "{departure}");
        }
    }
    let late = plan(&zones_path, "2026-12-03T20:00:00Z");
    assert_eq!(late["waypoints"], early["waypoints"]);
    // At the edge of the window: a zone opening one second before the latest arrival applies,
    // one opening one second after does not.
    let second = |s: i64| {
        skyplan_map::nofly::rfc3339_from_unix_s(
            skyplan_map::nofly::parse_rfc3339(&arrival).unwrap() + s,
        )
    };
    for (opens, applies) in [(second(-1), true), (second(1), false)] {
        let path = dir.path().join("timed.geojson");
        std::fs::write(&path, with_helipad_window(&opens, "2026-12-04T00:00:00Z")).unwrap();
        let v = plan(&path, &dep);
        assert_eq!(
            clearance(&rows(&v), helipad) >= 5.0 - 1e-6,
            applies,
            "{opens}"
        );
        if !applies {
            assert_eq!(v["no_fly"]["latest_arrival"], arrival.as_str());
        }
    }
    // A zone over the goal that opens hours after the departure does not stop the flight (it
    // made every route fail before); while it is open the goal is in it.
    let over_goal = common::dir_with(&[(
        "goal.geojson",
        r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
            "properties": {"radius_m": 40, "floor_m": 0, "ceiling_m": 120,
                           "start": "2026-12-03T10:00:00Z", "end": "2026-12-03T12:00:00Z"},
            "geometry": {"type": "Point", "coordinates": [-122.39298968, 37.79624260]}}]}"#,
    )]);
    let v = ok_json(
        over_goal.path(),
        "plan --json --no-fly goal.geojson --departure 2026-12-03T07:00:00Z",
    );
    assert_eq!(v["no_fly"]["outside_window"], serde_json::json!([0]));
    assert_eq!(v["waypoints"], early_plain_waypoints(dir.path()));
    fails_with(
        over_goal.path(),
        "plan --no-fly goal.geojson --departure 2026-12-03T10:30:00Z",
        2,
        &[
            "goal N 420.00 m, E 390.00 m",
            "inside an obstacle or its 5 m safety margin",
        ],
    );
    // Without a departure the helipad applies whatever its times, and the summary says so.
    let out = succeed(
        dir.path(),
        &format!("plan --no-fly {}", zones_path.display()),
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("no-fly     3 zones: 2 apply; not at this altitude: feature 2; timed, counted as active at every time"),
        "{text}"
    );
}

#[test]
fn a_bad_departure_or_one_without_zones_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let zones = data("no-fly-sample.geojson");
    fails_with(
        dir.path(),
        &format!(
            "plan --no-fly {} --departure 2026-13-01T00:00:00Z",
            zones.display()
        ),
        2,
        &["departure \"2026-13-01T00:00:00Z\": expected an RFC 3339 time"],
    );
    fails_with(
        dir.path(),
        "plan --departure 2026-12-03T07:00:00Z",
        2,
        &["departure is used only with no-fly zones (--no-fly)"],
    );
    fails_with(
        dir.path(),
        &format!(
            "fly --sim --no-fly {} --departure 2026-12-03T07:00:00Z",
            zones.display()
        ),
        2,
        &["--departure: fly takes off now"],
    );
}

/// The flown track of a `fly --log` CSV as waypoint rows (north, east, altitude, 0).
fn track(log: &Path) -> Vec<[f64; 4]> {
    let text = std::fs::read_to_string(log).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (n, e, a) = (col("north_m"), col("east_m"), col("alt_m"));
    lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .map(|f| {
            [
                f[n].parse().unwrap(),
                f[e].parse().unwrap(),
                f[a].parse().unwrap(),
                0.0,
            ]
        })
        .collect()
}

#[test]
fn a_flight_replanned_around_hidden_buildings_keeps_out_of_the_zones() {
    // Seed 1's hidden buildings send the replanned route straight through the stadium and the
    // helipad when the replanner does not know the zones.
    let dir = tempfile::tempdir().unwrap();
    let zones_path = data("no-fly-sample.geojson");
    let out = succeed(
        dir.path(),
        &format!(
            "fly --sim --speedup 20 --no-fly {} --hidden-random 3 --seed 1 --log track.csv",
            zones_path.display()
        ),
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("landed and disarmed after reaching all"),
        "{text}"
    );
    let replans: usize = text
        .lines()
        .find_map(|l| l.strip_prefix("replans"))
        .and_then(|l| l.split_whitespace().next()?.parse().ok())
        .unwrap_or(0);
    assert!(replans >= 1, "{text}");
    // The flight's own account of the zones agrees with the distances computed here.
    let said: f64 = text
        .lines()
        .find_map(|l| l.strip_prefix("no-fly     closest "))
        .and_then(|l| l.split_whitespace().next()?.parse().ok())
        .unwrap_or_else(|| panic!("no no-fly line in {text}"));
    let plan = ok_json(
        dir.path(),
        &format!("plan --json --no-fly {}", zones_path.display()),
    );
    let flown = track(&dir.path().join("track.csv"));
    let mut closest = f64::INFINITY;
    for z in zones_of(&zones_path, &plan["home"])
        .iter()
        .filter(|z| z.meets_altitude(5.0, 5.0))
    {
        // The margin less the vehicle's tracking error.
        let c = clearance(&flown, z);
        assert!(c >= 4.0, "zone {}: {c:.2} m", z.feature);
        closest = closest.min(c);
    }
    // The log's positions are rounded to millimetres.
    assert!(
        (said - closest).abs() < 0.01,
        "said {said} m, measured {closest} m"
    );
}
