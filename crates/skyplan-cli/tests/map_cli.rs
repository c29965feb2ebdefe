//! `skyplan map tile`: the copies are the map, shifted; the result plans.

mod common;
use common::{code_of, succeed};

#[test]
fn tiled_city_has_k_squared_copies_and_plans_across_them() {
    let dir = tempfile::tempdir().unwrap();
    succeed(
        dir.path(),
        "map tile --times 2 --pitch-m 1000 --out city2.csv",
    );
    let small = skyplan_map::colliders::parse_colliders(skyplan_plan::FCND_CITY_CSV).unwrap();
    let text = std::fs::read_to_string(dir.path().join("city2.csv")).unwrap();
    let big = skyplan_map::colliders::parse_colliders(&text).unwrap();
    assert_eq!(big.home, small.home);
    assert_eq!(big.boxes.len(), 4 * small.boxes.len());
    let last = big.boxes.last().unwrap();
    let orig = small.boxes.last().unwrap();
    assert_eq!(
        (last.north_m, last.east_m),
        (orig.north_m + 1000.0, orig.east_m + 1000.0)
    );
    // Across the copies: the default goal of the north-east copy.
    succeed(
        dir.path(),
        "plan --map city2.csv --goal-ne 1420,1390 --json --out w.json",
    );
    assert_eq!(
        code_of(dir.path(), "map tile --times 0 --out x.csv"),
        Some(2)
    );
}

/// The summary object of `scen --json` (its last line) and how many scenario lines came before.
fn scen_summary(out: &std::process::Output) -> (serde_json::Value, usize) {
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let last = serde_json::from_str(lines[lines.len() - 1]).unwrap();
    (last, lines.len() - 1)
}

#[test]
fn a_generated_maze_replays_with_every_scenario_optimal_under_every_exact_planner() {
    let dir = tempfile::tempdir().unwrap();
    // 65 = 1 + 13 · (4 + 1): whole corridors; 50 rows cut the last corridor short.
    let out = succeed(
        dir.path(),
        "map maze --size 65 50 --corridor-cells 4 --seed 3 --out m.map --scen m.map.scen --queries 300",
    );
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("65 × 50 maze, corridor width 4 cells, seed 3"),
        "{said}"
    );
    let map_text = std::fs::read_to_string(dir.path().join("m.map")).unwrap();
    let map = skyplan_map::movingai::parse_map(&map_text).unwrap();
    assert_eq!((map.width, map.height), (65, 50));
    let scen_text = std::fs::read_to_string(dir.path().join("m.map.scen")).unwrap();
    let scen = skyplan_map::movingai::parse_scen(&scen_text).unwrap();
    assert_eq!(scen.len(), 300);
    assert!(scen.iter().all(|s| s.map == "m.map"));
    // The same options write the same files.
    succeed(
        dir.path(),
        "map maze --size 65 50 --corridor-cells 4 --seed 3 --out n.map --scen n.map.scen --queries 300",
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("n.map")).unwrap(),
        map_text
    );
    // Lengths found by skyplan's planners (A*, JPS, JPS+, CH and auto, none of them the
    // generator's Dijkstra) equal the written ones on every scenario.
    all_match(
        dir.path(),
        "m.map",
        300,
        &["auto", "astar", "jps", "jps-plus", "ch"],
    );
}

/// `scen MAP MAP.scen` with each planner: all `n` scenarios reported, every one matching.
fn all_match(dir: &std::path::Path, map: &str, n: u64, planners: &[&str]) {
    for planner in planners {
        let out = succeed(
            dir,
            &format!("scen {map} {map}.scen --json --planner {planner}"),
        );
        let (summary, records) = scen_summary(&out);
        assert_eq!(records as u64, n, "{planner}");
        assert_eq!(summary["matched"].as_u64(), Some(n), "{planner}: {summary}");
    }
}

#[test]
fn bad_maze_options_are_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    for (line, needle) in [
        (
            "map maze --size 4 64 --corridor-cells 4 --out m.map",
            "width 4: expected 5 to 32768 cells",
        ),
        (
            "map maze --size 64 64 --corridor-cells 0 --out m.map",
            "0 is not in 1..=64",
        ),
        (
            "map maze --size 64 --corridor-cells 2 --out m.map",
            "--size",
        ),
        (
            "map maze --size 64 64 --corridor-cells 2 --out m.txt",
            "expected a .map file name",
        ),
        (
            "map maze --size 64 64 --corridor-cells 2 --out m.map --scen m.txt",
            "--scen m.txt: expected a .scen file name",
        ),
        (
            "map maze --size 64 64 --corridor-cells 2 --out m.map --queries 5",
            "--scen",
        ),
        (
            "map maze --size 64 64 --corridor-cells 2 --out m.map --scen m.scen --queries 0",
            "0 is not in 1..=1000000",
        ),
        (
            "map maze --size 64 64 --corridor-cells 2 --out nowhere/m.map",
            "does not exist",
        ),
        (
            "map rooms --size 64 64 --room-cells 8 --door-cells 9 --out r.map",
            "--size/--room-cells/--door-cells: door width 9: expected 1 to the room width, 8 cells",
        ),
        (
            "map rooms --size 64 64 --room-cells 0 --out r.map",
            "0 is not in 1..=64",
        ),
    ] {
        common::fails_with(dir.path(), line, 2, &[needle]);
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn generated_rooms_replay_with_every_scenario_optimal_under_every_exact_planner() {
    let dir = tempfile::tempdir().unwrap();
    // 6 × 6 rooms of 10 cells, doors of 3; 60 rows cut the last row of rooms short.
    let out = succeed(
        dir.path(),
        "map rooms --size 67 60 --room-cells 10 --door-cells 3 --seed 2 --out r.map --scen r.map.scen --queries 200",
    );
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("67 × 60 rooms of 10 cells, doors of 3 cells, seed 2"),
        "{said}"
    );
    let map_text = std::fs::read_to_string(dir.path().join("r.map")).unwrap();
    let map = skyplan_map::movingai::parse_map(&map_text).unwrap();
    assert_eq!((map.width, map.height), (67, 60));
    // The default door is a quarter of the room: another map from the same seed.
    succeed(
        dir.path(),
        "map rooms --size 67 60 --room-cells 10 --seed 2 --out q.map",
    );
    assert_ne!(
        std::fs::read_to_string(dir.path().join("q.map")).unwrap(),
        map_text
    );
    let planners = ["auto", "astar", "jps", "jps-plus", "ch", "subgoal"];
    all_match(dir.path(), "r.map", 200, &planners);
}
