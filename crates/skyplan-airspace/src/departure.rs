//! The earliest departure within a window whose volumes conflict with no binding stored
//! intent: the minimum form of planning around the others (the route stays; only the
//! departure moves). Searching in space and time (safe-interval path planning with the
//! intents as moving obstacles, hovering allowed) is a later step.

use crate::conflict::{PriorityRule, altitudes_overlap, footprints_intersect};
use crate::model::{IntentRef, OperationalIntent, Volume4D};
use crate::volumes::FlightVolumes;
use crate::{AirspaceError, Timestamp};
use serde::Serialize;
use std::collections::BTreeSet;

/// When a flight may leave: from `earliest` to `latest`, both included.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct DepartureWindow {
    /// The earliest departure.
    pub earliest: Timestamp,
    /// The latest departure.
    pub latest: Timestamp,
}

impl DepartureWindow {
    /// A window of one instant.
    pub fn at(t: Timestamp) -> Self {
        Self {
            earliest: t,
            latest: t,
        }
    }
}

/// The departure found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Departure {
    /// When to leave.
    pub departure: Timestamp,
    /// Milliseconds after the window's earliest departure.
    pub delay_ms: i64,
    /// The flight's volumes for that departure.
    #[serde(skip)]
    pub volumes: Vec<Volume4D>,
    /// Departures tried.
    pub tried: usize,
    /// Stored intents that bind this flight (priority and state) and meet its volumes in
    /// space, whatever the time: those the search had to keep clear of.
    pub nearby: usize,
}

/// Why no departure in the window is free.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, thiserror::Error)]
#[error(
    "no departure from {} to {} is free of the intents of equal or higher priority: blocked by {}",
    window.earliest, window.latest,
    blocking.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
)]
pub struct Blocked {
    /// The window searched.
    pub window: DepartureWindow,
    /// The intents that blocked some departure tried, sorted by id.
    pub blocking: Vec<IntentRef>,
}

/// A stored volume the flight's volume `own` meets in space (time aside).
struct Pair {
    own_start_ms: i64,
    own_end_ms: i64,
    start_ms: i64,
    end_ms: i64,
    intent: usize,
}

/// The earliest departure in `window`, on a grid of `step_ms` from its start, whose volumes
/// conflict with none of `stored` that bind a flight of `priority` under `rule`.
///
/// Exact on the grid: the space and altitude tests do not depend on the departure, so the
/// volume pairs that meet in space are found once; a departure then conflicts when the
/// time windows of such a pair overlap. A pair that overlaps at departure `d` overlaps at
/// every departure until its own volume starts after the other ends, so the search jumps
/// to the latest such instant over the pairs in conflict (rounded up to the grid) — no free
/// departure of the grid is skipped.
///
/// ```
/// use skyplan_airspace::{DepartureWindow, PriorityRule, Timestamp, earliest_departure, volumes_from_plan, VolumeOptions};
/// use skyplan_plan::{PlanRequest, Session, World};
/// let plan = Session::new(World::fcnd_city()).plan(&PlanRequest::default())?;
/// let flight = volumes_from_plan(&plan, &VolumeOptions::default())?;
/// let t0: Timestamp = "2026-03-01T12:00:00Z".parse()?;
/// let window = DepartureWindow { earliest: t0, latest: t0.plus_ms(3_600_000) };
/// let free = earliest_departure(&flight, window, 0, &[], PriorityRule::EqualOrHigher, 1000)?;
/// assert_eq!((free.departure, free.delay_ms), (t0, 0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn earliest_departure(
    flight: &FlightVolumes,
    window: DepartureWindow,
    priority: u32,
    stored: &[OperationalIntent],
    rule: PriorityRule,
    step_ms: i64,
) -> Result<Departure, DepartureError> {
    if window.latest < window.earliest {
        return Err(DepartureError::Invalid(AirspaceError::Invalid {
            field: "departure".into(),
            why: format!(
                "the window ends ({}) before it starts ({})",
                window.latest, window.earliest
            ),
        }));
    }
    let step_ms = step_ms.max(1);
    let mut pairs = Vec::new();
    let mut near = BTreeSet::new();
    for (k, intent) in stored.iter().enumerate() {
        if !rule.binds(priority, intent) {
            continue;
        }
        for own in &flight.relative {
            for theirs in &intent.volumes {
                if altitudes_overlap(own, theirs) && footprints_intersect(own, theirs) {
                    near.insert(k);
                    pairs.push(Pair {
                        own_start_ms: own.time_start.value.unix_ms(),
                        own_end_ms: own.time_end.value.unix_ms(),
                        start_ms: theirs.time_start.value.unix_ms(),
                        end_ms: theirs.time_end.value.unix_ms(),
                        intent: k,
                    });
                }
            }
        }
    }
    let (t0, t1) = (window.earliest.unix_ms(), window.latest.unix_ms());
    let mut blocking = BTreeSet::new();
    let mut d = t0;
    let mut tried = 0;
    while d <= t1 {
        tried += 1;
        let mut next = None::<i64>;
        for p in &pairs {
            if p.own_start_ms + d <= p.end_ms && p.start_ms <= p.own_end_ms + d {
                blocking.insert(p.intent);
                // Clear of this pair from the first departure where the own volume starts
                // after the other ends.
                let clear = p.end_ms - p.own_start_ms + 1;
                next = Some(next.map_or(clear, |n: i64| n.max(clear)));
            }
        }
        match next {
            None => {
                let departure = Timestamp::from_unix_ms(d);
                return Ok(Departure {
                    departure,
                    delay_ms: d - t0,
                    volumes: flight.at(departure),
                    tried,
                    nearby: near.len(),
                });
            }
            Some(clear) => {
                let steps = (clear - t0 + step_ms - 1).div_euclid(step_ms);
                d = (t0 + steps * step_ms).max(d + step_ms);
            }
        }
    }
    let mut blocking: Vec<IntentRef> = blocking
        .into_iter()
        .map(|k| stored[k].reference())
        .collect();
    blocking.sort();
    Err(DepartureError::Blocked(Blocked { window, blocking }))
}

/// Why [`earliest_departure`] found no departure.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DepartureError {
    /// Every departure of the window conflicts.
    #[error(transparent)]
    Blocked(#[from] Blocked),
    /// The window makes no sense.
    #[error(transparent)]
    Invalid(AirspaceError),
}
