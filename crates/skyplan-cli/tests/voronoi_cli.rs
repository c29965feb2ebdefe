//! `skyplan plan --planner voronoi`: the JSON contract, every segment free on the grid, start and
//! goal as asked, exit codes for blocked ends.

use skyplan_cspace::{Grid2, GridSpec, Touch};
mod common;
use common::{
    CITY_CSV as CITY, assert_no_waypoints, assert_segments_free, cmd, code_of, ok_json, rows,
};

/// `skyplan plan --planner voronoi` to the default goal, with JSON and `--out OUT`.
const TO_GOAL: &str = "plan --planner voronoi --goal-ne 420,390 --json --out";

#[test]
fn voronoi_json_route_is_free_and_ends_where_asked() {
    let dir = tempfile::tempdir().unwrap();
    let v = ok_json(dir.path(), &format!("{TO_GOAL} route.csv"));
    assert_eq!(v["status"], "ok");
    assert!(v["fallback"].is_null());
    // The city's roadmap at 5 m / 5 m margin (pinned: 12,349 nodes in 95 components).
    assert_eq!(v["components"].as_u64(), Some(95));
    assert_eq!(v["nodes"].as_u64(), Some(12_349));
    let rows = rows(&v);
    assert_eq!(&rows[0][..3], &[0.0, 0.0, 5.0]);
    assert_eq!(&rows.last().unwrap()[..3], &[420.0, 390.0, 5.0]);
    let map = skyplan_map::colliders::parse_colliders(CITY).unwrap();
    let grid = Grid2::from_colliders(&map, GridSpec::default()).unwrap();
    assert_segments_free(&grid, &rows, Touch::Closed);
    let length: f64 = rows
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    assert!((length - v["cost_m"].as_f64().unwrap()).abs() < 1e-6);
    assert!(dir.path().join("route.csv").exists());
}

#[test]
fn voronoi_refuses_a_start_inside_a_margin() {
    let dir = tempfile::tempdir().unwrap();
    let map = skyplan_map::colliders::parse_colliders(CITY).unwrap();
    let b = &map.boxes[0];
    cmd(dir.path(), "plan --planner voronoi --start-ne")
        .arg(format!("{},{}", b.north_m, b.east_m))
        .assert()
        .code(2);
    assert_no_waypoints(dir.path(), "nothing written on bad input");
}

#[test]
fn voronoi_plot_draws_the_graph_connectors_and_route() {
    let dir = tempfile::tempdir().unwrap();
    for (name, magic) in [
        ("voronoi.svg", &b"<svg"[..]),
        ("voronoi.png", &b"\x89PNG"[..]),
    ] {
        let v = ok_json(dir.path(), &format!("{TO_GOAL} route.json --plot {name}"));
        assert_eq!(v["outputs"]["plot"], name);
        let bytes = std::fs::read(dir.path().join(name)).unwrap();
        assert!(bytes.starts_with(magic), "{name}");
        if name.ends_with(".svg") {
            let svg = String::from_utf8(bytes).unwrap();
            let edges = v["edges"].as_u64().unwrap();
            assert!(svg.contains(&format!("roadmap ({edges} edges)")), "legend");
            assert!(svg.contains("connectors ("), "legend");
            assert!(svg.contains("graph route ("), "legend");
            assert!(svg.contains("waypoints ("), "legend");
        }
    }
    assert_eq!(
        code_of(dir.path(), "plan --planner voronoi --plot voronoi.jpg"),
        Some(2)
    );
    assert_no_waypoints(dir.path(), "nothing written on bad input");
}
