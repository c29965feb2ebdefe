//! The SQLite store: the conformance tests of every store (tests/common), a file that keeps
//! its intents and refuses another schema, concurrent writers — threads and processes, each
//! with its own connection to one file — never both accepting intents that conflict
//! (checked by brute force over every pair), and a writer killed with SIGKILL mid-write
//! losing nothing it acknowledged.

mod common;

use common::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use skyplan_airspace::*;
use skyplan_airspace_store::{Insert, IntentStore, SqliteStore, StoreError};
use std::path::Path;

#[test]
fn it_keeps_gets_lists_and_deletes() {
    common::it_keeps_gets_lists_and_deletes(&SqliteStore::memory().expect("a store"));
}

#[test]
fn the_index_finds_what_a_full_scan_finds() {
    common::the_index_finds_what_a_full_scan_finds(&SqliteStore::memory().expect("a store"));
}

#[test]
fn rows_name_what_nearby_reads() {
    common::rows_name_what_nearby_reads(&SqliteStore::memory().expect("a store"));
}

#[test]
fn a_reservation_leaves_at_the_earliest_free_departure_or_names_its_blockers() {
    common::a_reservation_leaves_at_the_earliest_free_departure_or_names_its_blockers(
        &SqliteStore::memory().expect("a store"),
    );
}

#[test]
fn concurrent_threads_never_both_accept_conflicting_intents() {
    let dir = tempfile::tempdir().expect("a folder");
    let url = format!("sqlite:{}", dir.path().join("airspace.db").display());
    common::concurrent_threads_never_both_accept_conflicting_intents(&url);
}

/// A child process's body (does nothing unless started by the test below).
#[test]
fn child_writer() {
    common::child_writer();
}

#[test]
fn concurrent_processes_never_both_accept_conflicting_intents() {
    let dir = tempfile::tempdir().expect("a folder");
    let url = format!("sqlite:{}", dir.path().join("airspace.db").display());
    common::concurrent_processes_never_both_accept_conflicting_intents(&url, dir.path());
}

/// The killed child's body (does nothing unless started by the test below).
#[test]
fn endless_writer() {
    common::endless_writer();
}

#[test]
fn a_writer_killed_mid_write_loses_nothing_it_acknowledged() {
    let dir = tempfile::tempdir().expect("a folder");
    let file = dir.path().join("airspace.db");
    let acked = common::a_killed_writer_loses_nothing_it_acknowledged(&format!(
        "sqlite:{}",
        file.display()
    ));
    // Another SQLite (Python's) finds the file whole and every acknowledged row in it.
    let out = std::process::Command::new("python3")
        .args([
            "-c",
            "import sqlite3, sys; c = sqlite3.connect(sys.argv[1]); print(c.execute('PRAGMA integrity_check').fetchone()[0]); print('\\n'.join(r[0] for r in c.execute('SELECT id FROM intents')))",
        ])
        .arg(&file)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("ok"), "integrity_check");
    let rows: Vec<&str> = lines.collect();
    for id in &acked {
        assert!(rows.contains(&id.as_str()), "{id} not in the file");
    }
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
