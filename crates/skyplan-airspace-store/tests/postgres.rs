//! The PostgreSQL store, on a real server (`SKYPLAN_TEST_POSTGRES`, which `.ci/run` starts;
//! unset, these tests fail and say so): the conformance tests every store passes, each on a
//! database of its own; the schema version; an unreachable server; concurrent writers —
//! threads and processes — never both accepting conflicting intents; a writer killed with
//! SIGKILL losing nothing it acknowledged.

mod common;

use common::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use skyplan_airspace::PriorityRule;
use skyplan_airspace_store::{Insert, IntentStore, PostgresStore, StoreError};

fn fresh_store(tag: &str) -> (String, PostgresStore) {
    let url = fresh_database(tag);
    let store = PostgresStore::open_url(&url).unwrap_or_else(|e| panic!("{e}"));
    (url, store)
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn it_keeps_gets_lists_and_deletes() {
    common::it_keeps_gets_lists_and_deletes(&fresh_store("keeps").1);
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn the_index_finds_what_a_full_scan_finds() {
    common::the_index_finds_what_a_full_scan_finds(&fresh_store("index").1);
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn rows_name_what_nearby_reads() {
    common::rows_name_what_nearby_reads(&fresh_store("rows").1);
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn a_reservation_leaves_at_the_earliest_free_departure_or_names_its_blockers() {
    common::a_reservation_leaves_at_the_earliest_free_departure_or_names_its_blockers(
        &fresh_store("reserve").1,
    );
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn concurrent_threads_never_both_accept_conflicting_intents() {
    let url = fresh_database("threads");
    common::concurrent_threads_never_both_accept_conflicting_intents(&url);
}

/// A child process's body (does nothing unless started by the test below).
#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn child_writer() {
    common::child_writer();
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn concurrent_processes_never_both_accept_conflicting_intents() {
    let dir = tempfile::tempdir().expect("a folder");
    let url = fresh_database("processes");
    common::concurrent_processes_never_both_accept_conflicting_intents(&url, dir.path());
}

/// The killed child's body (does nothing unless started by the test below).
#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn endless_writer() {
    common::endless_writer();
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn a_writer_killed_mid_write_loses_nothing_it_acknowledged() {
    let url = fresh_database("killed");
    common::a_killed_writer_loses_nothing_it_acknowledged(&url);
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn a_database_keeps_its_intents_and_refuses_another_schema() {
    let (url, store) = fresh_store("schema");
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let a = random_intent(&mut rng, 1, 1, "a");
    assert!(matches!(
        store.insert_if_clear(&a, PriorityRule::Every),
        Ok(Insert::Accepted { .. })
    ));
    drop(store);
    // Another connection (postgresql:// works too) finds it.
    let again = PostgresStore::open_url(&url.replacen("postgres://", "postgresql://", 1))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again.list().expect("listed"), [a]);
    // Written by another schema version: refused, saying which.
    psql(
        &url,
        "UPDATE airspace_meta SET value = '99' WHERE key = 'schema_version'",
    );
    assert_eq!(
        PostgresStore::open_url(&url)
            .expect_err("another version")
            .to_string(),
        "the airspace store has schema version 99; this skyplan reads version 1"
    );
    for bad in ["sqlite:x", "postgres://x:notaport/db", "mysql://x"] {
        assert!(
            matches!(PostgresStore::open_url(bad), Err(StoreError::Address(_))),
            "{bad}"
        );
    }
}

/// Runs `sql` on the database at `url` through `psql` (PostgreSQL's own client): its output,
/// unaligned, without headers.
fn psql(url: &str, sql: &str) -> String {
    let out = std::process::Command::new("psql")
        .args([url, "-v", "ON_ERROR_STOP=1", "-tA", "-c", sql])
        .output()
        .expect("psql runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

#[test]
#[ignore = "needs PostgreSQL with TLS (.ci/run starts one)"]
fn tls_connections_are_encrypted_and_check_the_servers_certificate() {
    let ca = std::env::var("SKYPLAN_TEST_POSTGRES_CA")
        .expect("SKYPLAN_TEST_POSTGRES_CA: the test server's CA certificate (.ci/run sets it)");
    let url = fresh_database("tls");
    let app = format!("skyplan_tls_{}", std::process::id());
    let store = PostgresStore::open_url(&format!(
        "{url}?sslmode=verify-full&sslrootcert={ca}&application_name={app}"
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(store.is_tls());
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let a = random_intent(&mut rng, 1, 1, "a");
    assert!(matches!(
        store.insert_if_clear(&a, PriorityRule::Every),
        Ok(Insert::Accepted { .. })
    ));
    assert_eq!(store.list().expect("listed"), [a]);
    // The server's own view (asked over a plain connection): the store's session is TLS.
    assert_eq!(
        psql(
            &format!("{url}?sslmode=disable"),
            &format!(
                "SELECT count(*) || ' ' || bool_and(s.ssl) FROM pg_stat_ssl s \
                 JOIN pg_stat_activity a USING (pid) WHERE a.application_name = '{app}'"
            )
        ),
        "1 true"
    );
    // Checked against the public web CAs instead, the test CA's certificate is refused.
    let e = PostgresStore::open_url(&format!("{url}?sslmode=require")).expect_err("unknown CA");
    assert!(matches!(e, StoreError::Down { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("certificate") && text.contains("checked against the public web CAs"),
        "{text}"
    );
    // A CA file that is not there is named.
    let e = PostgresStore::open_url(&format!("{url}?sslrootcert=/nonexistent/ca.pem"))
        .expect_err("no file");
    assert!(
        matches!(&e, StoreError::Address(why) if why.starts_with("sslrootcert /nonexistent/ca.pem: cannot read it")),
        "{e}"
    );
    // The plain URL still connects, unencrypted.
    assert!(!PostgresStore::open_url(&url).expect("plain").is_tls());
    // The user skyplan_cert, whom the server authenticates by certificate only (`.ci/run`:
    // `hostssl … skyplan_cert … cert`; client.pem and client.key lie beside the CA): in with
    // its certificate, the same intents; refused without it.
    let dir = std::path::Path::new(&ca)
        .parent()
        .expect("the CA's folder")
        .display()
        .to_string();
    let as_cert_user = url.replacen("postgres@", "skyplan_cert@", 1);
    let by_cert = PostgresStore::open_url(&format!(
        "{as_cert_user}?sslmode=verify-full&sslrootcert={ca}&sslcert={dir}/client.pem&sslkey={dir}/client.key"
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        by_cert.list().expect("listed"),
        store.list().expect("listed")
    );
    let e = PostgresStore::open_url(&format!(
        "{as_cert_user}?sslmode=verify-full&sslrootcert={ca}"
    ))
    .expect_err("no client certificate");
    assert!(
        matches!(e, StoreError::Down { .. }) && e.to_string().contains("certificate"),
        "{e}"
    );
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn an_unreachable_server_is_a_clear_error() {
    // A port nothing listens on: bound, then closed.
    let port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").expect("a port");
        l.local_addr().expect("its address").port()
    };
    let url = format!("postgres://someone:secret@127.0.0.1:{port}/airspace");
    let e = PostgresStore::open_url(&url).expect_err("nothing listens");
    assert!(matches!(e, StoreError::Down { .. }), "{e}");
    let text = e.to_string();
    assert!(
        text.starts_with(&format!(
            "the airspace store at postgres://someone@127.0.0.1:{port}/airspace is down: "
        )),
        "{text}"
    );
    assert!(!text.contains("secret"), "{text}");
    // The test server itself is reachable (this test is not passing for a wrong reason).
    postgres_url();
    fresh_store("reach");
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn a_store_whose_database_goes_away_says_it_is_down_then_reconnects() {
    let (url, store) = fresh_store("away");
    let name = url.rsplit('/').next().expect("a database name");
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let a = random_intent(&mut rng, 1, 1, "a");
    assert!(matches!(
        store.insert_if_clear(&a, PriorityRule::Every),
        Ok(Insert::Accepted { .. })
    ));
    // The database refuses connections and its sessions are ended (PostgreSQL's own SQL, run
    // through psql on the server's default database).
    let admin = postgres_url();
    psql(
        &admin,
        &format!(
            "ALTER DATABASE {name} ALLOW_CONNECTIONS false; \
             SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE datname = '{name}'"
        ),
    );
    let b = random_intent(&mut rng, 1, 1, "b");
    for e in [
        store.list().expect_err("down"),
        store
            .insert_if_clear(&b, PriorityRule::Every)
            .expect_err("down"),
    ] {
        assert!(matches!(e, StoreError::Down { .. }), "{e}");
        assert!(e.to_string().contains("is down"), "{e}");
    }
    psql(
        &admin,
        &format!("ALTER DATABASE {name} ALLOW_CONNECTIONS true"),
    );
    // Back: the store connects again; nothing of the refused insert was stored.
    assert_eq!(store.list().expect("listed"), [a]);
    assert!(matches!(
        store.insert_if_clear(&b, PriorityRule::Every),
        Ok(Insert::Accepted { .. })
    ));
}
