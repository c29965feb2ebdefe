//! # Shared airspace (no I/O)
//!
//! Strategic deconfliction as ASTM F3548-21 and the InterUSS DSS describe it: each flight
//! declares an [`OperationalIntent`] — 4D volumes ([`Volume4D`]: a footprint polygon in
//! latitude and longitude, an altitude band, a time window), serialised exactly in the DSS's
//! JSON shape — and must not conflict with the stored intents of equal or higher priority.
//!
//! - [`volumes_from_plan`]: a plan's route with times (its trajectory's samples, else a
//!   constant cruise speed from rest to rest) cut into stretches, each grown by a lateral
//!   margin, a vertical buffer and a time buffer ([`VolumeOptions`]).
//! - [`volumes_conflict`] / [`conflicts`]: the exact test (separating axes between the
//!   convex footprints on a local metric plane, closed altitude and time intervals).
//! - [`earliest_departure`]: the first departure of a window that conflicts with none of the
//!   binding intents, or the intents that block the window.
//!
//! The store (SQLite, atomic check-and-insert across processes) is `skyplan-airspace-store`.
//!
//! ```
//! use skyplan_airspace::*;
//! use skyplan_plan::{PlanRequest, Session, World};
//! let plan = Session::new(World::fcnd_city()).plan(&PlanRequest::default())?;
//! let flight = volumes_from_plan(&plan, &VolumeOptions::default())?;
//! let t0: Timestamp = "2026-03-01T12:00:00Z".parse()?;
//! let first = OperationalIntent {
//!     id: "a".into(), version: 1, state: IntentState::Accepted, priority: 0,
//!     owner: "op-1".into(), volumes: flight.at(t0),
//! };
//! // The same flight at the same time conflicts; it may leave once the first is clear.
//! let window = DepartureWindow { earliest: t0, latest: t0.plus_ms(3_600_000) };
//! let later = earliest_departure(&flight, window, 0, &[first.clone()], PriorityRule::EqualOrHigher, 1000)?;
//! assert!(later.delay_ms > 0);
//! let second = OperationalIntent { id: "b".into(), volumes: later.volumes.clone(), ..first.clone() };
//! assert!(conflicts(&second, [&first], PriorityRule::EqualOrHigher).is_empty());
//! // A more important flight is not bound by a less important one.
//! let urgent = OperationalIntent { id: "c".into(), priority: 5, ..first.clone() };
//! assert!(conflicts(&urgent, [&first], PriorityRule::EqualOrHigher).is_empty());
//! assert_eq!(conflicts(&urgent, [&first], PriorityRule::Every).len(), 1);
//! println!("{}", serde_json::to_string(&first.volumes[0]).unwrap_or_default());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod conflict;
mod departure;
pub mod geometry;
mod model;
mod time;
mod volumes;

pub use conflict::{
    Conflict, PriorityRule, altitudes_overlap, bbox_deg, conflicts, first_conflict,
    footprints_intersect, times_overlap, volumes_conflict,
};
pub use departure::{Blocked, Departure, DepartureError, DepartureWindow, earliest_departure};
pub use model::{
    Altitude, AltitudeReference, AltitudeUnits, IntentRef, IntentState, LatLng, MAX_PRIORITY,
    OperationalIntent, Polygon, Time, TimeFormat, Volume3D, Volume4D,
};
pub use time::{TimeError, Timestamp};
pub use volumes::{
    FlightVolumes, TimedPoint, Timing, VolumeOptions, timed_path, timed_route, volumes_from_path,
    volumes_from_plan, volumes_hugging_path,
};

/// Why volumes could not be made or an intent is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AirspaceError {
    /// A field out of its range or shape.
    #[error("{field}: {why}")]
    Invalid {
        /// The field, as a JSON path (`volumes[2].time_start`).
        field: String,
        /// What is wrong.
        why: String,
    },
    /// The plan's map has no geodetic home, so its route has no latitude and longitude.
    #[error("the map has no geodetic home: an operational intent needs latitude and longitude")]
    NoHome,
    /// A frame conversion failed.
    #[error("{0}")]
    Frame(#[from] skyplan_frames::FrameError),
    /// The route cannot be timed.
    #[error("the route {0}")]
    Route(String),
}
