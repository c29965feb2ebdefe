//! `skyplan serve` processes sharing one airspace, with the real parts: two servers on one
//! store (a SQLite file; a PostgreSQL database) answering hundreds of concurrent intent
//! requests on crossing routes accept no two intents that intersect (every pair re-checked
//! with the exact 4D test), and every intent acknowledged with 201 is stored; a server killed
//! with SIGKILL mid-run loses no acknowledged intent (a restarted server lists them all); an
//! unreachable database fails `serve` at start-up with a clear error.
//!
//! The PostgreSQL tests need `SKYPLAN_TEST_POSTGRES` (`.ci/run` starts a server and sets it);
//! each makes a database of its own.

use serde_json::{Value, json};
use skyplan_airspace::{OperationalIntent, Timestamp, first_conflict};
use skyplan_airspace_store::PostgresStore;
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

/// A running `skyplan serve`, killed (SIGKILL) when dropped.
struct Server {
    child: Child,
    addr: SocketAddr,
}

impl Server {
    /// Starts `skyplan serve --airspace URL` on a free loopback port; waits for its banner.
    fn start(airspace: &str) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_skyplan"))
            .args([
                "serve",
                "--bind",
                "127.0.0.1:0",
                "--airspace",
                airspace,
                "--max-concurrent",
                "2",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("skyplan serve starts");
        let stdout = child.stdout.take().expect("its stdout");
        let mut lines = BufReader::new(stdout).lines();
        let banner = match lines.next() {
            Some(Ok(line)) => line,
            _ => {
                let mut err = String::new();
                if let Some(mut e) = child.stderr.take() {
                    let _ = e.read_to_string(&mut err);
                }
                panic!("skyplan serve printed no banner: {err}");
            }
        };
        let addr = banner
            .split("http://")
            .nth(1)
            .and_then(|r| r.split('/').next())
            .and_then(|a| a.parse().ok())
            .unwrap_or_else(|| panic!("no address in {banner:?}"));
        // Keep reading its stdout so that it never blocks on a full pipe.
        std::thread::spawn(move || for _ in lines {});
        Self { child, addr }
    }

    /// SIGKILL, and waits for the end.
    fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.kill();
    }
}

/// One HTTP/1.1 request (`Connection: close`): the status and the body as JSON.
fn http(
    addr: SocketAddr,
    method: &str,
    path: &str,
    body: Option<&Value>,
) -> std::io::Result<(u16, Value)> {
    let mut s = TcpStream::connect_timeout(&addr, Duration::from_secs(5))?;
    s.set_read_timeout(Some(Duration::from_secs(120)))?;
    let body = body.map(Value::to_string).unwrap_or_default();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nContent-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    )?;
    let mut text = String::new();
    s.read_to_string(&mut text)?;
    let (head, body) = text
        .split_once("\r\n\r\n")
        .ok_or_else(|| std::io::Error::other(format!("no header end in {text:?}")))?;
    let status = head
        .split(' ')
        .nth(1)
        .and_then(|c| c.parse().ok())
        .ok_or_else(|| std::io::Error::other(format!("no status in {head:?}")))?;
    let json = serde_json::from_str(body).unwrap_or(Value::Null);
    Ok((status, json))
}

/// The crossing routes: both ways across the city and diagonally, at 10 and 40 m.
fn route(k: usize) -> Value {
    let routes = [
        ([0.0, 0.0], [420.0, 390.0]),
        ([420.0, 390.0], [0.0, 0.0]),
        ([300.0, 0.0], [48.5, 399.5]),
        ([48.5, 399.5], [300.0, 0.0]),
    ];
    let (s, g) = routes[k % routes.len()];
    let alt = [10.0, 40.0][(k / routes.len()) % 2];
    json!({ "start_ne": s, "goal_ne": g, "alt_m": alt })
}

/// An intent request on route `k`, leaving within the window that opens at `earliest`.
fn intent_request(k: usize, earliest: Timestamp, window_ms: i64) -> Value {
    json!({
        "plan": route(k),
        "departure": { "earliest": earliest.to_string(), "latest": earliest.plus_ms(window_ms).to_string() },
        "priority": 10,
        "owner": format!("op-{}", k % 5),
    })
}

/// The intent of a 201 answer.
fn intent_of(answer: &Value) -> OperationalIntent {
    serde_json::from_value(answer["intent"].clone()).expect("an intent in a 201")
}

/// No two of `intents` (all of one priority) intersect: every pair, the exact 4D test.
fn assert_no_two_intersect(intents: &[OperationalIntent]) {
    for (j, b) in intents.iter().enumerate() {
        for a in &intents[..j] {
            assert!(
                first_conflict(&a.volumes, &b.volumes).is_none(),
                "{} and {} were both accepted and intersect",
                a.id,
                b.id
            );
        }
    }
}

/// Two servers on `airspace`, `threads` × `each` concurrent intent requests on crossing
/// routes, spread over both: every answer is 201 or 409, no two accepted intents intersect,
/// and what `list` reads from the store afterwards is exactly the acknowledged set.
fn two_servers_accept_no_intersecting_intents(
    airspace: &str,
    list: impl Fn() -> Vec<OperationalIntent>,
) {
    let servers = [Server::start(airspace), Server::start(airspace)];
    let earliest = Timestamp::now().plus_ms(3_600_000);
    let (threads, each) = (16, 20);
    let accepted = Mutex::new(Vec::new());
    let (refused, delayed) = (AtomicUsize::new(0), AtomicUsize::new(0));
    std::thread::scope(|s| {
        for t in 0..threads {
            let (servers, accepted, refused, delayed) = (&servers, &accepted, &refused, &delayed);
            s.spawn(move || {
                for i in 0..each {
                    let k = t * each + i;
                    let server = &servers[k % 2];
                    let (status, answer) = http(
                        server.addr,
                        "POST",
                        "/api/intents",
                        Some(&intent_request(k, earliest, 2_400_000)),
                    )
                    .unwrap_or_else(|e| panic!("request {k}: {e}"));
                    match status {
                        201 => {
                            if answer["delay_s"].as_f64().unwrap_or(0.0) > 0.0 {
                                delayed.fetch_add(1, Ordering::Relaxed);
                            }
                            accepted.lock().expect("the list").push(intent_of(&answer));
                        }
                        409 => {
                            assert!(
                                !answer["conflicts"].as_array().is_none_or(Vec::is_empty),
                                "a 409 names the blocking intents: {answer}"
                            );
                            refused.fetch_add(1, Ordering::Relaxed);
                        }
                        _ => panic!("request {k}: {status} {answer}"),
                    }
                }
            });
        }
    });
    let accepted = accepted.into_inner().expect("the list");
    let (refused, delayed) = (refused.into_inner(), delayed.into_inner());
    assert_eq!(accepted.len() + refused, threads * each);
    // The routes cross: many were moved to a later departure, and the window filled up.
    assert!(accepted.len() >= 20, "{} accepted", accepted.len());
    eprintln!(
        "{} accepted ({delayed} later than asked), {refused} refused",
        accepted.len()
    );
    assert!(delayed >= 20, "{delayed} delayed");
    assert!(refused >= 1, "{refused} refused");
    assert_no_two_intersect(&accepted);
    // The store holds exactly what was acknowledged, unchanged.
    let stored = list();
    let by_id: HashMap<&str, &OperationalIntent> =
        stored.iter().map(|i| (i.id.as_str(), i)).collect();
    assert_eq!(stored.len(), accepted.len());
    for a in &accepted {
        assert_eq!(
            by_id.get(a.id.as_str()),
            Some(&a),
            "{} as acknowledged",
            a.id
        );
    }
    assert_no_two_intersect(&stored);
}

/// A server on `airspace` answering 8 clients is killed with SIGKILL after 30 acknowledged
/// intents; a new server on the same store lists every one of them, unchanged.
fn a_killed_server_loses_no_acknowledged_intent(airspace: &str) {
    let mut server = Server::start(airspace);
    let addr = server.addr;
    let earliest = Timestamp::now().plus_ms(3_600_000);
    let acked = Mutex::new(Vec::new());
    let stop = AtomicBool::new(false);
    std::thread::scope(|s| {
        for t in 0..8 {
            let (acked, stop) = (&acked, &stop);
            s.spawn(move || {
                for i in 0..40 {
                    if stop.load(Ordering::Relaxed) {
                        break;
                    }
                    // Wide windows and four routes at two heights: nearly every one is accepted.
                    let k = t * 40 + i;
                    let start = earliest.plus_ms(i64::try_from(k).unwrap_or(0) * 300_000);
                    match http(
                        addr,
                        "POST",
                        "/api/intents",
                        Some(&intent_request(k, start, 600_000)),
                    ) {
                        Ok((201, answer)) => {
                            acked.lock().expect("the list").push(intent_of(&answer))
                        }
                        Ok((409, _)) => {}
                        Ok((status, answer)) => panic!("{status} {answer}"),
                        // The server was killed.
                        Err(_) => break,
                    }
                }
            });
        }
        let waited = std::time::Instant::now();
        while acked.lock().expect("the list").len() < 30 {
            assert!(
                waited.elapsed() < Duration::from_secs(300),
                "30 acknowledged within 300 s"
            );
            std::thread::sleep(Duration::from_millis(5));
        }
        server.kill();
        stop.store(true, Ordering::Relaxed);
    });
    let acked = acked.into_inner().expect("the list");
    assert!(acked.len() >= 30);
    let again = Server::start(airspace);
    let (status, answer) = http(again.addr, "GET", "/api/intents", None).expect("the list");
    assert_eq!(status, 200, "{answer}");
    let stored: Vec<OperationalIntent> =
        serde_json::from_value(answer["intents"].clone()).expect("intents");
    let by_id: HashMap<&str, &OperationalIntent> =
        stored.iter().map(|i| (i.id.as_str(), i)).collect();
    for a in &acked {
        assert_eq!(
            by_id.get(a.id.as_str()),
            Some(&a),
            "acknowledged intent {} lost",
            a.id
        );
    }
    // At most the requests in flight when it was killed were stored unacknowledged.
    assert!(
        stored.len() <= acked.len() + 8,
        "{} stored, {} acknowledged",
        stored.len(),
        acked.len()
    );
    assert_no_two_intersect(&stored);
}

#[test]
fn two_servers_on_one_sqlite_file_accept_no_intersecting_intents() {
    let dir = tempfile::tempdir().expect("a folder");
    let file = dir.path().join("airspace.db");
    let url = format!("sqlite:{}", file.display());
    two_servers_accept_no_intersecting_intents(&url, || {
        use skyplan_airspace_store::IntentStore;
        skyplan_airspace_store::SqliteStore::open(&file)
            .expect("the file")
            .list()
            .expect("listed")
    });
}

#[test]
fn a_server_on_sqlite_killed_mid_run_loses_no_acknowledged_intent() {
    let dir = tempfile::tempdir().expect("a folder");
    a_killed_server_loses_no_acknowledged_intent(&format!(
        "sqlite:{}",
        dir.path().join("airspace.db").display()
    ));
}

/// `SKYPLAN_TEST_POSTGRES`, or a failure that says how to set it.
fn postgres_url() -> String {
    std::env::var("SKYPLAN_TEST_POSTGRES").unwrap_or_else(|_| {
        panic!(
            "SKYPLAN_TEST_POSTGRES is not set: this test needs a PostgreSQL server, e.g. \
             SKYPLAN_TEST_POSTGRES=postgres://postgres@127.0.0.1:5432/postgres (.ci/run starts one)"
        )
    })
}

/// A new, empty database on the test server: its URL.
fn fresh_database(tag: &str) -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let name = format!("skyplan_cli_{tag}_{}_{nanos}", std::process::id());
    PostgresStore::create_database(&postgres_url(), &name).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn two_servers_on_one_postgres_database_accept_no_intersecting_intents() {
    let url = fresh_database("two");
    two_servers_accept_no_intersecting_intents(&url, || {
        use skyplan_airspace_store::IntentStore;
        PostgresStore::open_url(&url)
            .unwrap_or_else(|e| panic!("{e}"))
            .list()
            .expect("listed")
    });
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn a_server_on_postgres_killed_mid_run_loses_no_acknowledged_intent() {
    a_killed_server_loses_no_acknowledged_intent(&fresh_database("killed"));
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn serve_on_an_unreachable_or_wrong_database_fails_at_start_up_with_a_clear_error() {
    let port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").expect("a port");
        l.local_addr().expect("its address").port()
    };
    let down = format!("postgres://skyplan:secret@127.0.0.1:{port}/airspace");
    let out = Command::new(env!("CARGO_BIN_EXE_skyplan"))
        .args(["serve", "--bind", "127.0.0.1:0", "--airspace", &down])
        .output()
        .expect("skyplan serve runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains(&format!(
            "the airspace store at postgres://skyplan@127.0.0.1:{port}/airspace is down"
        )),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    // A database of another schema version.
    let url = fresh_database("schema");
    drop(PostgresStore::open_url(&url).unwrap_or_else(|e| panic!("{e}")));
    let psql = Command::new("psql")
        .args([
            &url,
            "-c",
            "UPDATE airspace_meta SET value = '7' WHERE key = 'schema_version'",
        ])
        .output()
        .expect("psql runs");
    assert!(
        psql.status.success(),
        "{}",
        String::from_utf8_lossy(&psql.stderr)
    );
    let out = Command::new(env!("CARGO_BIN_EXE_skyplan"))
        .args(["serve", "--bind", "127.0.0.1:0", "--airspace", &url])
        .output()
        .expect("skyplan serve runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("the airspace store has schema version 7; this skyplan reads version 1"),
        "{err}"
    );
}

#[test]
#[ignore = "needs PostgreSQL (.ci/run starts one)"]
fn a_server_whose_database_goes_away_answers_503_saying_the_store_is_down() {
    let url = fresh_database("away");
    let name = url.rsplit('/').next().expect("a database name").to_string();
    let server = Server::start(&url);
    let earliest = Timestamp::now().plus_ms(3_600_000);
    let (status, answer) = http(
        server.addr,
        "POST",
        "/api/intents",
        Some(&intent_request(0, earliest, 0)),
    )
    .expect("an answer");
    assert_eq!(status, 201, "{answer}");
    let first = intent_of(&answer);
    // The database refuses connections and the server's sessions are ended (PostgreSQL's own
    // SQL through psql, on the server's default database).
    let psql = |sql: &str| {
        let out = Command::new("psql")
            .args([&postgres_url(), "-v", "ON_ERROR_STOP=1", "-c", sql])
            .output()
            .expect("psql runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    psql(&format!(
        "ALTER DATABASE {name} ALLOW_CONNECTIONS false; \
         SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE datname = '{name}'"
    ));
    let (status, answer) = http(
        server.addr,
        "POST",
        "/api/intents",
        Some(&intent_request(2, earliest, 0)),
    )
    .expect("an answer");
    assert_eq!(status, 503, "{answer}");
    assert_eq!(answer["kind"], "store_unavailable", "{answer}");
    assert!(answer.to_string().contains("is down"), "{answer}");
    let (status, answer) = http(server.addr, "GET", "/api/intents", None).expect("an answer");
    assert_eq!(
        (status, answer["kind"].as_str()),
        (503, Some("store_unavailable")),
        "{answer}"
    );
    // Back: the same server answers again, and the refused request left nothing behind.
    psql(&format!("ALTER DATABASE {name} ALLOW_CONNECTIONS true"));
    let (status, answer) = http(server.addr, "GET", "/api/intents", None).expect("an answer");
    assert_eq!(status, 200, "{answer}");
    let stored: Vec<OperationalIntent> =
        serde_json::from_value(answer["intents"].clone()).expect("intents");
    assert_eq!(stored, [first]);
}
