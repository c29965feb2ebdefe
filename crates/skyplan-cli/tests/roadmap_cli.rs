//! `skyplan plan --planner lazy-prm` and `--save-roadmap` / `--load-roadmap`: the real binary.
//! Every returned segment is re-checked here against every box with the brute-force checker.

use serde_json::Value;
mod common;
use common::{CITY_CSV, checked_path_3d};
use skyplan_world3::Neu;
use std::path::Path;

/// `skyplan plan --json ARGS`: exit code, JSON (or null), stderr.
fn run(dir: &Path, args: &[&str]) -> (i32, Value, String) {
    common::run(dir, &[&["plan", "--json"], args].concat())
}

/// The route of an answer, exactly re-checked against every box grown by 5 m.
fn checked_path(v: &Value, start: Neu, goal: Neu) -> Vec<Neu> {
    checked_path_3d(CITY_CSV, v, 5.0, start, goal)
}

#[test]
fn lazy_prm_returns_an_exactly_free_path_and_tests_fewer_edges_than_prm() {
    let dir = tempfile::tempdir().unwrap();
    let (start, goal) = ([0.0, 0.0, 5.0], [420.0, 390.0, 20.0]);
    let mut tested = Vec::new();
    for planner in ["prm", "lazy-prm"] {
        let (code, v, err) = run(
            dir.path(),
            &[
                "--planner",
                planner,
                "--goal-alt-m",
                "20",
                "--seed",
                "11",
                "--save-roadmap",
                &format!("{planner}.json"),
            ],
        );
        assert_eq!(code, 0, "{err}");
        assert_eq!(v["planner"], planner);
        checked_path(&v, start, goal);
        tested.push(v["roadmap"]["edges_tested"].as_u64().unwrap());
    }
    assert!(
        tested[1] * 10 < tested[0],
        "lazy {} vs eager {}",
        tested[1],
        tested[0]
    );
    // Without saving or plotting, lazy-prm runs through the library's `plan`.
    let (code, v, err) = run(dir.path(), &["--planner", "lazy-prm", "--seed", "3"]);
    assert_eq!(code, 0, "{err}");
    checked_path(&v, start, [420.0, 390.0, 5.0]);
}

fn args(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

#[test]
fn a_saved_roadmap_gives_the_same_route_and_is_refused_for_another_margin() {
    let dir = tempfile::tempdir().unwrap();
    let common = ["--planner", "prm", "--goal-alt-m", "20", "--seed", "11"];
    let with = |extra: &[&str]| -> Vec<String> {
        common.iter().chain(extra).map(|s| s.to_string()).collect()
    };
    let saving = with(&["--save-roadmap", "city.roadmap.json", "--out", "a.json"]);
    let (code, a, err) = run(dir.path(), &args(&saving));
    assert_eq!(code, 0, "{err}");
    let saved = std::fs::read(dir.path().join("city.roadmap.json")).unwrap();
    assert_eq!(
        a["roadmap"]["saved_bytes"].as_u64(),
        Some(saved.len() as u64)
    );
    // Nothing but the outputs in the directory: the write was atomic.
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["a.json", "city.roadmap.json"]);

    let loading = with(&["--load-roadmap", "city.roadmap.json", "--out", "b.json"]);
    let (code, b, err) = run(dir.path(), &args(&loading));
    assert_eq!(code, 0, "{err}");
    assert_eq!(a["waypoints"], b["waypoints"]);
    assert_eq!(
        b["iterations"], 0,
        "the loaded roadmap answers without sampling"
    );
    assert_eq!(b["roadmap"]["vertices"], a["roadmap"]["vertices"]);
    checked_path(&b, [0.0, 0.0, 5.0], [420.0, 390.0, 20.0]);

    // Another margin, another flight volume, the other planner, a broken file: exit 2, named.
    for (extra, needle) in [
        (vec!["--safety-m", "4"], "safety margin of 5 m, not 4 m"),
        (vec!["--max-alt-m", "90"], "another flight volume"),
    ] {
        let mut v = loading.clone();
        v.extend(extra.iter().map(|s| s.to_string()));
        let (code, _, err) = run(dir.path(), &args(&v));
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains("city.roadmap.json") && err.contains(needle),
            "{err}"
        );
    }
    let lazy: Vec<String> = args(&loading)
        .iter()
        .map(|s| if *s == "prm" { "lazy-prm" } else { s }.to_string())
        .collect();
    let (code, _, err) = run(dir.path(), &args(&lazy));
    assert_eq!(code, 2);
    assert!(err.contains("built by --planner prm"), "{err}");
    std::fs::write(dir.path().join("broken.json"), "{\"format\": 7").unwrap();
    let (code, _, err) = run(
        dir.path(),
        &["--planner", "prm", "--load-roadmap", "broken.json"],
    );
    assert_eq!(code, 2);
    assert!(
        err.contains("broken.json") && err.contains("not a skyplan roadmap"),
        "{err}"
    );
    let (code, _, err) = run(
        dir.path(),
        &["--planner", "prm", "--load-roadmap", "missing.json"],
    );
    assert_eq!(code, 2);
    assert!(err.contains("missing.json"), "{err}");
    let (code, _, err) = run(
        dir.path(),
        &["--planner", "rrt-connect", "--save-roadmap", "x.json"],
    );
    assert_eq!(code, 2);
    assert!(err.contains("need --planner prm or lazy-prm"), "{err}");
}
