//! What the store tests share: the flights, random intents, the brute-force check over every
//! pair, and the conformance tests every [`IntentStore`] passes (run on SQLite by
//! `tests/store.rs`, on PostgreSQL by `tests/postgres.rs`).
#![allow(dead_code)]

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_airspace::*;
use skyplan_airspace_store::{Insert, IntentStore, StoreError, new_id};
use skyplan_plan::{PlanRequest, Session, World};
use std::io::Write;
use std::path::Path;
use std::sync::OnceLock;

pub fn t0() -> Timestamp {
    "2026-03-01T12:00:00Z".parse().expect("a time")
}
/// Flights crossing the city both ways and diagonally, at 10, 40 and 70 m (bands apart).
pub fn flights() -> &'static [FlightVolumes] {
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
pub fn random_intent(
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
pub fn assert_deconflicted(stored: &[OperationalIntent]) {
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

/// Stores, reads, lists, refuses and deletes on an empty `store`.
pub fn it_keeps_gets_lists_and_deletes(store: &dyn IntentStore) {
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

/// On an empty `store`: the index finds what a full scan finds.
pub fn the_index_finds_what_a_full_scan_finds(store: &dyn IntentStore) {
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
            let by_scan = conflicts(&probe, &store.list().expect("listed"), rule);
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

/// On an empty `store`: `nearby_rows` names exactly the intents `nearby` reads (ids, versions,
/// order), by rows that `get_rows` reads back as those intents; a deleted intent's row is
/// named and read no more, and a row number is never given again.
pub fn rows_name_what_nearby_reads(store: &dyn IntentStore) {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..80 {
        let i = random_intent(&mut rng, 1_800_000, 3, "crowd");
        store
            .insert_if_clear(&i, PriorityRule::EqualOrHigher)
            .expect("checked");
    }
    let mut named = 0;
    let mut last_probe = None;
    for _ in 0..60 {
        let probe = random_intent(&mut rng, 1_800_000, 3, "probe");
        let read = store.nearby(&probe.volumes, 300_000).expect("read");
        let rows = store.nearby_rows(&probe.volumes, 300_000).expect("rows");
        let refs: Vec<(String, u64)> = rows.iter().map(|r| (r.id.clone(), r.version)).collect();
        let want: Vec<(String, u64)> = read.iter().map(|i| (i.id.clone(), i.version)).collect();
        assert_eq!(refs, want);
        assert!(rows.windows(2).all(|w| w[0].row < w[1].row), "store order");
        let numbers: Vec<i64> = rows.iter().rev().map(|r| r.row).collect();
        let back = store.get_rows(&numbers).expect("read back");
        assert_eq!(back.iter().map(|b| b.0).collect::<Vec<_>>(), {
            let mut n = numbers.clone();
            n.reverse();
            n
        });
        assert_eq!(back.into_iter().map(|b| b.1).collect::<Vec<_>>(), read);
        named += rows.len();
        if !rows.is_empty() {
            last_probe = Some((probe, rows));
        }
    }
    assert!(named > 100, "{named} named");
    let (probe, rows) = last_probe.expect("some probe met the crowd");
    let gone = &rows[0];
    assert!(store.delete(&gone.id).expect("deleted").is_some());
    let after = store.nearby_rows(&probe.volumes, 300_000).expect("rows");
    assert!(!after.contains(gone));
    assert_eq!(after.len(), rows.len() - 1);
    assert!(store.get_rows(&[gone.row]).expect("read").is_empty());
    // A new intent takes a new row, above every row given before (the deleted one's too).
    let fresh = random_intent(&mut rng, 1_800_000, 3, "late");
    if let Insert::Accepted { .. } = store
        .insert_if_clear(&fresh, PriorityRule::Every)
        .expect("checked")
    {
        let r = store.nearby_rows(&fresh.volumes, 0).expect("rows");
        let mine = r.iter().find(|r| r.id == fresh.id).expect("named");
        assert!(rows.iter().all(|o| o.row < mine.row), "a row number reused");
    }
}

/// On an empty `store`: a reservation leaves at the earliest free departure or names its
/// blockers.
pub fn a_reservation_leaves_at_the_earliest_free_departure_or_names_its_blockers(
    store: &dyn IntentStore,
) {
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
        skyplan_airspace_store::reserve(store, flight, &r)
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

/// Inserts `intents` through a store of its own opened at `url`; how many it stored.
pub fn insert_all(url: &str, intents: &[OperationalIntent]) -> usize {
    let store = skyplan_airspace_store::open_url(url).expect("a connection");
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

/// Four threads, each with a store of its own on `url` (empty), insert crossing intents at
/// once: no two conflicting intents are both accepted (with one priority, and with three).
pub fn concurrent_threads_never_both_accept_conflicting_intents(url: &str) {
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
                .map(|b| s.spawn(|| insert_all(url, b)))
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("a writer"))
                .sum()
        });
        let store = skyplan_airspace_store::open_url(url).expect("read");
        let stored = store.list().expect("listed");
        assert_eq!(stored.len(), accepted);
        assert!(
            accepted > 10 && accepted < 160,
            "{accepted} of 160 accepted"
        );
        assert_deconflicted(&stored);
        // Next round on an empty store.
        for i in stored {
            store.delete(&i.id).expect("deleted");
        }
    }
}

/// Set by [`concurrent_processes_never_both_accept_conflicting_intents`] for its children.
pub const CHILD_DB: &str = "SKYPLAN_STORE_TEST_DB";
pub const CHILD_INTENTS: &str = "SKYPLAN_STORE_TEST_INTENTS";
pub const CHILD_GO: &str = "SKYPLAN_STORE_TEST_GO";

/// A child process's body: nothing unless started by the test below (each test binary has a
/// `child_writer` test that calls it).
pub fn child_writer() {
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
    let accepted = insert_all(&db, &intents);
    println!("child accepted {accepted}");
}

/// Three processes (this test binary again, its `child_writer` test) insert crossing intents
/// into the empty store at `url` at once: what they report accepted is what is stored, and no
/// two stored intents conflict.
pub fn concurrent_processes_never_both_accept_conflicting_intents(url: &str, dir: &Path) {
    skyplan_airspace_store::open_url(url).expect("created");
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let children: Vec<_> = (0..3)
        .map(|w| {
            let batch: Vec<OperationalIntent> = (0..40)
                .map(|_| random_intent(&mut rng, 900_000, 1, &format!("p{w}")))
                .collect();
            let path = dir.join(format!("batch{w}.json"));
            std::fs::write(&path, serde_json::to_string(&batch).expect("JSON")).expect("written");
            std::process::Command::new(std::env::current_exe().expect("this test binary"))
                .args([
                    "--exact",
                    "child_writer",
                    "--nocapture",
                    "--test-threads",
                    "1",
                    "--include-ignored",
                ])
                .env(CHILD_DB, url)
                .env(CHILD_INTENTS, &path)
                .env(CHILD_GO, dir.join("go"))
                .stdout(std::process::Stdio::piped())
                .spawn()
                .expect("a child")
        })
        .collect();
    std::thread::sleep(std::time::Duration::from_millis(300));
    std::fs::write(dir.join("go"), "").expect("the go file");
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
    let stored = skyplan_airspace_store::open_url(url)
        .expect("read")
        .list()
        .expect("listed");
    assert_eq!(stored.len(), accepted);
    assert!(accepted > 5 && accepted < 120, "{accepted} of 120 accepted");
    assert_deconflicted(&stored);
}

/// Set by [`a_killed_writer_loses_nothing_it_acknowledged`] for its child.
pub const KILL_DB: &str = "SKYPLAN_STORE_TEST_KILL_DB";

/// A child that inserts intents into the store at `KILL_DB` until it is killed, printing
/// `acked ID` after each accepted insert has returned (nothing unless started by the test).
pub fn endless_writer() {
    let Ok(db) = std::env::var(KILL_DB) else {
        return;
    };
    let store = skyplan_airspace_store::open_url(&db).expect("a store");
    let mut rng = ChaCha8Rng::seed_from_u64(u64::from(std::process::id()));
    let mut out = std::io::stdout().lock();
    for _ in 0..100_000 {
        // Spread over a month: nearly every one is accepted.
        let i = random_intent(&mut rng, 30 * 86_400_000, 1, "killed");
        if let Insert::Accepted { .. } = store
            .insert_if_clear(&i, PriorityRule::EqualOrHigher)
            .expect("checked")
        {
            writeln!(out, "acked {}", i.id).expect("stdout");
            out.flush().expect("stdout");
        }
    }
}

/// A writer process (this test binary's `endless_writer` test) killed with SIGKILL while it
/// writes: every intent it acknowledged is in the store at `url` afterwards, read back equal
/// by a new store; returns the acknowledged ids.
pub fn a_killed_writer_loses_nothing_it_acknowledged(url: &str) -> Vec<String> {
    use std::io::BufRead;
    skyplan_airspace_store::open_url(url).expect("created");
    let mut child = std::process::Command::new(std::env::current_exe().expect("this test binary"))
        .args([
            "--exact",
            "endless_writer",
            "--nocapture",
            "--test-threads",
            "1",
            "--include-ignored",
        ])
        .env(KILL_DB, url)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("a child");
    let stdout = child.stdout.take().expect("its stdout");
    let mut lines = std::io::BufReader::new(stdout).lines();
    let mut acked = Vec::new();
    for line in lines.by_ref() {
        let line = line.expect("a line");
        if let Some(id) = line.strip_prefix("acked ") {
            acked.push(id.to_string());
            if acked.len() == 60 {
                // SIGKILL, mid-write: it is writing the next one.
                child.kill().expect("killed");
                break;
            }
        }
    }
    // What it acknowledged after the 60th but before the kill landed, still in the pipe.
    let late: Vec<String> = lines
        .map_while(Result::ok)
        .filter_map(|l| l.strip_prefix("acked ").map(str::to_string))
        .collect();
    let status = child.wait().expect("its end");
    assert!(!status.success(), "the writer was killed, not finished");
    assert_eq!(acked.len(), 60, "the writer acknowledged 60 intents first");
    let store = skyplan_airspace_store::open_url(url).expect("reopened");
    let stored = store.list().expect("listed");
    let ids: std::collections::HashSet<&str> = stored.iter().map(|i| i.id.as_str()).collect();
    for id in &acked {
        assert!(ids.contains(id.as_str()), "acknowledged intent {id} lost");
        let back = store.get(id).expect("read").expect("stored");
        back.validate().expect("a whole intent");
    }
    // What it acknowledged after the 60th, before the kill landed, is stored too; and
    // whatever is stored (acknowledged or caught in flight) reads back whole. (How many were
    // stored but not yet acknowledged depends on where the kill lands: not asserted.)
    for id in &late {
        assert!(ids.contains(id.as_str()), "acknowledged intent {id} lost");
    }
    for i in &stored {
        i.validate().expect("a whole intent");
    }
    acked
}

/// `SKYPLAN_TEST_POSTGRES`, or a failure that says how to set it.
pub fn postgres_url() -> String {
    std::env::var("SKYPLAN_TEST_POSTGRES").unwrap_or_else(|_| {
        panic!(
            "SKYPLAN_TEST_POSTGRES is not set: these tests need a PostgreSQL server, e.g. \
             SKYPLAN_TEST_POSTGRES=postgres://postgres@127.0.0.1:5432/postgres (.ci/run starts one)"
        )
    })
}

/// A new, empty database on the test server, named after `tag`, this process and the time:
/// its URL.
pub fn fresh_database(tag: &str) -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let name = format!("skyplan_t_{tag}_{}_{nanos}", std::process::id());
    skyplan_airspace_store::PostgresStore::create_database(&postgres_url(), &name)
        .unwrap_or_else(|e| panic!("{e}"))
}
