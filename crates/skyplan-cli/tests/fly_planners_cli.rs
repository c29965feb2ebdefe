//! `skyplan fly --planner P` flies any planner's route on the built-in simulator: landed,
//! disarmed, every waypoint reached, no collision with the map's boxes.

use assert_cmd::Command;

fn fly(args: &[&str]) -> (Option<i32>, String) {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("skyplan")
        .unwrap()
        .current_dir(dir.path())
        .args(["fly", "--sim", "--speedup", "50", "--timeout-s", "120"])
        .args(args)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.code(), text)
}

#[test]
fn every_route_producing_planner_flies_to_landing() {
    for planner in [
        "jps",
        "jps-plus",
        "astar",
        "dijkstra",
        "theta",
        "wavefront",
        "costmap",
        "voronoi",
        "prm",
        "lazy-prm",
        "rrt-connect",
        "rrt-star",
        "voxel",
    ] {
        let (code, text) = fly(&["--planner", planner, "--goal-ne", "60,40"]);
        assert_eq!(code, Some(0), "{planner}: {text}");
        assert!(
            text.contains("result     landed and disarmed after reaching all"),
            "{planner}: {text}"
        );
        assert!(
            text.contains("no collision with the map's obstacles"),
            "{planner}: {text}"
        );
    }
}

#[test]
fn a_3d_route_is_flown_at_its_altitudes() {
    let (code, text) = fly(&[
        "--planner",
        "rrt-connect",
        "--goal-ne",
        "150,-80",
        "--goal-alt-m",
        "25",
    ]);
    assert_eq!(code, Some(0), "{text}");
    let max_alt: f64 = text
        .lines()
        .find_map(|l| l.split("max altitude ").nth(1))
        .and_then(|rest| rest.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no max altitude in {text}"));
    assert!((24.0..=26.0).contains(&max_alt), "{max_alt} in {text}");
}

#[test]
fn fly_refuses_maps_without_boxes() {
    let (code, text) = fly(&["--random", "20x20", "--planner", "jps"]);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("colliders map"), "{text}");
}
