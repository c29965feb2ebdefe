//! `skyplan fly --planner P` flies every planner's route on the built-in simulator: landed,
//! disarmed, every waypoint reached, no collision with the map's boxes.

mod common;
use common::{cmd, ok, python};
use skyplan_plan::{MapKinds, PlannerId};

/// `skyplan fly --sim --speedup 50 --timeout-s 120 LINE` in a new directory: exit code, stdout
/// and stderr together.
fn fly(line: &str) -> (Option<i32>, String) {
    let dir = tempfile::tempdir().unwrap();
    let out = cmd(
        dir.path(),
        &format!("fly --sim --speedup 50 --timeout-s 120 {line}"),
    )
    .output()
    .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.code(), text)
}

/// Whether a planner takes a colliders map, the only kind `fly` flies (an exhaustive match: a new
/// kind of map decides here).
fn takes_colliders(planner: PlannerId) -> bool {
    match planner.info().maps {
        MapKinds::AnyGrid | MapKinds::Obstacles => true,
        // Its table does not fit the city's grid (refused, tested in skyplan-plan).
        MapKinds::SmallGrid => false,
    }
}

/// Every planner of the registry that takes a colliders map, 2D or 3D. On a 5 m grid, so that
/// `ch`'s per-grid preprocessing takes a second, not minutes.
#[test]
fn every_planner_of_the_registry_flies_to_landing() {
    let planners = PlannerId::ALL
        .iter()
        .copied()
        .filter(|&p| takes_colliders(p));
    for planner in planners {
        let (code, text) = fly(&format!("--planner {planner} --cell-m 5 --goal-ne 60,40"));
        assert_eq!(code, Some(0), "{planner}: {text}");
        assert!(
            text.contains("result     landed and disarmed after reaching all"),
            "{planner}: {text}"
        );
        assert!(
            text.contains("no collision with the map's obstacles"),
            "{planner}: {text}"
        );
    }
}

#[test]
fn a_3d_route_is_flown_at_its_altitudes() {
    let (code, text) = fly("--planner rrt-connect --goal-ne 150,-80 --goal-alt-m 25");
    assert_eq!(code, Some(0), "{text}");
    let max_alt: f64 = text
        .lines()
        .find_map(|l| l.split("max altitude ").nth(1))
        .and_then(|rest| rest.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no max altitude in {text}"));
    assert!((24.0..=26.0).contains(&max_alt), "{max_alt} in {text}");
}

/// A goal on a 60 m roof (README's voxel route): the vehicle lands on the roof, not through
/// the building to the street, with no collision; the roof it stands on is not a near miss.
#[test]
fn a_goal_on_a_roof_is_landed_on_the_roof() {
    let (code, text) = fly("--planner voxel --goal-ne 200,330 --goal-alt-m 66");
    assert_eq!(code, Some(0), "{text}");
    let end_alt = common::final_alt_m(&text);
    assert!(
        (60.0..60.2).contains(&end_alt),
        "landed at {end_alt} m: {text}"
    );
    assert!(
        text.contains("no collision with the map's obstacles"),
        "{text}"
    );
}

#[test]
fn fly_refuses_maps_without_boxes() {
    let (code, text) = fly("--random 20x20 --planner jps");
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("colliders map"), "{text}");
}

/// `fly --record`: an MCAP file (magic bytes), read back by the Python `mcap` package with
/// Foxglove's schemas: the route once, the vehicle's location, pose and state along the flight.
#[test]
#[ignore = "needs Python with mcap (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn a_flight_recording_reads_back_with_python_mcap() {
    let dir = tempfile::tempdir().unwrap();
    let out = ok(&mut cmd(
        dir.path(),
        "fly --sim --speedup 5 --goal-ne 60,40 --record flight.mcap --view 127.0.0.1:0",
    ));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("view       http://127.0.0.1:"), "{text}");
    let path = dir.path().join("flight.mcap");
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[..8], b"\x89MCAP0\r\n");
    let script = r#"
import sys, collections
from mcap.reader import make_reader
c = collections.Counter()
for schema, channel, msg in make_reader(open(sys.argv[1], 'rb')).iter_messages():
    c[schema.name] += 1
print(dict(c))
"#;
    let read = ok(assert_cmd::Command::new(python())
        .args(["-c", script])
        .arg(&path));
    let counts = String::from_utf8_lossy(&read.stdout);
    assert!(counts.contains("'foxglove.PosesInFrame': 1"), "{counts}");
    let fixes: usize = counts
        .split("'foxglove.LocationFix': ")
        .nth(1)
        .and_then(|r| r.split([',', '}']).next())
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or(0);
    assert!(fixes >= 10, "{counts}");
}
