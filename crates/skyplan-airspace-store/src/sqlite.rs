//! [`SqliteStore`]: the store in SQLite.

use crate::{Insert, IntentStore, SCHEMA_VERSION, StoreError, StoredRow, index_keys, version_of};
use rusqlite::{Connection, OptionalExtension, TransactionBehavior, params};
use skyplan_airspace::{Conflict, OperationalIntent, PriorityRule, Volume4D, conflicts};
use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Mutex;
use std::time::Duration;

/// Operational intents in one SQLite database (a file in WAL mode, or memory). One
/// connection per value, used by one thread at a time; open one value per process or
/// thread that needs its own (they all share the file's locks).
pub struct SqliteStore {
    conn: Mutex<Connection>,
    place: String,
}

impl std::fmt::Debug for SqliteStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "SqliteStore({})", self.place)
    }
}

const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS intents (
    seq INTEGER PRIMARY KEY AUTOINCREMENT,
    id TEXT NOT NULL UNIQUE,
    version INTEGER NOT NULL,
    state TEXT NOT NULL,
    priority INTEGER NOT NULL,
    owner TEXT NOT NULL,
    time_start_ms INTEGER NOT NULL,
    time_end_ms INTEGER NOT NULL,
    body TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS intent_keys (
    cell INTEGER NOT NULL,
    bucket INTEGER NOT NULL,
    seq INTEGER NOT NULL REFERENCES intents(seq) ON DELETE CASCADE,
    PRIMARY KEY (cell, bucket, seq)
) WITHOUT ROWID;
CREATE INDEX IF NOT EXISTS intent_keys_seq ON intent_keys(seq);
";

/// How long a connection waits for another's lock before answering busy, seconds.
const BUSY_TIMEOUT_S: u64 = 30;

impl SqliteStore {
    /// Opens (creating if needed) the database file at `path`, in WAL mode.
    pub fn open(path: &Path) -> Result<Self, StoreError> {
        let conn = Connection::open(path)?;
        Self::setup(conn, path.display().to_string())
    }

    /// A database in memory: gone when the value is dropped.
    pub fn memory() -> Result<Self, StoreError> {
        Self::setup(Connection::open_in_memory()?, ":memory:".into())
    }

    /// `sqlite:FILE` (a file; `sqlite://FILE` too) or `sqlite::memory:`.
    pub fn open_url(url: &str) -> Result<Self, StoreError> {
        match url.strip_prefix("sqlite:") {
            Some(":memory:") => Self::memory(),
            Some(rest) => {
                let file = rest.strip_prefix("//").unwrap_or(rest);
                if file.is_empty() {
                    return Err(StoreError::Address(url.into()));
                }
                Self::open(Path::new(file))
            }
            None => Err(StoreError::Address(url.into())),
        }
    }

    /// Where the database is: its file, or `:memory:`.
    pub fn place(&self) -> &str {
        &self.place
    }

    fn setup(conn: Connection, place: String) -> Result<Self, StoreError> {
        conn.busy_timeout(Duration::from_secs(BUSY_TIMEOUT_S))?;
        // WAL: readers never wait for the writer; FULL: a commit is on disk when it returns.
        // Switching a new file to WAL needs it to itself, and SQLite answers "database is
        // locked" at once (no busy handler) while another connection opens it too: retried.
        let started = std::time::Instant::now();
        loop {
            match conn.pragma_update(None, "journal_mode", "WAL") {
                Err(rusqlite::Error::SqliteFailure(e, _))
                    if e.code == rusqlite::ErrorCode::DatabaseBusy
                        && started.elapsed() < Duration::from_secs(BUSY_TIMEOUT_S) =>
                {
                    std::thread::sleep(Duration::from_millis(10));
                }
                other => break other?,
            }
        }
        conn.pragma_update(None, "synchronous", "FULL")?;
        conn.pragma_update(None, "foreign_keys", "ON")?;
        let mut conn = conn;
        let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
        tx.execute_batch(SCHEMA)?;
        let found: Option<String> = tx
            .query_row(
                "SELECT value FROM meta WHERE key = 'schema_version'",
                [],
                |r| r.get(0),
            )
            .optional()?;
        match found {
            None => {
                tx.execute(
                    "INSERT INTO meta (key, value) VALUES ('schema_version', ?1)",
                    params![SCHEMA_VERSION.to_string()],
                )?;
            }
            Some(v) if v == SCHEMA_VERSION.to_string() => {}
            Some(found) => return Err(StoreError::Schema { found }),
        }
        tx.commit()?;
        Ok(Self {
            conn: Mutex::new(conn),
            place,
        })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Connection> {
        // A panic while holding the connection leaves no transaction open (rusqlite rolls
        // back on drop), so the connection is still good.
        self.conn
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
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

/// The intent in a row's body.
fn read_body(id: &str, body: &str) -> Result<OperationalIntent, StoreError> {
    serde_json::from_str(body).map_err(|e| StoreError::Corrupt {
        id: id.into(),
        why: e.to_string(),
    })
}

/// The rows of the stored intents whose keys meet `volumes`' (windows widened by
/// `later_ms`), in the order they were stored.
fn candidate_rows(
    conn: &Connection,
    volumes: &[Volume4D],
    later_ms: i64,
) -> Result<BTreeSet<i64>, StoreError> {
    let keys = index_keys(volumes, later_ms)?;
    let mut seqs = BTreeSet::new();
    let mut q =
        conn.prepare("SELECT seq FROM intent_keys WHERE cell = ?1 AND bucket BETWEEN ?2 AND ?3")?;
    for (cell, b0, b1) in keys {
        for seq in q.query_map(params![cell, b0, b1], |r| r.get::<_, i64>(0))? {
            seqs.insert(seq?);
        }
    }
    Ok(seqs)
}

/// The stored intents whose keys meet `volumes`' (windows widened by `later_ms`), in the
/// order they were stored.
fn candidates(
    conn: &Connection,
    volumes: &[Volume4D],
    later_ms: i64,
) -> Result<Vec<OperationalIntent>, StoreError> {
    let seqs = candidate_rows(conn, volumes, later_ms)?;
    let mut q = conn.prepare("SELECT id, body FROM intents WHERE seq = ?1")?;
    let mut out = Vec::with_capacity(seqs.len());
    for seq in seqs {
        let (id, body): (String, String) =
            q.query_row(params![seq], |r| Ok((r.get(0)?, r.get(1)?)))?;
        out.push(read_body(&id, &body)?);
    }
    Ok(out)
}

impl IntentStore for SqliteStore {
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
        let (start, end) = intent.time_bounds().unwrap_or((
            skyplan_airspace::Timestamp::MIN,
            skyplan_airspace::Timestamp::MIN,
        ));
        let mut conn = self.lock();
        // The write lock first: from here to the commit no other writer runs.
        let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
        let exists: bool = tx.query_row(
            "SELECT EXISTS (SELECT 1 FROM intents WHERE id = ?1)",
            params![intent.id],
            |r| r.get(0),
        )?;
        if exists {
            return Err(StoreError::Duplicate(intent.id.clone()));
        }
        let nearby = candidates(&tx, &intent.volumes, 0)?;
        let found = conflicts(intent, &nearby, rule);
        if !found.is_empty() {
            return Ok(Insert::Conflicts(found));
        }
        tx.execute(
            "INSERT INTO intents (id, version, state, priority, owner, time_start_ms, time_end_ms, body) \
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)",
            params![
                intent.id,
                i64::try_from(intent.version).unwrap_or(i64::MAX),
                intent.state.name(),
                intent.priority,
                intent.owner,
                start.unix_ms(),
                end.unix_ms(),
                body
            ],
        )?;
        let seq = tx.last_insert_rowid();
        {
            let mut put = tx.prepare(
                "INSERT OR IGNORE INTO intent_keys (cell, bucket, seq) VALUES (?1, ?2, ?3)",
            )?;
            for (cell, b0, b1) in keys {
                for bucket in b0..=b1 {
                    put.execute(params![cell, bucket, seq])?;
                }
            }
        }
        tx.commit()?;
        Ok(Insert::Accepted {
            checked: nearby.len(),
        })
    }

    fn check(
        &self,
        intent: &OperationalIntent,
        rule: PriorityRule,
    ) -> Result<Vec<Conflict>, StoreError> {
        let conn = self.lock();
        let nearby = candidates(&conn, &intent.volumes, 0)?;
        Ok(conflicts(intent, &nearby, rule))
    }

    fn nearby(
        &self,
        volumes: &[Volume4D],
        later_ms: i64,
    ) -> Result<Vec<OperationalIntent>, StoreError> {
        let conn = self.lock();
        candidates(&conn, volumes, later_ms)
    }

    fn nearby_rows(
        &self,
        volumes: &[Volume4D],
        later_ms: i64,
    ) -> Result<Vec<StoredRow>, StoreError> {
        let mut conn = self.lock();
        // One read transaction: the keys and the rows they name seen at one moment.
        let tx = conn.transaction_with_behavior(TransactionBehavior::Deferred)?;
        let seqs = candidate_rows(&tx, volumes, later_ms)?;
        let mut out = Vec::with_capacity(seqs.len());
        {
            let mut q = tx.prepare("SELECT id, version FROM intents WHERE seq = ?1")?;
            for row in seqs {
                let found: Option<(String, i64)> = q
                    .query_row(params![row], |r| Ok((r.get(0)?, r.get(1)?)))
                    .optional()?;
                if let Some((id, version)) = found {
                    let version = version_of(&id, version)?;
                    out.push(StoredRow { row, id, version });
                }
            }
        }
        tx.commit()?;
        Ok(out)
    }

    fn get_rows(&self, rows: &[i64]) -> Result<Vec<(i64, OperationalIntent)>, StoreError> {
        let conn = self.lock();
        let mut sorted = rows.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        let mut q = conn.prepare("SELECT id, body FROM intents WHERE seq = ?1")?;
        let mut out = Vec::with_capacity(sorted.len());
        for row in sorted {
            let found: Option<(String, String)> = q
                .query_row(params![row], |r| Ok((r.get(0)?, r.get(1)?)))
                .optional()?;
            if let Some((id, body)) = found {
                out.push((row, read_body(&id, &body)?));
            }
        }
        Ok(out)
    }

    fn get(&self, id: &str) -> Result<Option<OperationalIntent>, StoreError> {
        let conn = self.lock();
        let body: Option<String> = conn
            .query_row("SELECT body FROM intents WHERE id = ?1", params![id], |r| {
                r.get(0)
            })
            .optional()?;
        body.map(|b| read_body(id, &b)).transpose()
    }

    fn list(&self) -> Result<Vec<OperationalIntent>, StoreError> {
        let conn = self.lock();
        let mut q = conn.prepare("SELECT id, body FROM intents ORDER BY seq")?;
        let rows = q.query_map([], |r| Ok((r.get::<_, String>(0)?, r.get::<_, String>(1)?)))?;
        let mut out = Vec::new();
        for row in rows {
            let (id, body) = row?;
            out.push(read_body(&id, &body)?);
        }
        Ok(out)
    }

    fn delete(&self, id: &str) -> Result<Option<OperationalIntent>, StoreError> {
        let mut conn = self.lock();
        let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
        let row: Option<(i64, String)> = tx
            .query_row(
                "SELECT seq, body FROM intents WHERE id = ?1",
                params![id],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .optional()?;
        let Some((seq, body)) = row else {
            return Ok(None);
        };
        tx.execute("DELETE FROM intent_keys WHERE seq = ?1", params![seq])?;
        tx.execute("DELETE FROM intents WHERE seq = ?1", params![seq])?;
        tx.commit()?;
        read_body(id, &body).map(Some)
    }
}
