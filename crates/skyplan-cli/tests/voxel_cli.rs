//! `skyplan plan --planner voxel`: the real binary; every returned segment is re-checked here
//! against every box with the brute-force checker, and the pictures are written.

use serde_json::Value;
mod common;
use common::{CITY_CSV, checked_path_3d, code_of, num, plan_json, succeed};
use skyplan_world3::{Neu, path_length_m};
use std::path::Path;

/// `skyplan plan --json --planner voxel LINE`.
fn run(dir: &Path, line: &str) -> (i32, Value) {
    plan_json(dir, &format!("--planner voxel {line}"))
}

/// The route of a voxel answer, exactly re-checked.
fn checked_path(v: &Value, start: Neu, goal: Neu) -> Vec<Neu> {
    assert_eq!(v["planner"], "voxel");
    checked_path_3d(CITY_CSV, v, 5.0, start, goal)
}

#[test]
fn climbs_onto_a_rooftop_and_draws_it() {
    let dir = tempfile::tempdir().unwrap();
    // The roof at N 200, E 330 is 60 m high: the goal is 1 m above its 5 m margin.
    let (code, v) = run(
        dir.path(),
        "--goal-ne 200,330 --goal-alt-m 66 --plot route.png --out route.plan",
    );
    assert_eq!(code, 0, "{v}");
    let path = checked_path(&v, [0.0, 0.0, 5.0], [200.0, 330.0, 66.0]);
    assert!(path.len() >= 3);
    let vox = &v["voxel"];
    assert!(num(&vox["climb_m"]) >= 61.0 - 1e-9, "{vox}");
    assert!(num(&vox["objective"]) <= num(&vox["lattice_objective"]) + 1e-9);
    assert_eq!(vox["dims"][2], 24, "layers 5, 10, …, 120 m");
    let png = std::fs::read(dir.path().join("route.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    assert!(dir.path().join("route.plan").exists());
}

#[test]
fn the_climb_weight_trades_climbing_for_distance() {
    let dir = tempfile::tempdir().unwrap();
    let (start, goal) = ([300.0, -50.0, 5.0], [30.0, 300.0, 5.0]);
    let args =
        |w: &str| format!("--start-ne 300,-50 --goal-ne 30,300 --climb-weight {w} --plot p.svg");
    let (code, free_climb) = run(dir.path(), &args("0"));
    assert_eq!(code, 0, "{free_climb}");
    let short = checked_path(&free_climb, start, goal);
    let (code, dear_climb) = run(dir.path(), &args("100"));
    assert_eq!(code, 0, "{dear_climb}");
    let flat = checked_path(&dear_climb, start, goal);
    assert!(num(&free_climb["voxel"]["climb_m"]) > 0.0);
    assert!(num(&dear_climb["voxel"]["climb_m"]) < num(&free_climb["voxel"]["climb_m"]));
    assert!(path_length_m(&short) <= path_length_m(&flat) + 1e-9);
    let svg = std::fs::read_to_string(dir.path().join("p.svg")).unwrap();
    assert!(svg.contains("ALTITUDE (m)"));
}

#[test]
fn bad_ends_and_options_exit_2_and_a_low_ceiling_exits_3() {
    let dir = tempfile::tempdir().unwrap();
    // The goal inside the 60 m building.
    let (code, v) = run(dir.path(), "--goal-ne 200,330 --goal-alt-m 30");
    assert_eq!(code, 2, "{v}");
    assert!(v["message"].as_str().unwrap().contains("goal"), "{v}");
    // Below --min-alt-m.
    let (code, v) = run(dir.path(), "--min-alt-m 10");
    assert_eq!(code, 2, "{v}");
    assert!(v["message"].as_str().unwrap().contains("below"), "{v}");
    // The rooftop goal under a ceiling lower than its approach: no path.
    let (code, v) = run(
        dir.path(),
        "--goal-ne 200,330 --goal-alt-m 66 --max-alt-m 67",
    );
    assert_eq!(code, 3, "{v}");
    // Voxel options with another planner.
    assert_eq!(
        code_of(dir.path(), "plan --planner astar --climb-weight 2"),
        Some(2)
    );
}

#[test]
fn the_sampling_planners_draw_too() {
    let dir = tempfile::tempdir().unwrap();
    succeed(
        dir.path(),
        "plan --planner prm --goal-alt-m 40 --plot prm.svg",
    );
    let svg = std::fs::read_to_string(dir.path().join("prm.svg")).unwrap();
    assert!(svg.contains("PRM roadmap") && svg.contains("ALTITUDE (m)"));
    assert_eq!(
        code_of(dir.path(), "plan --planner rrt-connect --plot x.jpg"),
        Some(2)
    );
}
