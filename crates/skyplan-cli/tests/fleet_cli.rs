//! `skyplan fleet`: a small random fleet planned against a fresh SQLite store accepts no two
//! intents that intersect (every pair re-checked here, independently of the command's own
//! count, with the airspace crate's exact 4D test on the intents read back from the store);
//! the report agrees with the store; bad mission files fail with errors naming the file, the
//! entry and the field, and store nothing.

use assert_cmd::Command;
use serde_json::Value;
use skyplan_airspace::{OperationalIntent, volumes_conflict};
use skyplan_airspace_store::{IntentStore, SqliteStore};

fn skyplan() -> Command {
    Command::cargo_bin("skyplan").expect("the skyplan binary")
}

/// Whether two intents share a point in space and time: every pair of volumes, brute force.
fn intersect(a: &OperationalIntent, b: &OperationalIntent) -> bool {
    a.volumes
        .iter()
        .any(|x| b.volumes.iter().any(|y| volumes_conflict(x, y)))
}

/// All pairs, exact 4D test (all priority 0: every stored intent binds every later one).
fn assert_no_pair_intersects(stored: &[OperationalIntent]) {
    let mut pairs = 0;
    for (i, a) in stored.iter().enumerate() {
        for b in &stored[..i] {
            pairs += 1;
            assert!(
                !intersect(a, b),
                "accepted intents {} and {} intersect",
                a.id,
                b.id
            );
        }
    }
    assert_eq!(pairs, stored.len() * (stored.len() - 1) / 2);
}

#[test]
fn a_random_fleet_stores_no_two_intersecting_intents() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let db = dir.path().join("air.sqlite");
    let report = dir.path().join("report.json");
    let plot = dir.path().join("fleet.png");
    // 40 flights over 10 minutes with 15-minute windows on the small city: many cross.
    skyplan()
        .args([
            "fleet",
            "--random",
            "40",
            "--seed",
            "7",
            "--spread-s",
            "600",
        ])
        .arg("--airspace")
        .arg(format!("sqlite:{}", db.display()))
        .arg("--json")
        .arg(&report)
        .arg("--plot")
        .arg(&plot)
        .assert()
        .success();
    let r: Value = serde_json::from_slice(&std::fs::read(&report).expect("the report"))
        .expect("the report is JSON");
    let flights = r["flights"].as_array().expect("flights");
    assert_eq!(flights.len(), 40);
    let store = SqliteStore::open_url(&format!("sqlite:{}", db.display())).expect("the store");
    let stored = store.list().expect("the intents");
    // Every accepted flight is stored, under its id; nothing else is.
    let accepted: Vec<&str> = flights
        .iter()
        .filter(|f| f["status"] == "accepted")
        .map(|f| {
            f["intent_id"]
                .as_str()
                .expect("an accepted flight's intent id")
        })
        .collect();
    let mut ids: Vec<&str> = stored.iter().map(|i| i.id.as_str()).collect();
    let mut want = accepted.clone();
    ids.sort_unstable();
    want.sort_unstable();
    assert_eq!(ids, want);
    assert_eq!(
        r["summary"]["accepted"].as_u64(),
        Some(accepted.len() as u64)
    );
    // The fleet is dense enough that some departures had to move.
    let delayed = flights
        .iter()
        .filter(|f| f["delay_s"].as_f64().is_some_and(|d| d > 0.0))
        .count();
    assert!(
        delayed > 0,
        "no flight was delayed: the test proves nothing"
    );
    assert!(stored.len() >= 20, "only {} flights accepted", stored.len());
    assert_no_pair_intersects(&stored);
    assert_eq!(r["conflicts"].as_u64(), Some(0));
    // A delayed flight's intent starts its delay later than at its window's start: the
    // departure really moved (the stored volumes, not only the report).
    for f in flights.iter().filter(|f| f["status"] == "accepted") {
        let id = f["intent_id"].as_str().unwrap_or_default();
        let intent = stored.iter().find(|i| i.id == id).expect("stored");
        let departure: skyplan_airspace::Timestamp = f["departure"]
            .as_str()
            .expect("a departure")
            .parse()
            .expect("RFC 3339");
        let first = intent.volumes[0].time_start.value;
        // The first volume starts the time buffer (10 s) before the departure.
        assert_eq!(departure.ms_since(first), 10_000, "flight {id}");
    }
    let png = std::fs::read(&plot).expect("the picture");
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn the_space_time_search_hovers_and_goes_around_and_accepts_more() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let run = |extra: &[&str], name: &str| {
        let db = dir.path().join(format!("{name}.sqlite"));
        let report = dir.path().join(format!("{name}.json"));
        skyplan()
            .args([
                "fleet",
                "--random",
                "40",
                "--seed",
                "7",
                "--spread-s",
                "600",
            ])
            .args(extra)
            .arg("--airspace")
            .arg(format!("sqlite:{}", db.display()))
            .arg("--json")
            .arg(&report)
            .assert()
            .success();
        let r: Value = serde_json::from_slice(&std::fs::read(&report).expect("the report"))
            .expect("the report is JSON");
        let store = SqliteStore::open_url(&format!("sqlite:{}", db.display())).expect("store");
        (r, store.list().expect("the intents"))
    };
    let (r, stored) = run(&["--space-time"], "space-time");
    assert_eq!(r["mode"], "space_time");
    assert_no_pair_intersects(&stored);
    assert_eq!(r["conflicts"].as_u64(), Some(0));
    let flights = r["flights"].as_array().expect("flights");
    let accepted: Vec<&Value> = flights
        .iter()
        .filter(|f| f["status"] == "accepted")
        .collect();
    assert_eq!(stored.len(), accepted.len());
    let hovered = accepted
        .iter()
        .filter(|f| f["hover_s"].as_f64().is_some_and(|h| h > 0.0))
        .count();
    let detoured = accepted
        .iter()
        .filter(|f| f["detour_m"].as_f64().is_some_and(|d| d > 1.0))
        .count();
    assert!(
        hovered > 0 && detoured > 0,
        "{hovered} hovered, {detoured} detoured: the test proves nothing"
    );
    // Each arrives no earlier than alone, its departure is within its window, and without a
    // deadline its arrival is proven the earliest.
    for f in &accepted {
        assert!(f["arrival_delay_s"].as_f64().expect("arrival delay") >= -1e-6);
        assert!(f["delay_s"].as_f64().expect("delay") <= 900.0);
        assert_eq!(f["arrival_gap_s"].as_f64(), Some(0.0));
    }
    assert_eq!(r["summary"]["unproven"].as_u64(), Some(0));
    // A deadline of a millisecond from each flight's start: searches longer than that stop,
    // their flights `timed_out` with nothing stored.
    let (hurried, stored) = run(&["--space-time", "--deadline-ms", "1"], "hurried");
    let timed_out: Vec<&Value> = hurried["flights"]
        .as_array()
        .expect("flights")
        .iter()
        .filter(|f| f["status"] == "timed_out")
        .collect();
    assert!(!timed_out.is_empty());
    assert_eq!(
        hurried["summary"]["timed_out"].as_u64(),
        Some(timed_out.len() as u64)
    );
    assert!(timed_out.iter().all(|f| {
        f["intent_id"].is_null()
            && f["message"]
                .as_str()
                .is_some_and(|m| m.contains("deadline"))
    }));
    assert_eq!(
        Some(stored.len() as u64),
        hurried["summary"]["accepted"].as_u64()
    );
    // The accepted ones each say how much sooner they could arrive at most; the totals count
    // those not proven the earliest.
    let gaps: Vec<f64> = hurried["flights"]
        .as_array()
        .expect("flights")
        .iter()
        .filter(|f| f["status"] == "accepted")
        .map(|f| f["arrival_gap_s"].as_f64().expect("a gap"))
        .collect();
    assert!(gaps.iter().all(|&g| g >= 0.0));
    assert_eq!(
        hurried["summary"]["unproven"].as_u64(),
        Some(gaps.iter().filter(|&&g| g > 0.0).count() as u64)
    );
    let (shifted, _) = run(&[], "shift");
    let count = |r: &Value| r["summary"]["accepted"].as_u64().expect("accepted");
    assert!(
        count(&r) >= count(&shifted),
        "space-time {} < shift {}",
        count(&r),
        count(&shifted)
    );
}

#[test]
fn the_baseline_refuses_instead_of_shifting() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let db = dir.path().join("air.sqlite");
    let report = dir.path().join("report.json");
    skyplan()
        .args([
            "fleet",
            "--random",
            "40",
            "--seed",
            "7",
            "--spread-s",
            "600",
            "--reject-on-conflict",
        ])
        .arg("--airspace")
        .arg(format!("sqlite:{}", db.display()))
        .arg("--json")
        .arg(&report)
        .assert()
        .success();
    let r: Value = serde_json::from_slice(&std::fs::read(&report).expect("the report"))
        .expect("the report is JSON");
    let flights = r["flights"].as_array().expect("flights");
    assert!(
        flights
            .iter()
            .filter(|f| f["status"] == "accepted")
            .all(|f| f["delay_s"].as_f64() == Some(0.0))
    );
    let refused: Vec<&Value> = flights
        .iter()
        .filter(|f| f["status"] == "refused")
        .collect();
    assert!(
        !refused.is_empty(),
        "nothing refused: the test proves nothing"
    );
    // Each refused flight names intents that are stored.
    let store = SqliteStore::open_url(&format!("sqlite:{}", db.display())).expect("the store");
    for f in refused {
        let blocking = f["blocking"].as_array().expect("blocking intents");
        assert!(!blocking.is_empty());
        for b in blocking {
            let id = b["id"].as_str().expect("an id");
            assert!(store.get(id).expect("read").is_some(), "{id} is not stored");
        }
    }
}

#[test]
fn a_mission_file_in_toml_plans_in_order_and_reports_a_table() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let file = dir.path().join("fleet.toml");
    std::fs::write(
        &file,
        "[[missions]]\nid = \"first\"\nstart_ne = [0.0, 0.0]\ngoal_ne = [420.0, 390.0]\n\n\
         [[missions]]\nid = \"second\"\nstart_ne = [0.0, 0.0]\ngoal_ne = [420.0, 390.0]\nwindow_s = 0\n\n\
         [[missions]]\nid = \"third\"\nstart_ne = [0.0, 0.0]\ngoal_ne = [420.0, 390.0]\npriority = 5\n",
    )
    .expect("written");
    let out = skyplan()
        .arg("fleet")
        .arg(&file)
        .args(["--airspace", "sqlite::memory:"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let text = String::from_utf8(out).expect("UTF-8");
    let row = |id: &str| {
        text.lines()
            .find(|l| l.starts_with(id))
            .unwrap_or_else(|| panic!("no row {id} in\n{text}"))
            .to_string()
    };
    // The second takes the same route at the same time with no window: refused, blocked by
    // the first; the third is more important: not bound by the first, accepted at once.
    assert!(row("first").contains("accepted"), "{text}");
    assert!(row("second").contains("refused"), "{text}");
    assert!(row("third").contains("accepted"), "{text}");
    assert!(text.contains("2 accepted"), "{text}");
    assert!(text.contains("conflicts: 0"), "{text}");
}

#[test]
fn bad_mission_files_name_the_file_the_entry_and_the_field() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let cases: &[(&str, &str, &str)] = &[
        (
            "a.json",
            r#"[{"start_ne": [0, 0], "goal_ne": [420]}]"#,
            "a.json: missions[0] (id \"m1\").goal_ne: expected [north_m, east_m], two numbers",
        ),
        (
            "b.json",
            r#"{"missions": [{"start_ne": [0, 0], "goal_ne": [4, 3]}, {"id": "x", "start_ne": [0, 0], "goal_ne": [4, 3], "priority": 101}]}"#,
            "b.json: missions[1] (id \"x\").priority: expected a whole number from 0 to 100",
        ),
        (
            "c.toml",
            "[[missions]]\nstart_ne = [0.0, 0.0]\ngoal_ne = [4.0, 3.0]\nspeed = 3\n",
            "c.toml: missions[0] (id \"m1\").speed: unknown field",
        ),
        (
            "d.json",
            r#"[{"start_ne": [0, 0], "goal_ne": [4, 3], "departure": "2020-01-01T00:00:00Z"}]"#,
            "d.json: missions[0] (id \"m1\").departure: 2020-01-01T00:00:00Z is in the past",
        ),
        (
            "e.json",
            r#"[{"start_ne": [0, 0], "goal_ne": [4, 3], "departure": {"earliest": "soon"}}]"#,
            "e.json: missions[0] (id \"m1\").departure.earliest:",
        ),
        (
            "f.json",
            r#"[{"id": "a", "start_ne": [0, 0], "goal_ne": [4, 3]}, {"id": "a", "start_ne": [0, 0], "goal_ne": [4, 3]}]"#,
            "f.json: missions[1] (id \"a\").id: \"a\" is used by an earlier mission",
        ),
        ("g.json", "[{\"start_ne\": [0, 0],", "g.json: not JSON:"),
        ("h.toml", "[[missions]\n", "h.toml: not TOML:"),
        ("i.json", "[]", "i.json: no missions"),
        (
            "j.json",
            r#"[{"goal_ne": [4, 3]}]"#,
            "j.json: missions[0] (id \"m1\").start_ne: missing: give start_ne or start_lla",
        ),
        (
            "k.yaml",
            "- start_ne: [0, 0]\n",
            "k.yaml: unknown mission file type; expected .json or .toml",
        ),
    ];
    for (name, text, want) in cases {
        let file = dir.path().join(name);
        std::fs::write(&file, text).expect("written");
        let db = dir.path().join(format!("{name}.sqlite"));
        let out = skyplan()
            .arg("fleet")
            .arg(&file)
            .arg("--airspace")
            .arg(format!("sqlite:{}", db.display()))
            .assert()
            .code(2)
            .get_output()
            .clone();
        let err = String::from_utf8_lossy(&out.stderr);
        let shown = format!("error: {}", dir.path().join(want).display());
        assert!(err.contains(&shown), "{name}: expected {shown:?} in\n{err}");
        assert!(!err.contains("panicked"), "{err}");
        // Refused before the store is opened: nothing is stored, no file is made.
        assert!(!db.exists(), "{name}: the store was created");
    }
}

#[test]
fn bad_options_fail_with_exit_2_naming_the_option() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["--airspace", "mysql://x"],
            "error: --airspace mysql://x: airspace mysql://x: expected sqlite:FILE",
        ),
        (
            &[
                "--map",
                "examples/floor.yaml",
                "--airspace",
                "sqlite::memory:",
            ],
            "error: --map examples/floor.yaml: the map has no geodetic home",
        ),
        (
            &[
                "--space-time",
                "--reject-on-conflict",
                "--airspace",
                "sqlite::memory:",
            ],
            "error: --reject-on-conflict and --space-time: choose one",
        ),
        (
            &["--deadline-ms", "50", "--airspace", "sqlite::memory:"],
            "--space-time",
        ),
        (
            &["--space-time", "--deadline-ms", "0"],
            "error: invalid value '0' for '--deadline-ms <MS>'",
        ),
        (
            &["--start", "tomorrow", "--airspace", "sqlite::memory:"],
            "error: --start tomorrow:",
        ),
        (
            &["--plot", "fleet.jpg", "--airspace", "sqlite::memory:"],
            "error: --plot fleet.jpg: expected a .png or .svg file name",
        ),
    ];
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for (args, want) in cases {
        let out = skyplan()
            .current_dir(&root)
            .args(["fleet", "--random", "3"])
            .args(*args)
            .assert()
            .code(2)
            .get_output()
            .clone();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(want), "{args:?}: expected {want:?} in\n{err}");
    }
}
