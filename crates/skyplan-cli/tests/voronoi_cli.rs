//! `skyplan plan --planner voronoi`: the JSON contract, every segment free on the grid, start and
//! goal as asked, exit codes for blocked ends.

use skyplan_cspace::{Grid2, GridSpec, Touch};
mod common;
use common::skyplan;

const CITY: &str = include_str!("../../../data/colliders.csv");

#[test]
fn voronoi_json_route_is_free_and_ends_where_asked() {
    let dir = tempfile::tempdir().unwrap();
    let out = skyplan(dir.path())
        .args([
            "plan",
            "--planner",
            "voronoi",
            "--goal-ne",
            "420,390",
            "--json",
        ])
        .args(["--out", "route.csv"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["status"], "ok");
    assert!(v["fallback"].is_null());
    // The city's roadmap at 5 m / 5 m margin (pinned: 12,349 nodes in 95 components).
    assert_eq!(v["components"].as_u64(), Some(95));
    assert_eq!(v["nodes"].as_u64(), Some(12_349));
    let rows: Vec<[f64; 4]> = serde_json::from_value(v["waypoints"].clone()).unwrap();
    assert_eq!(&rows[0][..3], &[0.0, 0.0, 5.0]);
    assert_eq!(&rows.last().unwrap()[..3], &[420.0, 390.0, 5.0]);
    let map = skyplan_map::colliders::parse_colliders(CITY).unwrap();
    let grid = Grid2::from_colliders(&map, GridSpec::default()).unwrap();
    let mut length = 0.0;
    for w in rows.windows(2) {
        assert!(grid.segment_is_free_ne((w[0][0], w[0][1]), (w[1][0], w[1][1]), Touch::Closed));
        length += (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
    }
    assert!((length - v["cost_m"].as_f64().unwrap()).abs() < 1e-6);
    assert!(dir.path().join("route.csv").exists());
}

#[test]
fn voronoi_refuses_a_start_inside_a_margin() {
    let dir = tempfile::tempdir().unwrap();
    let map = skyplan_map::colliders::parse_colliders(CITY).unwrap();
    let b = &map.boxes[0];
    skyplan(dir.path())
        .args(["plan", "--planner", "voronoi", "--start-ne"])
        .arg(format!("{},{}", b.north_m, b.east_m))
        .assert()
        .code(2);
    assert!(!dir.path().join("waypoints.json").exists());
}

#[test]
fn voronoi_plot_draws_the_graph_connectors_and_route() {
    let dir = tempfile::tempdir().unwrap();
    for (name, magic) in [
        ("voronoi.svg", &b"<svg"[..]),
        ("voronoi.png", &b"\x89PNG"[..]),
    ] {
        let out = skyplan(dir.path())
            .args([
                "plan",
                "--planner",
                "voronoi",
                "--goal-ne",
                "420,390",
                "--json",
            ])
            .args(["--out", "route.json", "--plot", name])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
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
    let out = skyplan(dir.path())
        .args(["plan", "--planner", "voronoi", "--plot", "voronoi.jpg"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        !dir.path().join("waypoints.json").exists(),
        "nothing written on bad input"
    );
}
