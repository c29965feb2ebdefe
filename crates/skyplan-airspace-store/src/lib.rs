//! # The store of the shared airspace
//!
//! Operational intents ([`skyplan_airspace::OperationalIntent`]) kept in a database behind the
//! [`IntentStore`] trait: [`SqliteStore`] — SQLite through `rusqlite` (compiled in: a fresh
//! machine needs nothing), a file in WAL mode, or memory — for one machine, and
//! [`PostgresStore`] — PostgreSQL through the `postgres` client, written so that CockroachDB
//! (which speaks its protocol) can serve it too — for several servers sharing one airspace.
//! [`open_url`] picks one by its address.
//!
//! **Atomic check-and-insert.** On SQLite, [`IntentStore::insert_if_clear`] runs in one `BEGIN
//! IMMEDIATE` transaction: it takes SQLite's write lock first (other writers, in this process
//! or another, wait for it: a busy timeout of 30 s), reads the candidate intents through the
//! index, checks them exactly ([`skyplan_airspace::conflicts`]), inserts and commits. So two
//! writers never both accept intersecting intents, and what was acknowledged is on disk
//! (`synchronous = FULL`). On PostgreSQL it runs in one `SERIALIZABLE` transaction, retried
//! when the database aborts it for a serialization failure (SQLSTATE 40001): of two
//! transactions that each read the index keys the other writes, at most one commits.
//!
//! **The index** is a table of `(cell, time bucket)` keys per intent (as the DSS keys intents
//! by S2 cells): the footprint's latitude/longitude box in cells of [`CELL_DEG`] degrees ×
//! its time window in buckets of [`BUCKET_MS`] milliseconds. Two volumes that share a point
//! share a key (both boxes hold the point's cell and both windows its bucket), so reading the
//! intents under the new one's keys misses no conflict; the exact test then decides.
//!
//! ```
//! use skyplan_airspace_store::{IntentStore, Insert, SqliteStore};
//! let store = SqliteStore::open_url("sqlite::memory:")?;
//! assert!(store.list()?.is_empty());
//! # Ok::<(), skyplan_airspace_store::StoreError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod pg;
mod reserve;
mod sqlite;
mod tls;

pub use pg::{MAX_CONNECTIONS, PostgresStore, SERIALIZABLE_TRIES};
pub use reserve::{
    RESERVE_TRIES, Reservation, ReserveCounts, ReserveError, Reserved, reserve, reserve_counted,
};
pub use sqlite::SqliteStore;

use skyplan_airspace::{Conflict, OperationalIntent, PriorityRule, Volume4D};

/// The schema version this build reads and writes.
pub const SCHEMA_VERSION: i64 = 1;

/// The index's cell size, degrees of latitude and of longitude (about 220 m north–south).
pub const CELL_DEG: f64 = 0.002;

/// The index's time bucket, milliseconds (one minute).
pub const BUCKET_MS: i64 = 60_000;

/// Most index keys one intent may have (its volumes' cells × buckets, counted with
/// repeats); a larger one is refused.
pub const MAX_KEYS: usize = 200_000;

/// What an insert did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Insert {
    /// Stored.
    Accepted {
        /// Stored intents read through the index and checked exactly.
        checked: usize,
    },
    /// Not stored: the intents it conflicts with.
    Conflicts(Vec<Conflict>),
}

/// Why the store failed.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// The database could not be opened or answered with an error.
    #[error("the airspace store: {0}")]
    Database(#[from] rusqlite::Error),
    /// The database was written by another schema version.
    #[error(
        "the airspace store has schema version {found}; this skyplan reads version {SCHEMA_VERSION}"
    )]
    Schema {
        /// The version found.
        found: String,
    },
    /// A stored intent that does not read back.
    #[error("the airspace store holds an unreadable intent {id}: {why}")]
    Corrupt {
        /// The intent's id.
        id: String,
        /// Why.
        why: String,
    },
    /// The intent is refused before it reaches the database.
    #[error(transparent)]
    Invalid(#[from] skyplan_airspace::AirspaceError),
    /// An intent with this id is stored already.
    #[error("an intent with id {0} is stored already")]
    Duplicate(String),
    /// The intent covers more index keys than [`MAX_KEYS`].
    #[error(
        "the intent covers {0} index keys (cells × minutes), more than the store's {MAX_KEYS}: make it smaller or shorter"
    )]
    TooLarge(usize),
    /// An address the store does not know.
    #[error(
        "airspace {0}: expected sqlite:FILE, sqlite::memory: or postgres://USER@HOST:PORT/DATABASE"
    )]
    Address(String),
    /// The database server cannot be reached, or the connection to it broke.
    #[error("the airspace store at {place} is down: {why}")]
    Down {
        /// Where (no password).
        place: String,
        /// The client's error.
        why: String,
    },
    /// PostgreSQL (or CockroachDB) answered with an error.
    #[error("the airspace store (PostgreSQL): {0}")]
    Postgres(String),
    /// A serializable transaction was aborted by other writers this many times in a row.
    #[error(
        "the airspace store is busy: the transaction met other writers {0} times in a row; try again"
    )]
    Contended(usize),
}

/// Opens the store at `url`: `sqlite:FILE`, `sqlite::memory:` ([`SqliteStore`]) or
/// `postgres://…` / `postgresql://…` ([`PostgresStore`]).
pub fn open_url(url: &str) -> Result<Box<dyn IntentStore>, StoreError> {
    if url.starts_with("postgres://") || url.starts_with("postgresql://") {
        Ok(Box::new(PostgresStore::open_url(url)?))
    } else {
        Ok(Box::new(SqliteStore::open_url(url)?))
    }
}

/// A stored intent's row, named without reading the intent: what a reader caching decoded
/// intents keys them by. A row is never rewritten (intents are inserted and deleted, never
/// updated in place) and its number is never given to another, so a row's intent, once read,
/// stays what it is.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct StoredRow {
    /// The row's number in the store (SQLite's `seq`, PostgreSQL's `BIGSERIAL`).
    pub row: i64,
    /// The intent's id.
    pub id: String,
    /// The intent's version.
    pub version: u64,
}

/// A stored version column as the intent's `u64`.
fn version_of(id: &str, version: i64) -> Result<u64, StoreError> {
    u64::try_from(version).map_err(|_| StoreError::Corrupt {
        id: id.into(),
        why: format!("version {version} is negative"),
    })
}

/// A store of operational intents. Implementations make [`IntentStore::insert_if_clear`]
/// atomic across every process that shares the store.
pub trait IntentStore: Send + Sync {
    /// Stores `intent` unless it conflicts with a stored intent that binds it under `rule`
    /// (checked and inserted atomically); `intent` is validated first.
    fn insert_if_clear(
        &self,
        intent: &OperationalIntent,
        rule: PriorityRule,
    ) -> Result<Insert, StoreError>;

    /// The stored intents that `intent` conflicts with under `rule`, read through the index.
    fn check(
        &self,
        intent: &OperationalIntent,
        rule: PriorityRule,
    ) -> Result<Vec<Conflict>, StoreError>;

    /// The stored intents whose index keys meet those of `volumes` with each window widened
    /// by `later_ms` at its end: every intent a flight with these volumes could conflict with
    /// if it left up to `later_ms` later (a superset; the exact test is the caller's).
    fn nearby(
        &self,
        volumes: &[Volume4D],
        later_ms: i64,
    ) -> Result<Vec<OperationalIntent>, StoreError>;

    /// The rows of the intents [`IntentStore::nearby`] would read, in the order they were
    /// stored, without reading the intents themselves (their ids and versions only).
    fn nearby_rows(
        &self,
        volumes: &[Volume4D],
        later_ms: i64,
    ) -> Result<Vec<StoredRow>, StoreError>;

    /// The intents stored in `rows` ([`StoredRow::row`]), each with its row, in the order
    /// they were stored; a row deleted meanwhile is left out.
    fn get_rows(&self, rows: &[i64]) -> Result<Vec<(i64, OperationalIntent)>, StoreError>;

    /// The intent with this id.
    fn get(&self, id: &str) -> Result<Option<OperationalIntent>, StoreError>;

    /// Every stored intent, in the order they were stored.
    fn list(&self) -> Result<Vec<OperationalIntent>, StoreError>;

    /// Removes the intent with this id, returning it.
    fn delete(&self, id: &str) -> Result<Option<OperationalIntent>, StoreError>;
}

/// A new random id: a UUID version 4 (`xxxxxxxx-xxxx-4xxx-yxxx-xxxxxxxxxxxx`).
///
/// ```
/// let id = skyplan_airspace_store::new_id();
/// assert_eq!((id.len(), &id[14..15]), (36, "4"));
/// ```
pub fn new_id() -> String {
    let v: u128 = rand::random();
    let v =
        (v & !(0xF000u128 << 64) | (0x4000u128 << 64)) & !(0xC000u128 << 48) | (0x8000u128 << 48);
    let h = format!("{v:032x}");
    format!(
        "{}-{}-{}-{}-{}",
        &h[..8],
        &h[8..12],
        &h[12..16],
        &h[16..20],
        &h[20..]
    )
}

/// The index keys `(cell, bucket range)` of `volumes`, each window widened by `later_ms` at
/// its end: one entry per volume and cell of its box, with the volume's first and last
/// bucket.
pub fn index_keys(volumes: &[Volume4D], later_ms: i64) -> Result<Vec<(i64, i64, i64)>, StoreError> {
    let mut keys = Vec::new();
    let mut count = 0usize;
    for v in volumes {
        let b = skyplan_airspace::bbox_deg(v);
        let cell = |deg: f64| (deg / CELL_DEG).floor() as i64;
        let (r0, c0, r1, c1) = (cell(b[0]), cell(b[1]), cell(b[2]), cell(b[3]));
        let t0 = v.time_start.value.unix_ms().div_euclid(BUCKET_MS);
        let t1 = v
            .time_end
            .value
            .unix_ms()
            .saturating_add(later_ms.max(0))
            .div_euclid(BUCKET_MS);
        let cells = usize::try_from((r1 - r0 + 1) * (c1 - c0 + 1)).unwrap_or(usize::MAX);
        count = count.saturating_add(
            cells.saturating_mul(usize::try_from(t1 - t0 + 1).unwrap_or(usize::MAX)),
        );
        if count > MAX_KEYS || cells > MAX_KEYS {
            return Err(StoreError::TooLarge(count));
        }
        for r in r0..=r1 {
            for c in c0..=c1 {
                keys.push((cell_key(r, c), t0, t1));
            }
        }
    }
    Ok(keys)
}

/// One integer per cell: `row · 10⁶ + column` (rows and columns stay within ±90 000).
fn cell_key(row: i64, col: i64) -> i64 {
    row * 1_000_000 + col
}
