//! [`PostgresStore`]: the store in PostgreSQL (and, by design, CockroachDB).
//!
//! Every write is one `SERIALIZABLE` transaction, retried (at most [`SERIALIZABLE_TRIES`]
//! times, with a random growing pause) when the database aborts it with a serialization
//! failure (SQLSTATE `40001`) or a deadlock (`40P01`). Serializable isolation makes the
//! check-and-insert atomic across connections and processes: two transactions that each read
//! the index keys the other writes cannot both commit. No PostgreSQL-only feature is used
//! (no advisory locks, no `ON CONFLICT`, no PL/pgSQL): `BIGSERIAL`, `unnest` of several
//! arrays and `= ANY` are understood by CockroachDB as well.

use crate::tls::Transport;
use crate::{Insert, IntentStore, SCHEMA_VERSION, StoreError, StoredRow, index_keys, version_of};
use postgres::error::SqlState;
use postgres::{Client, IsolationLevel, NoTls, Statement};
use skyplan_airspace::{Conflict, OperationalIntent, PriorityRule, Volume4D, conflicts};
use std::collections::BTreeSet;
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};
use std::time::Duration;

/// Connections one [`PostgresStore`] opens at most; more callers wait for one.
pub const MAX_CONNECTIONS: usize = 8;

/// How many times a transaction aborted by a serialization failure is run again.
pub const SERIALIZABLE_TRIES: usize = 60;

/// The connect timeout when the address gives none, seconds.
const CONNECT_TIMEOUT_S: u64 = 5;

const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS airspace_meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS airspace_intents (
    seq BIGSERIAL PRIMARY KEY,
    id TEXT NOT NULL UNIQUE,
    version BIGINT NOT NULL,
    state TEXT NOT NULL,
    priority BIGINT NOT NULL,
    owner TEXT NOT NULL,
    time_start_ms BIGINT NOT NULL,
    time_end_ms BIGINT NOT NULL,
    body TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS airspace_intent_keys (
    cell BIGINT NOT NULL,
    bucket BIGINT NOT NULL,
    seq BIGINT NOT NULL REFERENCES airspace_intents(seq) ON DELETE CASCADE,
    PRIMARY KEY (cell, bucket, seq)
);
CREATE INDEX IF NOT EXISTS airspace_intent_keys_seq ON airspace_intent_keys(seq);
";

/// The intents under any of the keys `(cells[i], buckets from[i] to to[i])`, in store order.
const CANDIDATES: &str = "SELECT i.id, i.body FROM airspace_intents i WHERE i.seq IN (
    SELECT k.seq FROM airspace_intent_keys k
    JOIN unnest($1::BIGINT[], $2::BIGINT[], $3::BIGINT[]) AS q(cell, b0, b1)
      ON k.cell = q.cell AND k.bucket >= q.b0 AND k.bucket <= q.b1
) ORDER BY i.seq";

/// The rows under any of the keys, as [`CANDIDATES`], without their bodies.
const CANDIDATE_ROWS: &str =
    "SELECT i.seq, i.id, i.version FROM airspace_intents i WHERE i.seq IN (
    SELECT k.seq FROM airspace_intent_keys k
    JOIN unnest($1::BIGINT[], $2::BIGINT[], $3::BIGINT[]) AS q(cell, b0, b1)
      ON k.cell = q.cell AND k.bucket >= q.b0 AND k.bucket <= q.b1
) ORDER BY i.seq";

/// Operational intents in a PostgreSQL database (or CockroachDB), shared by every process
/// that opens the same database. Holds up to [`MAX_CONNECTIONS`] connections; each call takes
/// one for its duration, and a connection that broke is replaced on the next call.
///
/// The calls block: call them from a thread that may block (in tokio, `spawn_blocking`),
/// not from async code.
pub struct PostgresStore {
    config: postgres::Config,
    transport: Transport,
    /// Where the server's certificate is checked against, with TLS.
    roots: Option<String>,
    place: String,
    pool: Mutex<PoolState>,
    freed: Condvar,
}

struct PoolState {
    idle: Vec<Conn>,
    open: usize,
}

/// A connection and its prepared statements.
struct Conn {
    client: Client,
    /// Set just before a commit is sent: past it a broken connection leaves the outcome
    /// unknown, so the work is not run again.
    committing: bool,
    exists: Statement,
    candidates: Statement,
    candidate_rows: Statement,
    rows: Statement,
    insert: Statement,
    insert_keys: Statement,
    get: Statement,
    list: Statement,
    find: Statement,
    delete: Statement,
}

impl std::fmt::Debug for PostgresStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PostgresStore({})", self.place)
    }
}

/// Drops clients on a thread of their own: a client closes its connection through a runtime
/// of its own, which may not run inside an async context.
fn discard(clients: Vec<Conn>) {
    if clients.is_empty() {
        return;
    }
    let _ = std::thread::spawn(move || drop(clients)).join();
}

/// Whether `e` asks for the transaction to be run again.
fn is_retryable(e: &postgres::Error) -> bool {
    matches!(
        e.code(),
        Some(c) if *c == SqlState::T_R_SERIALIZATION_FAILURE || *c == SqlState::T_R_DEADLOCK_DETECTED
    )
}

/// What went wrong in one attempt.
enum Failure {
    /// The database's error.
    Db(postgres::Error),
    /// The store's own refusal (duplicate, corrupt body…): not retried.
    Store(StoreError),
}

impl From<postgres::Error> for Failure {
    fn from(e: postgres::Error) -> Self {
        Self::Db(e)
    }
}

impl From<StoreError> for Failure {
    fn from(e: StoreError) -> Self {
        Self::Store(e)
    }
}

impl PostgresStore {
    /// Connects to the database at `url` (`postgres://…` or `postgresql://…`, libpq's URL
    /// form), creates the tables if they are missing and checks the schema version.
    ///
    /// TLS: `sslmode=require`, `verify-ca` or `verify-full`, `sslrootcert=FILE` (PEM CA
    /// certificates) or a client certificate (`sslcert=FILE&sslkey=FILE`, PEM) make every
    /// connection TLS, the server's certificate and host name checked against `FILE` or the
    /// public web CAs; without any of them (or with `sslmode=disable` or `prefer`) connections
    /// are plain.
    ///
    /// Errors: [`StoreError::Address`] for a URL that does not parse, a TLS parameter of an
    /// unknown value, given twice or in conflict, or a certificate or key file that cannot be
    /// read or holds none,
    /// [`StoreError::Down`] when the server cannot be reached (within 5 s unless the URL
    /// sets `connect_timeout`), [`StoreError::Schema`] for a database of another schema
    /// version.
    pub fn open_url(url: &str) -> Result<Self, StoreError> {
        if !(url.starts_with("postgres://") || url.starts_with("postgresql://")) {
            return Err(StoreError::Address(url.into()));
        }
        let (mut config, tls) = parse_url(url)?;
        if config.get_connect_timeout().is_none() {
            config.connect_timeout(Duration::from_secs(CONNECT_TIMEOUT_S));
        }
        let place = place_of(&config);
        let store = Self {
            config,
            transport: tls.transport,
            roots: tls.roots,
            place,
            pool: Mutex::new(PoolState {
                idle: Vec::new(),
                open: 0,
            }),
            freed: Condvar::new(),
        };
        // Connect (and set the schema up) on a thread of its own, so that opening works from
        // async code too.
        let first = std::thread::scope(|s| {
            s.spawn(|| store.connect_and_setup())
                .join()
                .unwrap_or_else(|_| {
                    Err(StoreError::Down {
                        place: store.place.clone(),
                        why: "the connecting thread panicked".into(),
                    })
                })
        })?;
        {
            let mut pool = store.lock_pool();
            pool.open = 1;
            pool.idle.push(first);
        }
        Ok(store)
    }

    /// Where the database is: `postgres://USER@HOST:PORT/DB` (no password).
    pub fn place(&self) -> &str {
        &self.place
    }

    /// True when connections are TLS.
    pub fn is_tls(&self) -> bool {
        matches!(self.transport, Transport::Tls(_))
    }

    fn down(&self, e: &postgres::Error) -> StoreError {
        down(&self.place, self.roots.as_deref(), e)
    }

    fn error(&self, e: postgres::Error) -> StoreError {
        if e.is_closed() || e.as_db_error().is_none() {
            self.down(&e)
        } else {
            StoreError::Postgres(describe(&e))
        }
    }

    fn lock_pool(&self) -> MutexGuard<'_, PoolState> {
        self.pool.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// A new connection with the schema checked (created if missing) and the statements
    /// prepared.
    fn connect_and_setup(&self) -> Result<Conn, StoreError> {
        let mut client = connect(&self.config, &self.transport).map_err(|e| self.down(&e))?;
        let mut tries = 0;
        loop {
            tries += 1;
            match setup_schema(&mut client) {
                Ok(None) => break,
                Ok(Some(found)) => {
                    discard_client(client);
                    return Err(StoreError::Schema { found });
                }
                // Two processes creating the tables at once: one wins, the other tries again.
                Err(e)
                    if tries < SERIALIZABLE_TRIES
                        && (is_retryable(&e)
                            || matches!(e.code(), Some(c) if *c == SqlState::UNIQUE_VIOLATION
                                || *c == SqlState::DUPLICATE_TABLE
                                || *c == SqlState::DUPLICATE_OBJECT)) =>
                {
                    backoff(tries)
                }
                Err(e) => {
                    let e = self.error(e);
                    discard_client(client);
                    return Err(e);
                }
            }
        }
        prepare(client).map_err(|e| self.error(e))
    }

    /// Runs `f` on a pooled connection; a serialization failure runs it again (on the same
    /// connection), a connection found broken before any work is replaced once.
    fn with_conn<T>(
        &self,
        mut f: impl FnMut(&mut Conn) -> Result<T, Failure>,
    ) -> Result<T, StoreError> {
        let mut conn = self.acquire()?;
        let mut tries = 0;
        let mut reconnected = false;
        loop {
            tries += 1;
            conn.committing = false;
            match f(&mut conn) {
                Ok(v) => {
                    self.release(conn);
                    return Ok(v);
                }
                Err(Failure::Store(e)) => {
                    self.release(conn);
                    return Err(e);
                }
                Err(Failure::Db(e)) if is_retryable(&e) && tries < SERIALIZABLE_TRIES => {
                    backoff(tries);
                }
                Err(Failure::Db(_))
                    if conn.client.is_closed() && !reconnected && !conn.committing =>
                {
                    // A pooled connection that the server closed (a restart): the attempt
                    // failed before its commit was sent, so nothing was written and it is
                    // safe to run it again on a new connection.
                    self.forget(conn);
                    conn = self.acquire()?;
                    reconnected = true;
                    tries = 0;
                }
                Err(Failure::Db(e)) => {
                    let err = if is_retryable(&e) {
                        StoreError::Contended(tries)
                    } else {
                        self.error(e)
                    };
                    if conn.client.is_closed() {
                        self.forget(conn);
                    } else {
                        self.release(conn);
                    }
                    return Err(err);
                }
            }
        }
    }

    fn acquire(&self) -> Result<Conn, StoreError> {
        let mut pool = self.lock_pool();
        loop {
            if let Some(c) = pool.idle.pop() {
                if !c.client.is_closed() {
                    return Ok(c);
                }
                pool.open -= 1;
                drop(pool);
                discard(vec![c]);
                pool = self.lock_pool();
                continue;
            }
            if pool.open < MAX_CONNECTIONS {
                pool.open += 1;
                drop(pool);
                return self.connect_and_setup().inspect_err(|_| {
                    self.lock_pool().open -= 1;
                    self.freed.notify_one();
                });
            }
            pool = self
                .freed
                .wait(pool)
                .unwrap_or_else(PoisonError::into_inner);
        }
    }

    fn release(&self, conn: Conn) {
        self.lock_pool().idle.push(conn);
        self.freed.notify_one();
    }

    fn forget(&self, conn: Conn) {
        self.lock_pool().open -= 1;
        self.freed.notify_one();
        discard(vec![conn]);
    }

    /// Creates the database `name` on the server at `url` (connecting to the database the URL
    /// names, which must exist) and returns `url` naming `name` instead: for setting up a
    /// fresh airspace, and for tests that each want a database of their own. `name` is
    /// letters, digits and `_`.
    pub fn create_database(url: &str, name: &str) -> Result<String, StoreError> {
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(StoreError::Address(format!(
                "database name {name}: expected letters, digits and _"
            )));
        }
        let (config, tls) = parse_url(url)?;
        let place = place_of(&config);
        std::thread::scope(|s| {
            s.spawn(|| {
                let mut client = connect(&config, &tls.transport)
                    .map_err(|e| down(&place, tls.roots.as_deref(), &e))?;
                let done = client
                    .batch_execute(&format!("CREATE DATABASE {name}"))
                    .map_err(|e| StoreError::Postgres(describe(&e)));
                discard_client(client);
                done
            })
            .join()
            .unwrap_or_else(|_| Err(StoreError::Postgres("the thread panicked".into())))
        })?;
        Ok(with_dbname(url, name))
    }

    /// The stored intents `intent` conflicts with under `rule`, every stored intent read: the
    /// reference the index is tested against.
    pub fn check_full_scan(
        &self,
        intent: &OperationalIntent,
        rule: PriorityRule,
    ) -> Result<Vec<Conflict>, StoreError> {
        let all = self.list()?;
        Ok(conflicts(intent, &all, rule))
    }
}

impl Drop for PostgresStore {
    fn drop(&mut self) {
        let idle = std::mem::take(&mut self.lock_pool().idle);
        discard(idle);
    }
}

/// The client's configuration of `url` and its TLS settings (`crate::tls`).
fn parse_url(url: &str) -> Result<(postgres::Config, crate::tls::Split), StoreError> {
    let tls = crate::tls::split(url, |file| std::fs::read(file))?;
    let config = tls
        .url
        .parse()
        .map_err(|e| StoreError::Address(format!("{} ({e})", redact(url))))?;
    Ok((config, tls))
}

/// The store at `place` is down: the client's error `e`, and with TLS which CAs the server's
/// certificate was checked against (`roots`).
fn down(place: &str, roots: Option<&str>, e: &postgres::Error) -> StoreError {
    let why = match roots {
        Some(roots) => format!(
            "{} (TLS: the server's certificate is checked against {roots})",
            describe(e)
        ),
        None => describe(e),
    };
    StoreError::Down {
        place: place.to_string(),
        why,
    }
}

/// A new client of `config` over `transport`.
fn connect(config: &postgres::Config, transport: &Transport) -> Result<Client, postgres::Error> {
    match transport {
        Transport::Plain => config.connect(NoTls),
        Transport::Tls(tls) => config.connect(tls.clone()),
    }
}

fn discard_client(client: Client) {
    let _ = std::thread::spawn(move || drop(client)).join();
}

/// Sleeps before try `tries + 1`: a random pause up to 1 ms · 2^tries, at most 100 ms.
fn backoff(tries: usize) {
    let cap_us = (1000u64 << tries.min(7)).min(100_000);
    let us = rand::random::<u64>() % cap_us.max(1);
    std::thread::sleep(Duration::from_micros(us));
}

/// The tables created if missing, and the schema version: `None` when it is this build's
/// (written if the database had none), else the version found.
fn setup_schema(client: &mut Client) -> Result<Option<String>, postgres::Error> {
    let mut tx = client
        .build_transaction()
        .isolation_level(IsolationLevel::Serializable)
        .start()?;
    tx.batch_execute(SCHEMA)?;
    let found: Option<String> = tx
        .query_opt(
            "SELECT value FROM airspace_meta WHERE key = 'schema_version'",
            &[],
        )?
        .map(|r| r.get(0));
    match found {
        None => {
            tx.execute(
                "INSERT INTO airspace_meta (key, value) VALUES ('schema_version', $1)",
                &[&SCHEMA_VERSION.to_string()],
            )?;
        }
        Some(v) if v == SCHEMA_VERSION.to_string() => {}
        Some(found) => return Ok(Some(found)),
    }
    tx.commit()?;
    Ok(None)
}

fn prepare(mut client: Client) -> Result<Conn, postgres::Error> {
    Ok(Conn {
        exists: client.prepare("SELECT 1 FROM airspace_intents WHERE id = $1")?,
        candidates: client.prepare(CANDIDATES)?,
        candidate_rows: client.prepare(CANDIDATE_ROWS)?,
        rows: client.prepare(
            "SELECT seq, id, body FROM airspace_intents WHERE seq = ANY($1::BIGINT[]) ORDER BY seq",
        )?,
        insert: client.prepare(
            "INSERT INTO airspace_intents \
             (id, version, state, priority, owner, time_start_ms, time_end_ms, body) \
             VALUES ($1, $2, $3, $4, $5, $6, $7, $8) RETURNING seq",
        )?,
        insert_keys: client.prepare(
            "INSERT INTO airspace_intent_keys (cell, bucket, seq) \
             SELECT c, b, $3 FROM unnest($1::BIGINT[], $2::BIGINT[]) AS t(c, b)",
        )?,
        get: client.prepare("SELECT body FROM airspace_intents WHERE id = $1")?,
        list: client.prepare("SELECT id, body FROM airspace_intents ORDER BY seq")?,
        find: client.prepare("SELECT seq, body FROM airspace_intents WHERE id = $1")?,
        delete: client.prepare("DELETE FROM airspace_intents WHERE seq = $1")?,
        committing: false,
        client,
    })
}

/// `postgres://USER@HOST:PORT/DB` from a configuration: no password.
fn place_of(config: &postgres::Config) -> String {
    let host = match config.get_hosts().first() {
        Some(postgres::config::Host::Tcp(h)) => h.clone(),
        Some(postgres::config::Host::Unix(p)) => p.display().to_string(),
        None => "localhost".into(),
    };
    let port = config.get_ports().first().copied().unwrap_or(5432);
    let user = config.get_user().unwrap_or("");
    let at = if user.is_empty() { "" } else { "@" };
    let db = config.get_dbname().unwrap_or(user);
    format!("postgres://{user}{at}{host}:{port}/{db}")
}

/// `url` with any password replaced by `***`.
fn redact(url: &str) -> String {
    let Some((scheme, rest)) = url.split_once("://") else {
        return url.into();
    };
    let authority_end = rest.find(['/', '?']).unwrap_or(rest.len());
    let (authority, tail) = rest.split_at(authority_end);
    match authority.rsplit_once('@') {
        Some((userinfo, host)) => match userinfo.split_once(':') {
            Some((user, _)) => format!("{scheme}://{user}:***@{host}{tail}"),
            None => url.into(),
        },
        None => url.into(),
    }
}

/// `url` naming the database `name` (its query kept).
fn with_dbname(url: &str, name: &str) -> String {
    let (scheme, rest) = url.split_once("://").unwrap_or(("postgres", url));
    let authority_end = rest.find(['/', '?']).unwrap_or(rest.len());
    let (authority, tail) = rest.split_at(authority_end);
    let query = tail.find('?').map_or("", |q| &tail[q..]);
    format!("{scheme}://{authority}/{name}{query}")
}

/// A database error as `SQLSTATE: message`, another as its text.
fn describe(e: &postgres::Error) -> String {
    match e.as_db_error() {
        Some(db) => format!("{} {}: {}", db.severity(), db.code().code(), db.message()),
        None => {
            let mut text = e.to_string();
            let mut source = std::error::Error::source(e);
            while let Some(s) = source {
                let s = s.to_string();
                if !text.contains(&s) {
                    text = format!("{text}: {s}");
                }
                source = s_source(source);
            }
            text
        }
    }
}

fn s_source<'a>(
    e: Option<&'a (dyn std::error::Error + 'static)>,
) -> Option<&'a (dyn std::error::Error + 'static)> {
    e.and_then(std::error::Error::source)
}

/// The intent in a row's body.
fn read_body(id: &str, body: &str) -> Result<OperationalIntent, StoreError> {
    serde_json::from_str(body).map_err(|e| StoreError::Corrupt {
        id: id.into(),
        why: e.to_string(),
    })
}

/// The keys as three arrays for [`CANDIDATES`].
fn key_arrays(keys: &[(i64, i64, i64)]) -> (Vec<i64>, Vec<i64>, Vec<i64>) {
    (
        keys.iter().map(|k| k.0).collect(),
        keys.iter().map(|k| k.1).collect(),
        keys.iter().map(|k| k.2).collect(),
    )
}

fn rows_to_intents(rows: Vec<postgres::Row>) -> Result<Vec<OperationalIntent>, StoreError> {
    rows.iter()
        .map(|r| read_body(r.get::<_, &str>(0), r.get::<_, &str>(1)))
        .collect()
}

impl IntentStore for PostgresStore {
    fn insert_if_clear(
        &self,
        intent: &OperationalIntent,
        rule: PriorityRule,
    ) -> Result<Insert, StoreError> {
        intent.validate()?;
        let body = serde_json::to_string(intent).map_err(|e| StoreError::Corrupt {
            id: intent.id.clone(),
            why: e.to_string(),
        })?;
        let keys = index_keys(&intent.volumes, 0)?;
        let (cells, b0, b1) = key_arrays(&keys);
        let mut pairs = BTreeSet::new();
        for &(cell, from, to) in &keys {
            for bucket in from..=to {
                pairs.insert((cell, bucket));
            }
        }
        let key_cells: Vec<i64> = pairs.iter().map(|p| p.0).collect();
        let key_buckets: Vec<i64> = pairs.iter().map(|p| p.1).collect();
        let (start, end) = intent.time_bounds().unwrap_or((
            skyplan_airspace::Timestamp::MIN,
            skyplan_airspace::Timestamp::MIN,
        ));
        let version = i64::try_from(intent.version).unwrap_or(i64::MAX);
        let priority = i64::from(intent.priority);
        let (start_ms, end_ms) = (start.unix_ms(), end.unix_ms());
        self.with_conn(|c| {
            let mut tx = c
                .client
                .build_transaction()
                .isolation_level(IsolationLevel::Serializable)
                .start()?;
            if tx.query_opt(&c.exists, &[&intent.id])?.is_some() {
                return Err(StoreError::Duplicate(intent.id.clone()).into());
            }
            let nearby = rows_to_intents(tx.query(&c.candidates, &[&cells, &b0, &b1])?)?;
            let found = conflicts(intent, &nearby, rule);
            if !found.is_empty() {
                tx.rollback()?;
                return Ok(Insert::Conflicts(found));
            }
            let inserted = tx.query_one(
                &c.insert,
                &[
                    &intent.id,
                    &version,
                    &intent.state.name(),
                    &priority,
                    &intent.owner,
                    &start_ms,
                    &end_ms,
                    &body,
                ],
            );
            let seq: i64 = match inserted {
                Ok(row) => row.get(0),
                Err(e) if e.code() == Some(&SqlState::UNIQUE_VIOLATION) => {
                    return Err(StoreError::Duplicate(intent.id.clone()).into());
                }
                Err(e) => return Err(e.into()),
            };
            tx.execute(&c.insert_keys, &[&key_cells, &key_buckets, &seq])?;
            c.committing = true;
            tx.commit()?;
            Ok(Insert::Accepted {
                checked: nearby.len(),
            })
        })
    }

    fn check(
        &self,
        intent: &OperationalIntent,
        rule: PriorityRule,
    ) -> Result<Vec<Conflict>, StoreError> {
        let nearby = self.nearby(&intent.volumes, 0)?;
        Ok(conflicts(intent, &nearby, rule))
    }

    fn nearby(
        &self,
        volumes: &[Volume4D],
        later_ms: i64,
    ) -> Result<Vec<OperationalIntent>, StoreError> {
        let keys = index_keys(volumes, later_ms)?;
        let (cells, b0, b1) = key_arrays(&keys);
        self.with_conn(|c| {
            let rows = c.client.query(&c.candidates, &[&cells, &b0, &b1])?;
            Ok(rows_to_intents(rows)?)
        })
    }

    fn nearby_rows(
        &self,
        volumes: &[Volume4D],
        later_ms: i64,
    ) -> Result<Vec<StoredRow>, StoreError> {
        let keys = index_keys(volumes, later_ms)?;
        let (cells, b0, b1) = key_arrays(&keys);
        self.with_conn(|c| {
            let rows = c.client.query(&c.candidate_rows, &[&cells, &b0, &b1])?;
            let mut out = Vec::with_capacity(rows.len());
            for r in &rows {
                let id: String = r.get(1);
                let version = version_of(&id, r.get(2))?;
                out.push(StoredRow {
                    row: r.get(0),
                    id,
                    version,
                });
            }
            Ok(out)
        })
    }

    fn get_rows(&self, rows: &[i64]) -> Result<Vec<(i64, OperationalIntent)>, StoreError> {
        let rows = rows.to_vec();
        self.with_conn(|c| {
            let found = c.client.query(&c.rows, &[&rows])?;
            let mut out = Vec::with_capacity(found.len());
            for r in &found {
                out.push((
                    r.get(0),
                    read_body(r.get::<_, &str>(1), r.get::<_, &str>(2))?,
                ));
            }
            Ok(out)
        })
    }

    fn get(&self, id: &str) -> Result<Option<OperationalIntent>, StoreError> {
        self.with_conn(|c| {
            let row = c.client.query_opt(&c.get, &[&id])?;
            Ok(row
                .map(|r| read_body(id, r.get::<_, &str>(0)))
                .transpose()?)
        })
    }

    fn list(&self) -> Result<Vec<OperationalIntent>, StoreError> {
        self.with_conn(|c| Ok(rows_to_intents(c.client.query(&c.list, &[])?)?))
    }

    fn delete(&self, id: &str) -> Result<Option<OperationalIntent>, StoreError> {
        self.with_conn(|c| {
            let mut tx = c
                .client
                .build_transaction()
                .isolation_level(IsolationLevel::Serializable)
                .start()?;
            let Some(row) = tx.query_opt(&c.find, &[&id])? else {
                tx.rollback()?;
                return Ok(None);
            };
            let (seq, body): (i64, String) = (row.get(0), row.get(1));
            // The keys go with the intent (ON DELETE CASCADE).
            tx.execute(&c.delete, &[&seq])?;
            c.committing = true;
            tx.commit()?;
            Ok(Some(read_body(id, &body)?))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_are_rewritten_and_redacted() {
        assert_eq!(
            with_dbname("postgres://u:p@h:5/db?sslmode=disable", "t1"),
            "postgres://u:p@h:5/t1?sslmode=disable"
        );
        assert_eq!(with_dbname("postgresql://h", "t2"), "postgresql://h/t2");
        assert_eq!(redact("postgres://u:secret@h/db"), "postgres://u:***@h/db");
        assert_eq!(redact("postgres://u@h/db"), "postgres://u@h/db");
        let config: postgres::Config = "postgres://u:secret@h:5433/db".parse().expect("a URL");
        assert_eq!(place_of(&config), "postgres://u@h:5433/db");
    }
}
