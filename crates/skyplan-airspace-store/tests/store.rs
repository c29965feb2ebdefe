//! The SQLite store: what it keeps, the index against a full scan, and concurrent writers —
//! threads and processes, each with its own connection to one file — never both accepting
//! intents that conflict (checked by brute force over every pair).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_airspace::*;
use skyplan_airspace_store::{Insert, IntentStore, SqliteStore, StoreError, new_id};
use skyplan_plan::{PlanRequest, Session, World};
use std::path::Path;
use std::sync::OnceLock;

fn t0() -> Timestamp {
    "2026-03-01T12:00:00Z".parse().expect("a time")
}

/// Flights crossing the city both ways and diagonally, at 10, 40 and 70 m (bands apart).
fn flights() -> &'static [FlightVolumes] {
    static FLIGHTS: OnceLock<Vec<FlightVolumes>> = OnceLock::new();
    FLIGHTS.get_or_init(|| {
        let mut session = Session::new(World::fcnd_city());
        let routes = [
            ([0.0, 0.0], [420.0, 390.0]),
            ([420.0, 390.0], [0.0, 0.0]),
            ([300.0, 0.0], [48.5, 399.5]),
            ([48.5, 399.5], [300.0, 0.0]),
        ];
        let mut out = Vec::new();
        for alt in [10.0, 40.0, 70.0] {
            for (s, g) in routes {
                let request = PlanRequest {
                    start_ne: Some(s),
                    goal_ne: Some(g),
                    alt_m: Some(alt),
                    ..Default::default()
                };
                let plan = session
                    .plan(&request)
                    .unwrap_or_else(|e| panic!("{s:?} → {g:?}: {e}"));
                out.push(volumes_from_plan(&plan, &VolumeOptions::default()).expect("volumes"));
            }
        }
        out
    })
}

/// A random intent: one of the flights, leaving within `spread_ms` of t0.
fn random_intent(
    rng: &mut ChaCha8Rng,
    spread_ms: i64,
    priorities: u32,
    owner: &str,
) -> OperationalIntent {
    let f = &flights()[rng.random_range(0..flights().len())];
    OperationalIntent {
        id: new_id(),
        version: 1,
        state: IntentState::Accepted,
        priority: rng.random_range(0..priorities),
        owner: owner.into(),
        volumes: f.at(t0().plus_ms(rng.random_range(0..spread_ms))),
    }
}

/// Every pair of `stored` (in the order stored): two that conflict have the later one of
/// strictly higher priority (with one priority: no two conflict).
fn assert_deconflicted(stored: &[OperationalIntent]) {
    for (j, b) in stored.iter().enumerate() {
        for a in &stored[..j] {
            if first_conflict(&a.volumes, &b.volumes).is_some() {
                assert!(
                    b.priority > a.priority,
                    "{} and {} both accepted, conflicting",
                    a.id,
                    b.id
                );
            }
        }
    }
}

#[test]
fn it_keeps_gets_lists_and_deletes() {
    let store = SqliteStore::memory().expect("a store");
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let a = OperationalIntent {
        priority: 1,
        ..random_intent(&mut rng, 1, 1, "a")
    };
    assert_eq!(
        store
            .insert_if_clear(&a, PriorityRule::EqualOrHigher)
            .expect("stored"),
        Insert::Accepted { checked: 0 }
    );
    assert_eq!(store.get(&a.id).expect("read"), Some(a.clone()));
    // The same flight at the same time, equal priority: refused, naming a's id and version.
    let b = OperationalIntent {
        id: new_id(),
        owner: "b".into(),
        ..a.clone()
    };
    match store
        .insert_if_clear(&b, PriorityRule::EqualOrHigher)
        .expect("checked")
    {
        Insert::Conflicts(c) => assert_eq!(
            c.iter().map(Conflict::reference).collect::<Vec<_>>(),
            [a.reference()]
        ),
        other => panic!("{other:?}"),
    }
    // More important: accepted over a; a duplicate id is refused.
    let urgent = OperationalIntent {
        id: new_id(),
        priority: 2,
        ..b.clone()
    };
    assert_eq!(
        store
            .insert_if_clear(&urgent, PriorityRule::EqualOrHigher)
            .expect("stored"),
        Insert::Accepted { checked: 1 }
    );
    assert!(matches!(
        store.insert_if_clear(&urgent, PriorityRule::Every),
        Err(StoreError::Duplicate(_))
    ));
    assert_eq!(store.list().expect("listed"), [a.clone(), urgent.clone()]);
    assert_eq!(store.delete(&a.id).expect("deleted"), Some(a.clone()));
    assert_eq!(store.delete(&a.id).expect("nothing"), None);
    assert_eq!(store.get(&a.id).expect("read"), None);
    // An invalid intent never reaches the table.
    let mut bad = OperationalIntent {
        id: new_id(),
        ..a.clone()
    };
    bad.volumes[0].volume.outline_polygon.vertices.truncate(2);
    assert!(matches!(
        store.insert_if_clear(&bad, PriorityRule::Every),
        Err(StoreError::Invalid(_))
    ));
    assert_eq!(store.list().expect("listed").len(), 1);
}

#[test]
fn a_file_keeps_its_intents_and_refuses_another_schema() {
    let dir = tempfile::tempdir().expect("a folder");
    let file = dir.path().join("airspace.db");
    let url = format!("sqlite:{}", file.display());
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let a = random_intent(&mut rng, 1, 1, "a");
    {
        let store = SqliteStore::open_url(&url).expect("a store");
        assert!(matches!(
            store.insert_if_clear(&a, PriorityRule::Every),
            Ok(Insert::Accepted { .. })
        ));
    }
    let store = SqliteStore::open(&file).expect("reopened");
    assert_eq!(store.list().expect("listed"), [a]);
    drop(store);
    python_sqlite(
        &file,
        "UPDATE meta SET value = '99' WHERE key = 'schema_version'",
    );
    assert_eq!(
        SqliteStore::open(&file)
            .expect_err("another version")
            .to_string(),
        "the airspace store has schema version 99; this skyplan reads version 1"
    );
    for bad in ["postgres://x", "sqlite:", "file.db"] {
        assert!(
            matches!(SqliteStore::open_url(bad), Err(StoreError::Address(_))),
            "{bad}"
        );
    }
}

/// Runs `sql` on the database at `file` through Python's sqlite3 (another SQLite than the
/// store's).
fn python_sqlite(file: &Path, sql: &str) {
    let out = std::process::Command::new("python3")
        .args(["-c", "import sqlite3, sys; c = sqlite3.connect(sys.argv[1]); c.execute(sys.argv[2]); c.commit()"])
        .arg(file)
        .arg(sql)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_index_finds_what_a_full_scan_finds() {
    let store = SqliteStore::memory().expect("a store");
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    // Crowd the store (priorities 0..3; an accepted intent may overlap a less important one).
    let mut stored = 0;
    for _ in 0..150 {
        let i = random_intent(&mut rng, 1_800_000, 3, "crowd");
        if let Insert::Accepted { .. } = store
            .insert_if_clear(&i, PriorityRule::EqualOrHigher)
            .expect("checked")
        {
            stored += 1;
        }
    }
    assert!(stored > 20, "{stored} stored");
    let (mut some, mut none) = (0, 0);
    for _ in 0..150 {
        let probe = random_intent(&mut rng, 1_800_000, 3, "probe");
        for rule in [PriorityRule::EqualOrHigher, PriorityRule::Every] {
            let by_index = store.check(&probe, rule).expect("checked");
            let by_scan = store.check_full_scan(&probe, rule).expect("scanned");
            let ids = |c: &[Conflict]| {
                let mut v: Vec<_> = c.iter().map(Conflict::reference).collect();
                v.sort();
                v
            };
            assert_eq!(ids(&by_index), ids(&by_scan));
            if by_scan.is_empty() {
                none += 1
            } else {
                some += 1
            }
        }
        // Widened windows: nearby holds every intent the flight meets leaving up to 10 min later.
        let later = 600_000;
        let nearby: Vec<String> = store
            .nearby(&probe.volumes, later)
            .expect("read")
            .into_iter()
            .map(|i| i.id)
            .collect();
        for s in store.list().expect("listed") {
            let meets = (0..=later / 30_000).any(|k| {
                let moved: Vec<Volume4D> = probe
                    .volumes
                    .iter()
                    .map(|v| v.shifted_ms(k * 30_000))
                    .collect();
                first_conflict(&moved, &s.volumes).is_some()
            });
            assert!(
                !meets || nearby.contains(&s.id),
                "{} missing from nearby",
                s.id
            );
        }
    }
    assert!(
        some > 30 && none > 30,
        "{some} with conflicts, {none} without"
    );
    assert_deconflicted(&store.list().expect("listed"));
}

/// Inserts `intents` through a connection of its own to `file`; how many it stored.
fn insert_all(file: &Path, intents: &[OperationalIntent]) -> usize {
    let store = SqliteStore::open(file).expect("a connection");
    intents
        .iter()
        .filter(|i| {
            matches!(
                store
                    .insert_if_clear(i, PriorityRule::EqualOrHigher)
                    .expect("checked"),
                Insert::Accepted { .. }
            )
        })
        .count()
}

#[test]
fn concurrent_threads_never_both_accept_conflicting_intents() {
    let dir = tempfile::tempdir().expect("a folder");
    let file = dir.path().join("airspace.db");
    SqliteStore::open(&file).expect("created");
    for (priorities, seed) in [(1, 10), (3, 11)] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let batches: Vec<Vec<OperationalIntent>> = (0..4)
            .map(|w| {
                (0..40)
                    .map(|_| random_intent(&mut rng, 900_000, priorities, &format!("w{w}")))
                    .collect()
            })
            .collect();
        let accepted: usize = std::thread::scope(|s| {
            let handles: Vec<_> = batches
                .iter()
                .map(|b| s.spawn(|| insert_all(&file, b)))
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("a writer"))
                .sum()
        });
        let stored = SqliteStore::open(&file)
            .expect("read")
            .list()
            .expect("listed");
        assert!(
            accepted > 10 && accepted < 160,
            "{accepted} of 160 accepted"
        );
        assert_deconflicted(&stored);
        // Next round on an empty store.
        let store = SqliteStore::open(&file).expect("read");
        for i in stored {
            store.delete(&i.id).expect("deleted");
        }
    }
}

/// Set by the test below for its child processes: the database and the intents to insert.
const CHILD_DB: &str = "SKYPLAN_STORE_TEST_DB";
const CHILD_INTENTS: &str = "SKYPLAN_STORE_TEST_INTENTS";
const CHILD_GO: &str = "SKYPLAN_STORE_TEST_GO";

/// A child process's body (does nothing unless started by the test below).
#[test]
fn child_writer() {
    let (Ok(db), Ok(intents)) = (std::env::var(CHILD_DB), std::env::var(CHILD_INTENTS)) else {
        return;
    };
    let text = std::fs::read_to_string(intents).expect("the intents");
    let intents: Vec<OperationalIntent> = serde_json::from_str(&text).expect("intents");
    // All children start together, when the parent creates the go file.
    let go = std::env::var(CHILD_GO).expect("the go file");
    let waited = std::time::Instant::now();
    while !Path::new(&go).exists() {
        assert!(waited.elapsed().as_secs() < 60, "no go in 60 s");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let accepted = insert_all(Path::new(&db), &intents);
    println!("child accepted {accepted}");
}

#[test]
fn concurrent_processes_never_both_accept_conflicting_intents() {
    let dir = tempfile::tempdir().expect("a folder");
    let file = dir.path().join("airspace.db");
    SqliteStore::open(&file).expect("created");
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let children: Vec<_> = (0..3)
        .map(|w| {
            let batch: Vec<OperationalIntent> = (0..40)
                .map(|_| random_intent(&mut rng, 900_000, 1, &format!("p{w}")))
                .collect();
            let path = dir.path().join(format!("batch{w}.json"));
            std::fs::write(&path, serde_json::to_string(&batch).expect("JSON")).expect("written");
            std::process::Command::new(std::env::current_exe().expect("this test binary"))
                .args([
                    "--exact",
                    "child_writer",
                    "--nocapture",
                    "--test-threads",
                    "1",
                ])
                .env(CHILD_DB, &file)
                .env(CHILD_INTENTS, &path)
                .env(CHILD_GO, dir.path().join("go"))
                .stdout(std::process::Stdio::piped())
                .spawn()
                .expect("a child")
        })
        .collect();
    std::thread::sleep(std::time::Duration::from_millis(300));
    std::fs::write(dir.path().join("go"), "").expect("the go file");
    let mut accepted = 0;
    for child in children {
        let out = child.wait_with_output().expect("a child's end");
        assert!(out.status.success());
        let text = String::from_utf8_lossy(&out.stdout);
        let n: usize = text
            .lines()
            .find_map(|l| l.split_once("child accepted ").map(|(_, n)| n))
            .and_then(|n| n.trim().parse().ok())
            .unwrap_or_else(|| panic!("no count in {text}"));
        accepted += n;
    }
    let stored = SqliteStore::open(&file)
        .expect("read")
        .list()
        .expect("listed");
    assert_eq!(stored.len(), accepted);
    assert!(accepted > 5 && accepted < 120, "{accepted} of 120 accepted");
    assert_deconflicted(&stored);
}

#[test]
fn a_reservation_leaves_at_the_earliest_free_departure_or_names_its_blockers() {
    let store = SqliteStore::memory().expect("a store");
    let flight = &flights()[0];
    let window = DepartureWindow {
        earliest: t0(),
        latest: t0().plus_ms(1_800_000),
    };
    let reserve = |owner: &str, priority: u32, window: DepartureWindow| {
        let r = skyplan_airspace_store::Reservation {
            window,
            priority,
            owner: owner.into(),
            id: new_id(),
            rule: PriorityRule::EqualOrHigher,
            step_ms: 1000,
        };
        skyplan_airspace_store::reserve(&store, flight, &r)
    };
    let first = reserve("a", 1, window).expect("free");
    assert_eq!(
        (first.departure, first.delay_ms, first.nearby, first.tries),
        (t0(), 0, 0, 1)
    );
    // The same flight again: it leaves once the first is clear of it, on the second grid.
    let second = reserve("b", 1, window).expect("later");
    assert!(
        second.delay_ms > 0 && second.delay_ms % 1000 == 0,
        "{}",
        second.delay_ms
    );
    assert_eq!(second.nearby, 1);
    let moved: Vec<Volume4D> = flight.at(second.departure.plus_ms(-1000));
    assert!(
        first_conflict(&moved, &first.intent.volumes).is_some(),
        "one second earlier conflicts"
    );
    assert_deconflicted(&store.list().expect("listed"));
    // A window of one instant at t0: blocked by the first (and the second, if it meets it then).
    let at_t0 = DepartureWindow::at(t0());
    match reserve("c", 1, at_t0) {
        Err(skyplan_airspace_store::ReserveError::Blocked(b)) => {
            assert!(b.blocking.contains(&first.intent.reference()))
        }
        other => panic!("{other:?}"),
    }
    // More important: it leaves at once.
    assert_eq!(reserve("d", 2, at_t0).expect("urgent").delay_ms, 0);
}
