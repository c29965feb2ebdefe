//! `skyplan plan --planner P` for every 3D planner of the registry: the real binary; every
//! returned segment is re-checked here against every box with the brute-force checker.

mod common;
use common::{CITY_CSV, assert_no_waypoints, checked_path_3d, num, plan_json};

use skyplan_plan::PlannerId;

/// The registry's 3D planners (a new one is tested here without an edit).
fn three_d_planners() -> impl Iterator<Item = PlannerId> {
    PlannerId::ALL
        .iter()
        .copied()
        .filter(|p| p.info().dims == 3)
}

#[test]
fn every_3d_planner_returns_an_exactly_free_path_on_the_city() {
    let dir = tempfile::tempdir().unwrap();
    let text = CITY_CSV;
    for planner in three_d_planners() {
        // Climb from 5 m at the home to 40 m across the city.
        let (code, v) = plan_json(
            dir.path(),
            &format!("--planner {planner} --goal-alt-m 40 --seed 3 --time-limit-ms 400"),
        );
        assert_eq!(code, 0, "{planner}: {v}");
        checked_path_3d(text, &v, 5.0, [0.0, 0.0, 5.0], [420.0, 390.0, 40.0]);
        // Low ceiling: the route must weave between the buildings at 0–15 m.
        let (code, v) = plan_json(
            dir.path(),
            &format!(
                "--planner {planner} --max-alt-m 15 --start-ne 0,0 --goal-ne 420,390 \
                 --seed 5 --time-limit-ms 3000 --out route.csv"
            ),
        );
        assert_eq!(code, 0, "{planner}: {v}");
        checked_path_3d(text, &v, 5.0, [0.0, 0.0, 5.0], [420.0, 390.0, 5.0]);
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
    let line = "--planner prm --goal-alt-m 20 --seed 11 --out a.json";
    let (_, a) = plan_json(dir.path(), line);
    let (_, b) = plan_json(dir.path(), line);
    assert_eq!(a["waypoints"], b["waypoints"]);
}

#[test]
fn goal_in_a_building_is_bad_input_and_an_enclosed_goal_is_no_path() {
    let dir = tempfile::tempdir().unwrap();
    // The bundled map has a box at N −310.2, E −439.2 rising to 171 m.
    let (code, v) = plan_json(
        dir.path(),
        "--planner rrt-connect --goal-ne -310.2389,-439.2315 --goal-alt-m 20",
    );
    assert_eq!(code, 2, "{v}");
    // The HTTP API's error shape: the planning failure's kind.
    assert_eq!(
        (&v["status"], &v["kind"]),
        (&"error".into(), &"invalid_goal".into())
    );
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
    for planner in three_d_planners() {
        let (code, v) = plan_json(
            dir.path(),
            &format!(
                "--planner {planner} --map cage.csv --safety-m 0 --start-ne 0,0 --goal-ne 50,50 \
                 --goal-alt-m 20 --time-limit-ms 150"
            ),
        );
        assert_eq!(code, 3, "{planner}: {v}");
        // Sampling planners cannot prove there is no path: they run out of time.
        assert_eq!(v["status"], "error", "{planner}: {v}");
        assert!(
            v["kind"] == "no_path" || v["kind"] == "timeout",
            "{planner}: {v}"
        );
        assert_no_waypoints(dir.path(), "nothing written on failure");
    }
}

#[test]
fn three_d_options_need_a_three_d_planner() {
    let dir = tempfile::tempdir().unwrap();
    let (code, v) = plan_json(dir.path(), "--goal-alt-m 30");
    assert_eq!(code, 2);
    // In the command line's words (the API says goal_alt_m), naming the planners that use it.
    let error = v["message"].as_str().unwrap();
    assert!(
        error.starts_with("--goal-alt-m is not used by --planner jps:")
            && error.contains("(prm, lazy-prm, rrt-connect, rrt-star, voxel)"),
        "{v}"
    );
}
