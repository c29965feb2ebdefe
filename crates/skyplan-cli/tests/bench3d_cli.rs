//! `skyplan bench --3d` without OMPL: every skyplan 3D planner solves every query, and every
//! returned path re-checks free against every box (the bench's own brute-force re-check).

mod common;
use common::ok_json;
use skyplan_plan::PlannerId;

#[test]
fn bench_3d_solves_and_rechecks_every_query() {
    let dir = tempfile::tempdir().unwrap();
    let v = ok_json(dir.path(), "bench --3d --random 2 --seed 3 --json");
    // The FCND route plus the two random queries.
    let queries = v["queries"].as_u64().unwrap();
    assert_eq!(queries, 3, "{v}");
    let rows = v["rows"].as_array().unwrap();
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["planner"].as_str().unwrap())
        .collect();
    // Every 3D planner of the registry, no peers without --peers.
    let want: Vec<String> = PlannerId::ALL
        .iter()
        .filter(|p| p.info().dims == 3)
        .map(|p| format!("skyplan {p}"))
        .collect();
    assert_eq!(names, want, "{v}");
    for r in rows {
        assert_eq!(r["queries"], queries, "{r}");
        assert_eq!(r["solved"], queries, "every query solved: {r}");
        assert_eq!(r["recheck_ok"], queries, "every path re-checked free: {r}");
        let ratio = r["median_length_over_straight"].as_f64().unwrap();
        assert!((1.0..3.0).contains(&ratio), "{r}");
        assert!(r["median_first_ms"].as_f64().unwrap() > 0.0, "{r}");
    }
}
