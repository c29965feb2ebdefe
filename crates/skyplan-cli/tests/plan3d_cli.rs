//! `skyplan plan --planner prm|rrt-connect|rrt-star`: the real binary; every returned segment is
//! re-checked here against every box with the brute-force checker.

use assert_cmd::Command;
use serde_json::Value;
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, Neu, WorldSpec, path_length_m};
use std::path::Path;

const CITY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/colliders.csv");
const PLANNERS: [&str; 3] = ["prm", "rrt-connect", "rrt-star"];

fn skyplan(dir: &Path) -> Command {
    let mut cmd = Command::cargo_bin("skyplan").unwrap();
    cmd.current_dir(dir);
    cmd
}

/// Runs `plan --json …`; returns the exit code and the JSON object on stdout.
fn run(dir: &Path, args: &[&str]) -> (i32, Value) {
    let out = skyplan(dir)
        .arg("plan")
        .arg("--json")
        .args(args)
        .output()
        .unwrap();
    let code = out.status.code().unwrap_or(-1);
    let v = serde_json::from_slice(&out.stdout).unwrap_or_else(|_| {
        panic!(
            "stdout is not JSON; stderr: {}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    (code, v)
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// Re-checks a JSON answer: the path starts and ends where asked and every segment is free
/// against every box grown by `safety_m`, inside the reported flight volume.
fn check(map_text: &str, v: &Value, safety_m: f64, start: Neu, goal: Neu) {
    assert_eq!(v["status"], "ok", "{v}");
    assert_eq!(v["planner_status"], "exact");
    let rows: Vec<[f64; 4]> = serde_json::from_value(v["waypoints"].clone()).unwrap();
    let path: Vec<Neu> = rows.iter().map(|r| [r[0], r[1], r[2]]).collect();
    assert!(path.len() >= 2);
    assert_eq!(path[0], start);
    assert_eq!(*path.last().unwrap(), goal);
    let vol = &v["flight_volume"];
    let corner = |c: &Value| -> Neu { [num(&c[0]), num(&c[1]), num(&c[2])] };
    let bounds = Aabb {
        min: corner(&vol["min"]),
        max: corner(&vol["max"]),
    };
    assert_eq!(bounds.min[2], 0.0, "the ground is the floor");
    let map = skyplan_map::colliders::parse_colliders(map_text).unwrap();
    let spec = WorldSpec {
        safety_m,
        min_alt_m: 0.0,
        max_alt_m: bounds.max[2],
        margin_bounds_m: 0.0,
    };
    let world = BoxWorld3::with_bounds(&map.boxes, &spec, bounds).unwrap();
    let bf = world.brute_force();
    for (k, w) in path.windows(2).enumerate() {
        assert!(
            bf.segment_is_free(w[0], w[1]),
            "segment {k} {:?} → {:?} is not free",
            w[0],
            w[1]
        );
    }
    let cost = num(&v["cost_m"]);
    assert!(
        (cost - path_length_m(&path)).abs() < 1e-6,
        "cost {cost} vs {}",
        path_length_m(&path)
    );
    assert!(cost + 1e-9 >= num(&v["straight_line_m"]));
}

#[test]
fn every_3d_planner_returns_an_exactly_free_path_on_the_city() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(CITY).unwrap();
    for planner in PLANNERS {
        // Climb from 5 m at the home to 40 m across the city.
        let (code, v) = run(
            dir.path(),
            &[
                "--planner",
                planner,
                "--goal-alt-m",
                "40",
                "--seed",
                "3",
                "--time-limit-ms",
                "400",
            ],
        );
        assert_eq!(code, 0, "{planner}: {v}");
        check(&text, &v, 5.0, [0.0, 0.0, 5.0], [420.0, 390.0, 40.0]);
        // Low ceiling: the route must weave between the buildings at 0–15 m.
        let (code, v) = run(
            dir.path(),
            &[
                "--planner",
                planner,
                "--max-alt-m",
                "15",
                "--start-ne",
                "0,0",
                "--goal-ne",
                "420,390",
                "--seed",
                "5",
                "--time-limit-ms",
                "3000",
                "--out",
                "route.csv",
            ],
        );
        assert_eq!(code, 0, "{planner}: {v}");
        check(&text, &v, 5.0, [0.0, 0.0, 5.0], [420.0, 390.0, 5.0]);
        assert!(dir.path().join("route.csv").exists());
        assert!(
            num(&v["cost_m"]) > num(&v["straight_line_m"]),
            "{planner}: the street route is longer than the line"
        );
    }
}

#[test]
fn same_seed_same_route() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "--planner",
        "prm",
        "--goal-alt-m",
        "20",
        "--seed",
        "11",
        "--out",
        "a.json",
    ];
    let (_, a) = run(dir.path(), &args);
    let (_, b) = run(dir.path(), &args);
    assert_eq!(a["waypoints"], b["waypoints"]);
}

#[test]
fn goal_in_a_building_is_bad_input_and_an_enclosed_goal_is_no_path() {
    let dir = tempfile::tempdir().unwrap();
    // The bundled map has a box at N −310.2, E −439.2 rising to 171 m.
    let (code, v) = run(
        dir.path(),
        &[
            "--planner",
            "rrt-connect",
            "--goal-ne",
            "-310.2389,-439.2315",
            "--goal-alt-m",
            "20",
        ],
    );
    assert_eq!(code, 2, "{v}");
    assert_eq!(v["status"], "bad_input");
    // A closed hollow cube around (50, 50, 20): the goal inside is free but unreachable.
    let mut text = String::from(
        "lat0 37.792480, lon0 -122.397450\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n",
    );
    for (dn, de, du, hn, he, hu) in [
        (-8.0, 0.0, 0.0, 1.0, 9.0, 9.0),
        (8.0, 0.0, 0.0, 1.0, 9.0, 9.0),
        (0.0, -8.0, 0.0, 9.0, 1.0, 9.0),
        (0.0, 8.0, 0.0, 9.0, 1.0, 9.0),
        (0.0, 0.0, -8.0, 9.0, 9.0, 1.0),
        (0.0, 0.0, 8.0, 9.0, 9.0, 1.0),
        (-50.0, -50.0, 5.0, 1.0, 1.0, 5.0),
        (150.0, 150.0, 5.0, 1.0, 1.0, 5.0),
    ] {
        text.push_str(&format!(
            "{},{},{},{hn},{he},{hu}\n",
            50.0 + dn,
            50.0 + de,
            20.0 + du
        ));
    }
    std::fs::write(dir.path().join("cage.csv"), text).unwrap();
    for planner in PLANNERS {
        let (code, v) = run(
            dir.path(),
            &[
                "--planner",
                planner,
                "--map",
                "cage.csv",
                "--safety-m",
                "0",
                "--start-ne",
                "0,0",
                "--goal-ne",
                "50,50",
                "--goal-alt-m",
                "20",
                "--time-limit-ms",
                "150",
            ],
        );
        assert_eq!(code, 3, "{planner}: {v}");
        assert_eq!(v["status"], "no_path");
        assert!(
            !dir.path().join("waypoints.json").exists(),
            "nothing written on failure"
        );
    }
}

#[test]
fn three_d_options_need_a_three_d_planner() {
    let dir = tempfile::tempdir().unwrap();
    let (code, v) = run(dir.path(), &["--goal-alt-m", "30"]);
    assert_eq!(code, 2);
    assert!(v["error"].as_str().unwrap().contains("3D planner"), "{v}");
}
