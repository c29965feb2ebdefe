//! `skyplan bench`: every skyplan planner and the Rust peer agree on every cost; the Python
//! textbook A* (an independent implementation) agrees too; records are written.

use serde_json::Value;
use skyplan_bench::Contender;
use skyplan_plan::{Optimality, PlannerId};
use std::path::Path;
mod common;
use common::{cmd, json_of, ok};

/// `skyplan bench --json LINE EXTRA` in `dir`, which must succeed: its JSON.
/// The MovingAI game map the tests replay (its scenarios beside it, `.scen`).
const DEN312D: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../data/movingai/den312d.map"
);

fn bench(dir: &Path, line: &str, extra: &[&str]) -> Value {
    json_of(&ok(cmd(dir, &format!("bench --json {line}")).args(extra)))
}

/// Every exact planner of the registry that `bench` runs, and the Rust peer, on a 10 m grid (so
/// that `ch`'s preprocessing takes a second, not minutes, and the first-move table of its
/// ≈ 6,000 free cells is 25 MB, not gigabytes).
#[test]
fn all_optimal_planners_agree_on_the_city_map() {
    let dir = tempfile::tempdir().unwrap();
    let records = dir.path().join("records.csv");
    let mut planners: Vec<&str> = (PlannerId::ALL.iter())
        .filter(|p| p.info().optimality == Optimality::Exact)
        .filter_map(|p| Contender::from_name(p.name()).map(Contender::name))
        .collect();
    assert!(planners.len() >= 2, "{planners:?}");
    planners.push(Contender::PathfindingCrateAStar.name());
    let line = format!(
        "--random 4 --seed 7 --cell-m 10 --planners {} --out",
        planners.join(",")
    );
    let v = bench(dir.path(), &line, &[records.to_str().unwrap()]);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), planners.len());
    for r in rows {
        assert_eq!(r["queries"], 4, "{r}");
        assert_eq!(r["cost_over_best"].as_f64(), Some(1.0), "{r}");
        assert!(r["median_us"].as_f64().unwrap() > 0.0);
    }
    let csv = std::fs::read_to_string(records).unwrap();
    assert!(csv.starts_with("planner,query,time_us,expansions,cost"));
    assert_eq!(csv.lines().count(), 1 + planners.len() * 4);
}

#[test]
#[ignore = "needs python3 (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn python_textbook_astar_agrees_with_the_optimum() {
    let map = DEN312D;
    let scen = format!("{map}.scen");
    let dir = tempfile::tempdir().unwrap();
    let v = bench(
        dir.path(),
        "--random 5 --planners jps-plus --peers --peer-budget-s 20",
        &["--map", map, "--scen", &scen],
    );
    let rows = v["rows"].as_array().unwrap();
    let textbook = rows
        .iter()
        .find(|r| r["planner"] == "python-heapq-astar")
        .expect("python peer ran");
    assert_eq!(textbook["cost_over_best"].as_f64(), Some(1.0), "{textbook}");
    let fcnd = rows
        .iter()
        .find(|r| r["planner"] == "fcnd-astar")
        .expect("FCND peer ran");
    assert!(fcnd["cost_over_best"].as_f64().unwrap() >= 1.0);
    let ours = rows.iter().find(|r| r["planner"] == "jps-plus").unwrap();
    assert_eq!(ours["cost_over_best"].as_f64(), Some(1.0));
}

/// `--save-preprocess` writes the JPS+ table, `--preprocess` loads it: the same optimal costs
/// as A*; a table of another grid or corner rule is refused naming the file; every row reports
/// the peak resident memory.
#[test]
fn saved_preprocessing_is_reloaded_and_refused_for_another_grid() {
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("city.jpsplus");
    let t = table.to_str().unwrap();
    let saved = bench(
        dir.path(),
        "--random 3 --planners jps-plus,astar --save-preprocess",
        &[t],
    );
    // An 88-byte header, one byte per cell and direction, and 8 landmarks: their cells, 4
    // bytes per cell each, a checksum (format version 3).
    let landmarks = 8 * 8 + 921 * 921 * 8 * 4 + 8;
    assert_eq!(
        std::fs::metadata(&table).unwrap().len(),
        88 + 921 * 921 * 8 + landmarks
    );
    let loaded = bench(
        dir.path(),
        "--random 3 --planners auto,jps-plus,astar --preprocess",
        &[t],
    );
    // `auto` uses the loaded table (its rule picks JPS for 3 queries: the table is faster).
    let names: Vec<&str> = (loaded["rows"].as_array().unwrap().iter())
        .map(|r| r["planner"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["auto (jps-plus)", "jps-plus", "astar"]);
    for v in [&saved, &loaded] {
        for r in v["rows"].as_array().unwrap() {
            assert_eq!(r["cost_over_best"].as_f64(), Some(1.0), "{r}");
            let peak = r["peak_rss_mib"].as_f64().unwrap();
            assert!(peak > 1.0, "{r}");
        }
    }
    let refused = |extra: &[&str], why: &str| {
        let out = cmd(
            dir.path(),
            "bench --random 2 --planners jps-plus --preprocess",
        )
        .arg(t)
        .args(extra)
        .output()
        .unwrap();
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(t) && err.contains(why), "{err}");
    };
    refused(&["--alt-m", "40"], "another map, altitude");
    refused(&["--corner-cutting"], "this run is with corner cutting");
    std::fs::write(&table, b"garbage").unwrap();
    refused(&[], "not a skyplan JPS+ table");
}

#[test]
fn contraction_hierarchy_matches_astar_on_every_den312d_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let map = DEN312D;
    let v = bench(
        dir.path(),
        &format!("--map {map} --scen {map}.scen --planners ch,astar"),
        &[],
    );
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for r in rows {
        assert_eq!(r["queries"], 290, "{r}"); // --scen without --random: every scenario
        assert_eq!(r["cost_over_best"].as_f64(), Some(1.0), "{r}");
    }
    let ch = rows.iter().find(|r| r["planner"] == "ch").unwrap();
    assert!(ch["precompute_ms"].as_f64().unwrap() > 0.0, "{ch}");
}

/// A first-move table saved by `scen` serves `first-move` and `auto` in `bench --preprocess`:
/// `auto` reports it picked the table, both find every scenario's A* cost, and the
/// preparation is the load.
#[test]
fn a_saved_first_move_table_serves_first_move_and_auto_in_bench() {
    let dir = tempfile::tempdir().unwrap();
    let map = DEN312D;
    saved_then_benched(
        dir.path(),
        (map, "first-move", "den.fm"),
        "auto,first-move,astar",
        &["auto (first-move)", "first-move", "astar"],
        290,
    );
}

/// `scen MAP --planner PLANNER --save-preprocess FILE` in `dir`, then `bench` on MAP's
/// scenarios (the first `queries`) with `planners` and `--preprocess FILE`: its rows, checked
/// to be `names`, each of `queries` queries at the best cost.
fn saved_then_benched(
    dir: &Path,
    (map, planner, file): (&str, &str, &str),
    planners: &str,
    names: &[&str],
    queries: u64,
) -> Vec<Value> {
    ok(&mut cmd(
        dir,
        &format!("scen {map} {map}.scen --planner {planner} --save-preprocess {file}"),
    ));
    let v = bench(
        dir,
        &format!(
            "--map {map} --scen {map}.scen --random {queries} --planners {planners} --preprocess {file}"
        ),
        &[],
    );
    let rows = v["rows"].as_array().unwrap().clone();
    let found: Vec<&str> = rows
        .iter()
        .map(|r| r["planner"].as_str().unwrap())
        .collect();
    assert_eq!(found, names);
    for r in &rows {
        assert_eq!(r["queries"], queries, "{r}");
        assert_eq!(r["cost_over_best"].as_f64(), Some(1.0), "{r}");
    }
    rows
}

/// A contraction hierarchy or a subgoal graph saved by `scen` serves its planner and `auto` in
/// `bench --preprocess` on a large map of scattered obstacles: `auto` reports it picked what is
/// at hand (over the JPS+ its rule gives for 150 queries), both find the A* cost of every query,
/// and both report the one load as their preparation (nothing built again). Given to another
/// map, the file is refused, naming it and what it was built for.
#[test]
fn a_saved_hierarchy_or_subgoal_graph_serves_its_planner_and_auto_in_bench() {
    let dir = tempfile::tempdir().unwrap();
    let map = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/movingai/random512-40-5.map"
    );
    for (planner, file, refusal) in [
        (
            "ch",
            "r.ch",
            "--preprocess r.ch: contraction hierarchy was built for a 512 × 512 grid",
        ),
        (
            "subgoal",
            "r.sg",
            "--preprocess r.sg: subgoal graph file: contraction hierarchy was built for a 512 × 512 grid",
        ),
    ] {
        let auto = format!("auto ({planner})");
        let rows = saved_then_benched(
            dir.path(),
            (map, planner, file),
            &format!("auto,{planner},astar"),
            &[&auto, planner, "astar"],
            150,
        );
        assert_eq!(rows[0]["precompute_ms"], rows[1]["precompute_ms"]);
        let den = DEN312D;
        let out = cmd(
            dir.path(),
            &format!(
                "bench --map {den} --scen {den}.scen --planners {planner} --preprocess {file}"
            ),
        )
        .output()
        .unwrap();
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(refusal), "{err}");
    }
}
