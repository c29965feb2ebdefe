//! `skyplan plan --planner wavefront|costmap` and `skyplan navigate` on image, MovingAI and
//! random maps: the CLI contract (maps by extension, north = up the image, JSON fields, exit codes).

use serde_json::Value;
use skyplan_cspace::{Cell, Grid2};
use skyplan_plan::{Optimality, PlannerId};
use skyplan_search::MoveModel;
use skyplan_search::oracle::dijkstra_exact;
mod common;
use common::{cmd, dir_with, fails_with, json_of, ok_json, succeed};

/// The non-empty lines of a picture, trimmed, top line first.
fn picture_lines(picture: &str) -> Vec<&str> {
    picture
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect()
}

/// A picture, top line = north, `#` black (occupied), `.` white (free), as a plain PGM.
fn pgm(picture: &str) -> String {
    let lines = picture_lines(picture);
    let mut text = format!("P2\n{} {}\n255\n", lines[0].len(), lines.len());
    for line in &lines {
        let px: Vec<&str> = line
            .chars()
            .map(|c| if c == '#' { "0" } else { "255" })
            .collect();
        text.push_str(&px.join(" "));
        text.push('\n');
    }
    text
}

/// A new temporary directory holding the picture as the PGM `name`.
fn pgm_dir(name: &str, picture: &str) -> tempfile::TempDir {
    dir_with(&[(name, &pgm(picture))])
}

/// The same picture as a grid, independently of the crate: row 0 = the LAST line.
fn grid_of(picture: &str) -> Grid2 {
    let flipped: Vec<&str> = picture_lines(picture).into_iter().rev().collect();
    Grid2::from_ascii(&flipped.join("\n")).unwrap()
}

const U_WALL: &str = "
    ..........
    .#......#.
    .#......#.
    .#......#.
    .########.
    ..........
    ..........";

#[test]
fn every_exact_planner_costs_the_oracle_optimum_on_an_image_map() {
    let dir = dir_with(&[
        ("u.pgm", &pgm(U_WALL)),
        (
            "u.yaml",
            "image: u.pgm\nresolution: 2.0\norigin: [100.0, 50.0, 0.0]\nnegate: 0\n\
             occupied_thresh: 0.65\nfree_thresh: 0.196\n",
        ),
    ]);
    // Source south of the U's bottom (image row 6, x 4), destination inside it (row 2, x 4):
    // north = 50 + (6 − 1 − y + 0.5)·2, east = 100 + (x + 0.5)·2.
    let (start, goal) = ("51,109", "59,109");
    let grid = grid_of(U_WALL);
    for (connectivity, model) in [("8", MoveModel::Octile), ("4", MoveModel::FourConnected)] {
        let truth = dijkstra_exact(&grid, Cell::new(0, 4), Cell::new(4, 4), model).unwrap();
        let mut costs = Vec::new();
        // The wavefront and every other exact planner of the registry.
        let exact = PlannerId::ALL
            .iter()
            .filter(|p| p.info().optimality == Optimality::Exact);
        for planner in exact {
            let v = ok_json(
                dir.path(),
                &format!(
                    "plan --map u.yaml --planner {planner} --json \
                     --start-ne {start} --goal-ne {goal} --connectivity {connectivity}"
                ),
            );
            assert_eq!(v["status"], "ok");
            assert_eq!(v["start"]["cell"], serde_json::json!([0, 4]));
            assert_eq!(v["goal"]["cell"], serde_json::json!([4, 4]));
            costs.push(v["cost_m"].as_f64().unwrap());
            assert_eq!(v["waypoints_lla"], Value::Null); // no --home: no lat/lon
        }
        assert!(costs.len() >= 2, "{costs:?}");
        assert!(
            costs
                .iter()
                .all(|&c| (c - truth.to_f64() * 2.0).abs() < 1e-9),
            "connectivity {connectivity}: {costs:?}"
        );
    }
}

#[test]
fn image_axes_north_is_up_east_is_right() {
    // An obstacle only in the top-left (north-west) corner of a 6 × 4 image of 1 m pixels.
    let dir = pgm_dir("corner.pgm", "##....\n#.....\n......\n......");
    let plan = |start: &str| {
        format!(
            "plan --map corner.pgm --resolution 1 --planner wavefront \
             --start-ne {start} --goal-ne 0.5,5.5"
        )
    };
    // North 3.5 m, east 0.5 m is the top-left pixel: an obstacle.
    fails_with(
        dir.path(),
        &plan("3.5,0.5"),
        2,
        &["start N 3.50 m, E 0.50 m (row 3, col 0) is at an obstacle"],
    );
    // The bottom-left pixel (north 0.5) is free; so is the top-right (east 5.5).
    succeed(dir.path(), &plan("0.5,0.5"));
    succeed(dir.path(), &plan("3.5,5.5"));
    // Off the map.
    fails_with(
        dir.path(),
        &plan("4.5,0.5"),
        2,
        &["off the map (north 0.00..4.00 m, east 0.00..6.00 m)"],
    );
}

#[test]
fn enclosed_destination_exits_3_and_show_marks_unreachable_cells() {
    let dir = pgm_dir("box.pgm", ".......\n.#####.\n.#...#.\n.#####.\n.......");
    let ends = "--start-ne 0.5,0.5 --goal-ne 2.5,3.5";
    let box_map = "plan --map box.pgm --resolution 1";
    let out = cmd(
        dir.path(),
        &format!("{box_map} --planner wavefront --show {ends}"),
    )
    .output()
    .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains(
        "path could not be found: the destination (row 2, col 3) is unreachable from the source (row 0, col 0)"
    ), "{err}");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(" 2 x#.D.#x") && text.contains(" 0 Sxxxxxx"),
        "{text}"
    );
    let out = cmd(
        dir.path(),
        &format!("{box_map} --planner costmap --json {ends}"),
    )
    .output()
    .unwrap();
    assert_eq!(out.status.code(), Some(3));
    // The HTTP API's error shape, with the planning failure's kind.
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (&v["status"], &v["kind"]),
        (&"error".into(), &"no_path".into()),
        "{v}"
    );
}

#[test]
fn workshop_show_prints_workspace_matrix_and_path() {
    let dir = pgm_dir(
        "corridor.pgm",
        "....#....\n....#....\n.........\n....#....\n....#....",
    );
    let out = succeed(
        dir.path(),
        "plan --map corridor.pgm --resolution 1 --planner wavefront \
         --connectivity 4 --field steps --show --start-ne 2.5,0.5 --goal-ne 2.5,8.5",
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(" 2 S*******D"), "{text}");
    assert!(text.contains("distance matrix"));
    assert!(text.contains(" 2   S  7  6  5  4  3  2  1  D"), "{text}");
    assert!(text.contains("8.00 m"));
}

#[test]
fn costmap_keeps_clearance_and_plots_a_heat_map() {
    let dir = tempfile::tempdir().unwrap();
    let random = "plan --random 60x40 --density 0.08 --seed 4 --planner costmap --json";
    let v = ok_json(
        dir.path(),
        &format!("{random} --plot heat.png --home 37.79,-122.39"),
    );
    assert!(v["costmap"]["min_clearance_m"].as_f64().unwrap() >= 1.0);
    assert_eq!(
        v["waypoints"].as_array().unwrap().len(),
        v["waypoints_lla"].as_array().unwrap().len()
    );
    let png = std::fs::read(dir.path().join("heat.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    // Reproducible: the same seed gives the same answer.
    let again = json_of(&cmd(dir.path(), random).output().unwrap());
    assert_eq!(again["waypoints"], v["waypoints"]);
}

#[test]
fn navigate_reports_reached_steps_distance_and_clearance() {
    let dir = pgm_dir(
        "open.pgm",
        "..........\n..........\n....##....\n..........\n..........",
    );
    let open = "navigate --map open.pgm --resolution 1 --start-ne 0.5,0.5";
    let v = ok_json(
        dir.path(),
        &format!("{open} --json --targets 4.5,9.5;0.5,9.5 --change-target-at 3:4.5,0.5"),
    );
    assert_eq!(v["reached"], true);
    let legs = v["legs"].as_array().unwrap();
    assert_eq!(legs.len(), 3);
    assert_eq!(legs[0]["replaced"], true);
    assert_eq!(legs[0]["to_step"], 3);
    assert!(v["steps"].as_u64().unwrap() >= 3 + 4 + 9);
    assert!(v["distance_m"].as_f64().unwrap() >= v["steps"].as_f64().unwrap());
    assert!(v["min_clearance_m"].as_f64().unwrap() >= 1.0);
    // A target inside an obstacle is bad input; an enclosed one is "no path".
    fails_with(
        dir.path(),
        &format!("{open} --targets 2.5,4.5"),
        2,
        &["target 1 N 2.5 m, E 4.5 m (row 2, col 4) is at an obstacle"],
    );
}

#[test]
fn bad_maps_name_the_file_and_field() {
    let dir = dir_with(&[
        ("a.pgm", &pgm("..\n..")),
        (
            "bad.yaml",
            "image: a.pgm\nresolution: -2\norigin: [0, 0, 0]\n",
        ),
        (
            "missing.yaml",
            "image: nope.png\nresolution: 1\norigin: [0, 0, 0]\n",
        ),
        ("empty.png", ""),
    ]);
    let cases = [
        ("a.pgm", "a.pgm: a bare image needs --resolution"),
        (
            "bad.yaml",
            "bad.yaml: resolution: expected metres per pixel > 0, found -2",
        ),
        ("missing.yaml", "missing.yaml: field image: cannot read"),
        (
            "empty.png --resolution 1",
            "empty.png: not a PNG or PGM image",
        ),
        ("x.tif", "x.tif: unknown map type"),
    ];
    for (map, expected) in cases {
        let line = format!("plan --map {map} --start-ne 0.5,0.5 --goal-ne 1.5,1.5");
        fails_with(dir.path(), &line, 2, &[expected]);
    }
}

#[test]
fn movingai_maps_are_north_up() {
    let dir = dir_with(&[(
        "m.map",
        "type octile\nheight 3\nwidth 4\nmap\n@...\n.@..\n....\n",
    )]);
    // MovingAI (x 0, y 0) — the first line's first character — is the north-west cell (row 2).
    let m = "plan --map m.map --planner wavefront";
    fails_with(
        dir.path(),
        &format!("{m} --start-ne 2.5,0.5 --goal-ne 0.5,3.5"),
        2,
        &["(row 2, col 0) is at an obstacle"],
    );
    let v = ok_json(
        dir.path(),
        &format!("{m} --json --start-ne 0.5,0.5 --goal-ne 2.5,3.5"),
    );
    assert_eq!(v["cost_m"], 2.0 + 2f64.sqrt() + 1.0);
}
