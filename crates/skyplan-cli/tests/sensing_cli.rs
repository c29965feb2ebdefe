//! Obstacles the map does not have (`--hidden`), the simulated sensor's OBSTACLE_DISTANCE read by
//! an independent MAVLink client (pymavlink), and flights through the true world.

mod common;

use common::{Run, SimProcess, python, run_args as run};
use std::path::Path;

const HEADER: &str =
    "lat0 37.792480, lon0 -122.397450\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n";

fn write(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// `fly --sim` at 50× from home to N 60, E 30 with one hidden box (a colliders line) in the
/// simulated world, and `extra` arguments; the exit code must be `code`.
fn fly_to_60_30(dir: &Path, hidden_box: &str, extra: &[&str], code: i32) -> Run {
    let hidden = &write(dir, "hidden.csv", &format!("{HEADER}{hidden_box}\n"));
    let line = [
        "fly",
        "--sim",
        "--speedup",
        "50",
        "--goal-ne",
        "60,30",
        "--hidden",
    ];
    let args: Vec<&str> = line
        .into_iter()
        .chain([hidden, "--timeout-s", "60"])
        .chain(extra.iter().copied())
        .collect();
    let r = run(dir, &args);
    r.expect_code(code);
    r
}

#[test]
fn fly_sim_lands_past_a_hidden_box_off_the_route() {
    let dir = tempfile::tempdir().unwrap();
    // 60 m south-west of home: the route to (60, 30) goes north-east.
    let r = fly_to_60_30(dir.path(), "-40,-40,10,3,3,10", &[], 0);
    assert!(r.stdout.contains("no collision"), "{}", r.stdout);
}

#[test]
fn a_hidden_box_on_the_route_without_a_watcher_is_a_collision_in_the_true_world() {
    let dir = tempfile::tempdir().unwrap();
    // A 20 m tower on the goal itself, and no replanner watching: the vehicle flies into it at
    // 5 m.
    let r = fly_to_60_30(dir.path(), "60,30,10,3,3,10", &["--replanner", "off"], 1);
    assert!(r.stdout.contains("track      COLLISION"), "{}", r.stdout);
    assert!(r.stderr.contains("hit obstacle"), "{}", r.stderr);
    // With the replanner (the default) it climbs over the tower and lands on its roof.
    let r = fly_to_60_30(dir.path(), "60,30,10,3,3,10", &[], 0);
    assert!(r.stdout.contains("climbing to 20.0 m"), "{}", r.stdout);
    assert!(
        r.stdout.contains(", 20.05 m above home, disarmed"),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains("no collision"), "{}", r.stdout);
}

#[test]
fn hidden_files_must_share_the_maps_home_and_ranges_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let other = write(
        dir.path(),
        "other.csv",
        "lat0 37.0, lon0 -122.0\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n1,1,1,1,1,1\n",
    );
    let r = run(dir.path(), &["fly", "--sim", "--hidden", &other]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(
        r.stderr.contains("other.csv") && r.stderr.contains("not the map's home"),
        "{}",
        r.stderr
    );
    let bad = write(dir.path(), "bad.csv", &format!("{HEADER}1,2,x,1,1,1\n"));
    let r = run(dir.path(), &["sim", "--hidden", &bad, "--duration-s", "1"]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(
        r.stderr.contains("bad.csv") && r.stderr.contains("line 3"),
        "{}",
        r.stderr
    );
    let r = run(
        dir.path(),
        &["sim", "--sensor-range-m", "0", "--duration-s", "1"],
    );
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.stderr.contains("--sensor-range-m"), "{}", r.stderr);
}

#[test]
#[ignore = "needs Python with pymavlink (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn pymavlink_reads_obstacle_distance_from_skyplan_sim() {
    let dir = tempfile::tempdir().unwrap();
    // A map with one box far away, and one hidden box whose west face is 25 m due east of home (grid east; the
    // sector is true east, 0.37° off: 25 / cos 0.37° = 25.0005 m → 2500 cm).
    let map = write(
        dir.path(),
        "far.csv",
        &format!("{HEADER}-500,-500,5,1,1,5\n"),
    );
    let hidden = write(
        dir.path(),
        "hidden.csv",
        &format!("{HEADER}0,27,10,10,2,10\n"),
    );
    let sim = SimProcess::start(&[
        "--map",
        &map,
        "--hidden",
        &hidden,
        "--ekf-delay-s",
        "0",
        "--speedup",
        "2",
        "--duration-s",
        "60",
    ]);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/sensing/obstacle_distance_peer.py"
    );
    let out = std::process::Command::new(python())
        .args([script, &sim.address, "2500", "18"])
        .output()
        .unwrap();
    drop(sim);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for expected in ["east sector reads", "western half reads no obstacle", "OK"] {
        assert!(stdout.contains(expected), "missing {expected:?}:\n{stdout}");
    }
}
