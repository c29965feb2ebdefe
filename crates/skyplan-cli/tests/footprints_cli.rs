//! `skyplan plan --map FILE.geojson`: building footprints planned on with the grid planners, the
//! route checked against the grid rasterised here from the same file, against the exact
//! Dijkstra optimum, and against the polygons themselves (every flown point at least the margin
//! from every footprint whose band holds the altitude).

use serde_json::Value;
use skyplan_cspace::{Cell, Grid2, GridSpec, Touch};
use skyplan_map::colliders::GeodeticHome;
use skyplan_map::footprints::{DEFAULT_HEIGHT_M, FootprintMap, parse_geojson};
use skyplan_search::MoveModel;
use skyplan_search::oracle::dijkstra_exact;
use std::path::{Path, PathBuf};
mod common;
use common::{fails_with, ok_json, rows, run_args};
use skyplan_testkit::distance_to_segment;

const SAMPLE: &str = include_str!("../../../data/footprints-sample.geojson");

fn sample_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/footprints-sample.geojson")
}

fn sample_map(home: Option<GeodeticHome>) -> FootprintMap {
    parse_geojson(SAMPLE, DEFAULT_HEIGHT_M)
        .unwrap()
        .project(home)
        .unwrap()
}

fn cell(p: &Value) -> Cell {
    Cell::new(
        p["cell"][0].as_u64().unwrap() as u32,
        p["cell"][1].as_u64().unwrap() as u32,
    )
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Distance between two segments (0 when they cross).
fn segment_segment(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    if orient(a, b, c) * orient(a, b, d) <= 0.0 && orient(c, d, a) * orient(c, d, b) <= 0.0 {
        return 0.0;
    }
    distance_to_segment(a, c, d)
        .min(distance_to_segment(b, c, d))
        .min(distance_to_segment(c, a, b))
        .min(distance_to_segment(d, a, b))
}

/// Even-odd inside test of a point in a polygon with holes.
fn inside(p: [f64; 2], rings: &[Vec<[f64; 2]>]) -> bool {
    let mut odd = false;
    for ring in rings {
        for k in 0..ring.len() {
            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
            if (a[0] <= p[0]) != (b[0] <= p[0])
                && p[1] < a[1] + (p[0] - a[0]) / (b[0] - a[0]) * (b[1] - a[1])
            {
                odd = !odd;
            }
        }
    }
    odd
}

/// The smallest distance from the route's segments to the footprints whose band holds the
/// altitude (0 if the route enters one).
fn clearance_m(map: &FootprintMap, wps: &[[f64; 4]], alt_m: f64, margin_m: f64) -> f64 {
    let mut best = f64::INFINITY;
    for f in map
        .footprints
        .iter()
        .filter(|f| f.meets_altitude(alt_m, margin_m))
    {
        for w in wps.windows(2) {
            best = best.min(polygon_clearance_m(
                &f.rings,
                [w[0][0], w[0][1]],
                [w[1][0], w[1][1]],
            ));
        }
    }
    best
}

/// The distance from the segment `a`–`b` to the polygon (0 if it enters it).
fn polygon_clearance_m(rings: &[Vec<[f64; 2]>], a: [f64; 2], b: [f64; 2]) -> f64 {
    if inside(a, rings) {
        return 0.0;
    }
    let mut best = f64::INFINITY;
    for ring in rings {
        for k in 0..ring.len() {
            best = best.min(segment_segment(a, b, ring[k], ring[(k + 1) % ring.len()]));
        }
    }
    best
}

#[test]
fn grid_planners_plan_on_footprints_keeping_the_margin() {
    let dir = tempfile::tempdir().unwrap();
    let map_arg = sample_path();
    let map_arg = map_arg.display();
    let map = sample_map(None);
    assert_eq!(map.footprints.len(), 42); // 36 buildings, 6 of them two-winged
    assert_eq!(map.default_heights, 9);
    for (planner, alt_m, margin_m) in [("jps", 5.0, 5.0), ("astar", 25.0, 3.0), ("theta", 5.0, 5.0)]
    {
        let v = ok_json(
            dir.path(),
            &format!(
                "plan --json --map {map_arg} --planner {planner} --alt-m {alt_m} --safety-m {margin_m} --goal-ne 118,-61"
            ),
        );
        assert_eq!(v["status"], "ok");
        assert_eq!(v["obstacles"], 42);
        let spec = GridSpec {
            alt_m,
            safety_m: margin_m,
            cell_m: 1.0,
        };
        let grid = Grid2::from_footprints(&map, spec).unwrap();
        assert_eq!(v["grid"]["rows"], grid.rows());
        assert_eq!(v["grid"]["blocked_cells"], grid.blocked_count());
        let wps = rows(&v);
        assert_eq!(
            (wps[0][0], wps[0][1]),
            (0.0, 0.0),
            "{planner}: starts at home"
        );
        let last = wps[wps.len() - 1];
        assert_eq!((last[0], last[1]), (118.0, -61.0));
        for w in wps.windows(2) {
            assert!(
                grid.segment_is_free_ne((w[0][0], w[0][1]), (w[1][0], w[1][1]), Touch::Closed),
                "{planner}: {w:?}"
            );
        }
        let clearance = clearance_m(&map, &wps, alt_m, margin_m);
        assert!(
            clearance >= margin_m,
            "{planner}: the route comes {clearance} m from a footprint"
        );
        if planner != "theta" {
            let truth = dijkstra_exact(
                &grid,
                cell(&v["start"]),
                cell(&v["goal"]),
                MoveModel::Octile,
            )
            .unwrap();
            assert_eq!(v["cost_m"].as_f64().unwrap(), truth.to_f64(), "{planner}");
        }
    }
}

/// The smallest distance from the route's 3D segments to the footprint prisms, each taken
/// with its band grown by the margin (0 if the route enters one): the part of a segment within
/// a prism's grown band is measured against its polygon.
fn clearance_3d_m(map: &FootprintMap, wps: &[[f64; 4]], margin_m: f64) -> f64 {
    let mut best = f64::INFINITY;
    for f in &map.footprints {
        let (lo, hi) = (f.min_height_m - margin_m, f.height_m + margin_m);
        for w in wps.windows(2) {
            if let Some((a, b)) = common::part_in_band(w[0], w[1], lo, hi) {
                best = best.min(polygon_clearance_m(&f.rings, a, b));
            }
        }
    }
    best
}

#[test]
fn three_d_planners_and_voronoi_plan_on_footprints() {
    let dir = tempfile::tempdir().unwrap();
    let map_arg = sample_path();
    let map_arg = map_arg.display();
    let map = sample_map(None);
    // Every planner that needs a map of obstacles (the registry's), on footprints.
    let planners = skyplan_plan::PlannerId::ALL
        .iter()
        .filter(|p| p.info().maps == skyplan_plan::MapKinds::Obstacles);
    for p in planners {
        let planner = p.name();
        let v = ok_json(
            dir.path(),
            &format!(
                "plan --json --map {map_arg} --planner {planner} --safety-m 4 --goal-ne 118,-61{}",
                if p.info().dims == 2 {
                    ""
                } else {
                    " --time-limit-ms 3000"
                }
            ),
        );
        assert_eq!(v["status"], "ok", "{planner}");
        let wps = rows(&v);
        let last = wps[wps.len() - 1];
        assert_eq!(
            (wps[0][0], wps[0][1], last[0], last[1]),
            (0.0, 0.0, 118.0, -61.0)
        );
        let clearance = clearance_3d_m(&map, &wps, 4.0);
        assert!(
            clearance >= 4.0 - 1e-9,
            "{planner}: the route comes {clearance} m from a footprint"
        );
        // Not the straight line: a building stands in the way at 5 m.
        assert!(
            v["cost_m"].as_f64().unwrap() > 118f64.hypot(61.0) + 1.0,
            "{planner}"
        );
    }
}

/// `fly --sim` on a footprint map with a hidden pole on the last leg: the replanner learns it
/// from the simulated sensor and flies around it; the flight log's track keeps more than half
/// the margin from every building whose band holds its altitude (measured here from the
/// polygons), and from the pole; the RTL altitude clears the tallest building under a straight
/// way home.
#[test]
fn fly_replans_on_a_footprint_map() {
    let dir = tempfile::tempdir().unwrap();
    let map = sample_map(None);
    let home = map.home;
    std::fs::write(
        dir.path().join("pole.csv"),
        format!(
            "lat0 {}, lon0 {}\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n95,-61,10,2,2,10\n",
            home.lat_deg, home.lon_deg
        ),
    )
    .unwrap();
    let map_arg = sample_path();
    let r = run_args(
        dir.path(),
        &[
            "fly",
            "--sim",
            "--speedup",
            "20",
            "--map",
            &map_arg.display().to_string(),
            "--goal-ne",
            "118,-61",
            "--hidden",
            "pole.csv",
            "--log",
            "flight.csv",
        ],
    );
    r.expect_code(0);
    for needle in [
        ": 42 obstacles",
        "result     landed and disarmed after reaching all",
        "no collision with the map's obstacles or the hidden building",
    ] {
        assert!(r.stdout.contains(needle), "{needle} in {}", r.stdout);
    }
    let replans: usize = (r.stdout.lines())
        .find_map(|l| l.strip_prefix("replans    "))
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{}", r.stdout));
    assert!(replans >= 1, "{}", r.stdout);
    let log = std::fs::read_to_string(dir.path().join("flight.csv")).unwrap();
    let mut lines = log.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (n, e, a) = (col("north_m"), col("east_m"), col("alt_m"));
    let (mut airborne, mut closest) = (0, f64::INFINITY);
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let p = [f[n].parse::<f64>().unwrap(), f[e].parse::<f64>().unwrap()];
        let alt: f64 = f[a].parse().unwrap();
        if alt < 1.0 {
            continue;
        }
        airborne += 1;
        for fp in map
            .footprints
            .iter()
            .filter(|fp| fp.meets_altitude(alt, 0.0))
        {
            closest = closest.min(polygon_clearance_m(&fp.rings, p, p));
        }
        let pole =
            (((p[0] - 95.0).abs() - 2.0).max(0.0)).hypot(((p[1] + 61.0).abs() - 2.0).max(0.0));
        closest = closest.min(pole);
    }
    assert!(airborne > 100, "{airborne} airborne rows");
    assert!(
        closest > 2.5,
        "the track came {closest} m from a building or the pole"
    );
    let rtl: f64 = (r.stdout.lines())
        .find_map(|l| l.split("RTL altitude of at least ").nth(1))
        .and_then(|l| l.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{}", r.stdout));
    // The building named sets it: its top plus the margin.
    let feature: usize = (r.stdout.lines())
        .find_map(|l| l.split("passes over the building of feature ").nth(1))
        .and_then(|l| l.split(':').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{}", r.stdout));
    let top = (map.footprints.iter())
        .find(|f| f.feature == feature)
        .map(|f| f.height_m)
        .unwrap();
    assert!(
        (rtl - (top + 5.0)).abs() < 0.006,
        "{rtl} vs feature {feature}'s top {top}"
    );
    // The closest building is named by its feature too.
    assert!(
        r.stdout.contains("(the building of feature "),
        "{}",
        r.stdout
    );
}

/// `--hidden-random` on a footprint map: the buildings placed keep the goal reachable on the
/// footprints' grid, and the flight replans around them without touching any.
#[test]
fn fly_around_random_hidden_buildings_on_a_footprint_map() {
    let dir = tempfile::tempdir().unwrap();
    let map_arg = sample_path().display().to_string();
    let r = run_args(
        dir.path(),
        &[
            "fly",
            "--sim",
            "--speedup",
            "50",
            "--map",
            &map_arg,
            "--goal-ne",
            "118,-61",
            "--hidden-random",
            "2",
            "--seed",
            "3",
        ],
    );
    r.expect_code(0);
    for needle in [
        "hidden     2 buildings on or near the route (seed 3)",
        "no collision with the map's obstacles or the 2 hidden buildings",
    ] {
        assert!(r.stdout.contains(needle), "{needle} in {}", r.stdout);
    }
    assert!(!r.stdout.contains("replans    0 "), "{}", r.stdout);
}

/// The Euclidean-shortest route among polygons grown by a margin, by shapely: a visibility
/// graph over the vertices of the footprints buffered by the margin (inscribed arcs: obstacles
/// a little smaller than the true grown ones, so its length is a lower bound of the exact
/// optimum) and the ends, an edge kept when it does not meet the grown union shrunk by 1 cm;
/// Dijkstra over it. Input JSON `{margin, polys: [[outer, hole, …], …], start, goal}` in
/// (east, north); prints the length.
const VISIBILITY: &str = r#"
import heapq, json, sys
import numpy as np
import shapely
from shapely.geometry import Polygon
d = json.load(sys.stdin)
m = d["margin"]
grown = shapely.union_all([Polygon(p[0], p[1:]).buffer(m, quad_segs=4) for p in d["polys"]])
inner = grown.buffer(-0.01)
shapely.prepare(inner)
start, goal = tuple(d["start"]), tuple(d["goal"])
lo = np.minimum(start, goal) - 100.0
hi = np.maximum(start, goal) + 100.0
pts = [start, goal]
for g in getattr(grown, "geoms", [grown]):
    for ring in [g.exterior, *g.interiors]:
        for c in ring.coords[:-1]:
            if np.all(np.asarray(c) >= lo) and np.all(np.asarray(c) <= hi):
                pts.append(tuple(c))
P = np.array(pts)
n = len(P)
i, j = np.triu_indices(n, 1)
lines = shapely.linestrings(np.stack([P[i], P[j]], axis=1))
ok = ~shapely.intersects(lines, inner)
adj = [[] for _ in range(n)]
for a, b in zip(i[ok], j[ok]):
    w = float(np.hypot(*(P[a] - P[b])))
    adj[a].append((b, w))
    adj[b].append((a, w))
dist = [float("inf")] * n
dist[0] = 0.0
q = [(0.0, 0)]
while q:
    du, u = heapq.heappop(q)
    if du > dist[u]:
        continue
    for v, w in adj[u]:
        if du + w < dist[v]:
            dist[v] = du + w
            heapq.heappush(q, (du + w, v))
print(json.dumps(dist[1]))
"#;

/// The any-angle route on a footprint map is within 3 % of the exact Euclidean optimum among
/// the footprints grown by the margin (and never shorter than shapely's lower bound of it).
#[test]
#[ignore = "needs SKYPLAN_PYTHON with shapely (.ci/run's virtual environment has it)"]
fn any_angle_is_within_3_percent_of_the_euclidean_optimum() {
    let dir = tempfile::tempdir().unwrap();
    let map = sample_map(None);
    let map_arg = sample_path().display().to_string();
    for (goal, alt_m, margin_m) in [
        ([118.0, -61.0], 5.0, 5.0),
        ([-155.5, 138.5], 5.0, 3.0),
        ([-130.0, -120.0], 25.0, 5.0),
        ([130.0, 150.0], 5.0, 3.0),
    ] {
        let v = ok_json(
            dir.path(),
            &format!(
                "plan --json --map {map_arg} --planner any-angle --alt-m {alt_m} --safety-m {margin_m} --goal-ne {},{}",
                goal[0], goal[1]
            ),
        );
        let ours = v["cost_m"].as_f64().unwrap();
        let en = |p: [f64; 2]| serde_json::json!([p[1], p[0]]);
        let polys: Vec<Value> = (map.footprints.iter())
            .filter(|f| f.meets_altitude(alt_m, margin_m))
            .map(|f| {
                Value::from(
                    (f.rings.iter())
                        .map(|r| Value::from(r.iter().map(|p| en(*p)).collect::<Vec<_>>()))
                        .collect::<Vec<_>>(),
                )
            })
            .collect();
        let input = serde_json::json!({
            "margin": margin_m, "polys": polys, "start": en([0.0, 0.0]), "goal": en(goal),
        });
        let mut child = std::process::Command::new(common::python())
            .args(["-c", VISIBILITY])
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .expect("python with shapely (set SKYPLAN_PYTHON)");
        std::io::Write::write_all(
            &mut child.stdin.take().unwrap(),
            input.to_string().as_bytes(),
        )
        .unwrap();
        let out = child.wait_with_output().unwrap();
        assert!(out.status.success(), "the shapely script failed");
        let bound: f64 = String::from_utf8(out.stdout)
            .unwrap()
            .trim()
            .parse()
            .unwrap();
        eprintln!(
            "goal {goal:?} at {alt_m} m, margin {margin_m} m: any-angle {ours:.2} m, shapely's bound {bound:.2} m"
        );
        assert!(ours >= bound - 1e-6, "{ours} below the lower bound {bound}");
        assert!(ours <= 1.03 * bound, "{ours} more than 3 % over {bound}");
    }
}

/// `skyplan sim --map FILE.geojson` in its own process: the vehicle starts at the footprints'
/// home (the data's centre, as `fly` places it), and `fly --connect` with the same map lands
/// at the goal without meeting a building.
#[test]
fn a_separate_sim_takes_a_footprint_map() {
    let map_arg = sample_path().display().to_string();
    let sim =
        common::SimProcess::start(&["--map", &map_arg, "--speedup", "20", "--duration-s", "120"]);
    let dir = tempfile::tempdir().unwrap();
    let r = run_args(
        dir.path(),
        &[
            "fly",
            "--connect",
            &sim.address,
            "--speedup",
            "20",
            "--map",
            &map_arg,
            "--goal-ne",
            "118,-61",
            "--timeout-s",
            "60",
        ],
    );
    r.expect_code(0);
    assert!(
        r.stdout
            .contains("result     landed and disarmed after reaching all"),
        "{}",
        r.stdout
    );
    // The vehicle was where the map's home is: the plan starts there.
    assert!(r.stdout.contains("plan       jps: N 0.0"), "{}", r.stdout);
}

#[test]
fn home_moves_the_frame() {
    let dir = tempfile::tempdir().unwrap();
    let map_arg = sample_path();
    let map_arg = map_arg.display();
    // The FCND home, a few metres south-west of the data's centre: the same street corners,
    // given as lat/lon, planned in the frame about the new home.
    let v = ok_json(
        dir.path(),
        &format!(
            "plan --json --map {map_arg} --home 37.7925,-122.3975 --start-lla 37.79255,-122.39745 --goal-lla 37.79361,-122.39814"
        ),
    );
    assert_eq!(v["home"]["lat_deg"], 37.7925);
    assert_eq!(v["home"]["lon_deg"], -122.3975);
    let moved = sample_map(Some(GeodeticHome {
        lat_deg: 37.7925,
        lon_deg: -122.3975,
    }));
    let grid = Grid2::from_footprints(&moved, GridSpec::default()).unwrap();
    assert_eq!(v["grid"]["blocked_cells"], grid.blocked_count());
    let wps = rows(&v);
    assert!(clearance_m(&moved, &wps, 5.0, 5.0) >= 5.0);
}

#[test]
fn bad_geojson_names_file_feature_and_field() {
    let dir = common::dir_with(&[(
        "bad.geojson",
        r#"{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {},
            "geometry": {"type": "Polygon", "coordinates": [[[37.79, -122.39], [37.8, -122.39], [37.8, -122.38], [37.79, -122.39]]]}}]}"#,
    )]);
    fails_with(
        dir.path(),
        "plan --map bad.geojson",
        2,
        &[
            "bad.geojson: feature 0, geometry.coordinates[0][0]",
            "swapped",
        ],
    );
}
