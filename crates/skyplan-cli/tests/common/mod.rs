//! Helpers shared by the CLI tests: running the binary, reading its JSON, and the independent
//! exact re-check of 3D routes against every box.
#![allow(dead_code)]

use assert_cmd::Command;
use serde_json::Value;
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, Neu, WorldSpec, path_length_m};
use std::path::Path;

/// The bundled city map's text.
pub const CITY_CSV: &str = include_str!("../../../../data/colliders.csv");

/// The binary, run in `dir`.
pub fn skyplan(dir: &Path) -> Command {
    let mut cmd = Command::cargo_bin("skyplan").unwrap();
    cmd.current_dir(dir);
    cmd
}

/// Runs the binary with `args` in `dir`: exit code, stdout as JSON (null if it is not JSON),
/// stderr.
pub fn run(dir: &Path, args: &[&str]) -> (i32, Value, String) {
    let out = skyplan(dir).args(args).output().unwrap();
    let v = serde_json::from_slice(&out.stdout).unwrap_or(Value::Null);
    (
        out.status.code().unwrap_or(-1),
        v,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `skyplan plan --json ARGS`: exit code and the JSON object (stdout must be JSON).
pub fn plan_json(dir: &Path, args: &[&str]) -> (i32, Value) {
    let (code, v, err) = run(dir, &[&["plan", "--json"], args].concat());
    assert!(!v.is_null(), "stdout is not JSON; stderr: {err}");
    (code, v)
}

/// A JSON number.
pub fn num(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// The waypoints of a 3D answer, from `start` to `goal` exactly, re-checked free against every
/// box of `map_text` grown by `safety_m` inside the answer's flight volume (brute force, exact
/// slab tests), with `cost_m` equal to their length.
pub fn checked_path_3d(
    map_text: &str,
    v: &Value,
    safety_m: f64,
    start: Neu,
    goal: Neu,
) -> Vec<Neu> {
    assert_eq!(v["status"], "ok", "{v}");
    assert_eq!(v["planner_status"], "exact", "{v}");
    let rows: Vec<[f64; 4]> = serde_json::from_value(v["waypoints"].clone()).unwrap();
    let path: Vec<Neu> = rows.iter().map(|r| [r[0], r[1], r[2]]).collect();
    assert!(path.len() >= 2);
    assert_eq!(path[0], start);
    assert_eq!(*path.last().unwrap(), goal);
    let corner = |c: &Value| -> Neu { [0, 1, 2].map(|i| num(&c[i])) };
    let bounds = Aabb {
        min: corner(&v["flight_volume"]["min"]),
        max: corner(&v["flight_volume"]["max"]),
    };
    let map = skyplan_map::colliders::parse_colliders(map_text).unwrap();
    let spec = WorldSpec {
        safety_m,
        min_alt_m: bounds.min[2],
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
    path
}
