//! Planning around the others, minimum form, against a store: the earliest free departure of
//! a window, reserved atomically.

use crate::{Insert, IntentStore, StoreError};
use skyplan_airspace::{
    Blocked, DepartureError, DepartureWindow, FlightVolumes, IntentState, OperationalIntent,
    PriorityRule, Timestamp, earliest_departure,
};

/// How many times a departure found free is tried again when another writer took it first.
pub const RESERVE_TRIES: usize = 5;

/// A reserved flight.
#[derive(Debug, Clone, PartialEq)]
pub struct Reserved {
    /// The intent stored.
    pub intent: OperationalIntent,
    /// Its departure.
    pub departure: Timestamp,
    /// Milliseconds after the window's earliest departure.
    pub delay_ms: i64,
    /// Stored intents read near the flight (through the index) for the search.
    pub nearby: usize,
    /// Searches run (more than 1 when another writer took a departure first).
    pub tries: usize,
}

/// Why a flight was not reserved.
#[derive(Debug, thiserror::Error)]
pub enum ReserveError {
    /// No departure of the window is free.
    #[error(transparent)]
    Blocked(Blocked),
    /// The request makes no sense (a window that ends before it starts, an invalid intent).
    #[error(transparent)]
    Invalid(skyplan_airspace::AirspaceError),
    /// The store failed.
    #[error(transparent)]
    Store(StoreError),
    /// The search for a route around the others gave up, with none found, to answer by the
    /// request's deadline: nothing was reserved.
    #[error(
        "the search for a route around the other flights gave up to answer by the deadline, after {states} states; nothing was reserved"
    )]
    Deadline {
        /// States the search took from its queue.
        states: usize,
    },
}

impl From<StoreError> for ReserveError {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::Invalid(e) => Self::Invalid(e),
            e => Self::Store(e),
        }
    }
}

/// What to reserve, besides the flight.
#[derive(Debug, Clone, PartialEq)]
pub struct Reservation {
    /// When the flight may leave.
    pub window: DepartureWindow,
    /// Its priority.
    pub priority: u32,
    /// Who flies it.
    pub owner: String,
    /// The new intent's id ([`crate::new_id`]).
    pub id: String,
    /// Which stored intents bind it.
    pub rule: PriorityRule,
    /// The departure grid's step, milliseconds.
    pub step_ms: i64,
}

/// Reserves `flight` at the earliest departure of the window (on a grid of `step_ms`) that
/// conflicts with no stored intent binding it under the rule: reads the intents near the
/// flight over the whole window through the index, searches ([`earliest_departure`]), then
/// inserts with the exact check-and-insert; if another writer took the departure meanwhile,
/// searches again (at most [`RESERVE_TRIES`] times).
pub fn reserve(
    store: &dyn IntentStore,
    flight: &FlightVolumes,
    r: &Reservation,
) -> Result<Reserved, ReserveError> {
    reserve_counted(store, flight, r).0
}

/// What a [`reserve`] call read, whatever its outcome.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ReserveCounts {
    /// Stored intents read near the flight through the index (the last search's).
    pub nearby: usize,
    /// Searches run.
    pub tries: usize,
}

/// [`reserve`], with what it read counted also when the flight is refused.
pub fn reserve_counted(
    store: &dyn IntentStore,
    flight: &FlightVolumes,
    r: &Reservation,
) -> (Result<Reserved, ReserveError>, ReserveCounts) {
    let mut counts = ReserveCounts::default();
    let result = reserve_inner(store, flight, r, &mut counts);
    (result, counts)
}

fn reserve_inner(
    store: &dyn IntentStore,
    flight: &FlightVolumes,
    r: &Reservation,
    counts: &mut ReserveCounts,
) -> Result<Reserved, ReserveError> {
    let (window, priority, rule) = (r.window, r.priority, r.rule);
    let span = window.latest.ms_since(window.earliest).max(0);
    let mut last_conflicts = Vec::new();
    for tries in 1..=RESERVE_TRIES {
        counts.tries = tries;
        let nearby = store.nearby(&flight.at(window.earliest), span)?;
        counts.nearby = nearby.len();
        let found = earliest_departure(flight, window, priority, &nearby, rule, r.step_ms)
            .map_err(|e| match e {
                DepartureError::Blocked(b) => ReserveError::Blocked(b),
                DepartureError::Invalid(e) => ReserveError::Invalid(e),
            })?;
        let intent = OperationalIntent {
            id: r.id.clone(),
            version: 1,
            state: IntentState::Accepted,
            priority,
            owner: r.owner.clone(),
            volumes: found.volumes,
        };
        match store.insert_if_clear(&intent, rule)? {
            Insert::Accepted { .. } => {
                return Ok(Reserved {
                    intent,
                    departure: found.departure,
                    delay_ms: found.delay_ms,
                    nearby: nearby.len(),
                    tries,
                });
            }
            Insert::Conflicts(c) => last_conflicts = c,
        }
    }
    let mut blocking: Vec<_> = last_conflicts
        .iter()
        .map(skyplan_airspace::Conflict::reference)
        .collect();
    blocking.sort();
    Err(ReserveError::Blocked(Blocked { window, blocking }))
}
