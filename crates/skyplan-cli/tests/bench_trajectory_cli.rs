//! `skyplan bench --trajectory`: the table's rows, no violation, the optimised trajectory faster
//! than stopping at each waypoint and never faster than the route at the speed limit; with
//! `--peers`, TOPP-RA and ruckig on the same routes.

mod common;
use common::{cmd, ok};

/// The numbers of the table row whose method starts with `method`: p50 ms, p99 ms, ÷len/v p50,
/// max, ÷stop p50, max, and the violations column.
fn row(text: &str, method: &str) -> (Vec<f64>, String) {
    let line = text
        .lines()
        .find(|l| l.contains(method))
        .unwrap_or_else(|| panic!("no row {method:?} in {text}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    let numbers = words[..6].iter().map(|w| w.parse().unwrap()).collect();
    (numbers, words[6].to_string())
}

#[test]
fn the_trajectory_bench_has_no_violation_and_beats_stopping_at_each_waypoint() {
    let dir = tempfile::tempdir().unwrap();
    let out = ok(&mut cmd(dir.path(), "bench --trajectory --random 3"));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(text.starts_with("trajectory bench: 3 JPS routes"), "{text}");
    let (opt, violations) = row(&text, "skyplan minimum jerk");
    assert_eq!(violations, "0", "{text}");
    assert!(opt[2] >= 1.0 && opt[3] >= opt[2], "÷len/v below 1: {text}");
    assert!(
        opt[4] < 1.0 && opt[5] < 1.0,
        "not faster than stopping: {text}"
    );
    let (stop, violations) = row(&text, "skyplan stop at each waypoint");
    assert_eq!(violations, "0", "{text}");
    assert_eq!((stop[4], stop[5]), (1.0, 1.0), "{text}");
    assert!(text.contains("fallbacks  0 of 3 routes"), "{text}");
}

#[test]
#[ignore = "needs Python with toppra and ruckig (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn toppra_and_ruckig_run_on_the_same_routes() {
    let dir = tempfile::tempdir().unwrap();
    let out = ok(&mut cmd(
        dir.path(),
        "bench --trajectory --random 2 --peers",
    ));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let (toppra, _) = row(&text, "TOPP-RA");
    let (ruckig, _) = row(&text, "ruckig");
    // No parametrisation beats the route at the speed limit; ruckig stops at every waypoint
    // with per-axis limits ÷ √2, so it is no faster than skyplan's stop-at-each-waypoint.
    assert!(toppra[2] >= 1.0 && ruckig[2] >= 1.0, "{text}");
    assert!(ruckig[4] >= 1.0, "{text}");
    assert!(!text.contains("note:"), "a peer failed: {text}");
}
