//! `skyplan bench --3d` without OMPL: every skyplan 3D planner solves every query, and every
//! returned path re-checks free against every box (the bench's own brute-force re-check).

use assert_cmd::Command;
use serde_json::Value;

#[test]
fn bench_3d_solves_and_rechecks_every_query() {
    let out = Command::cargo_bin("skyplan")
        .unwrap()
        .args(["bench", "--3d", "--random", "2", "--seed", "3", "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    // The FCND route plus the two random queries.
    let queries = v["queries"].as_u64().unwrap();
    assert_eq!(queries, 3, "{v}");
    let rows = v["rows"].as_array().unwrap();
    let mut names: Vec<&str> = rows
        .iter()
        .map(|r| r["planner"].as_str().unwrap())
        .collect();
    names.sort_unstable();
    assert_eq!(
        names,
        ["skyplan prm", "skyplan rrt-connect", "skyplan rrt-star"],
        "no peers without --peers: {v}"
    );
    for r in rows {
        assert_eq!(r["queries"], queries, "{r}");
        assert_eq!(r["solved"], queries, "every query solved: {r}");
        assert_eq!(r["recheck_ok"], queries, "every path re-checked free: {r}");
        let ratio = r["median_length_over_straight"].as_f64().unwrap();
        assert!((1.0..3.0).contains(&ratio), "{r}");
        assert!(r["median_first_ms"].as_f64().unwrap() > 0.0, "{r}");
    }
}
