//! # Flights against the shared airspace
//!
//! What the server's `POST /api/intents` and the CLI's `skyplan fleet` / `bench --fleet` share,
//! without I/O beyond the store they are given:
//!
//! - [`departure_window`], [`check_window`]: a departure (an RFC 3339 instant or `{earliest,
//!   latest}`) read and checked against the present (not in the past, within the horizon).
//! - [`reserve_plan`] / [`reserve_flight`]: a plan's volumes reserved as a new operational
//!   intent at the earliest free departure of its window, atomically against the store.
//! - [`parse_missions`] (JSON or TOML, every field checked, errors naming the file, the entry
//!   and the field) and [`random_missions`]: the missions of a fleet.
//! - [`fly_fleet`]: each mission planned and reserved in order, departures shifted
//!   ([`Mode::Shift`]) or refused on conflict (the baseline, [`Mode::RejectOnConflict`]);
//!   [`Summary`] of a run (share planned, delays, latency as the store fills, intents checked
//!   per request); [`binding_conflicts`], the brute-force all-pairs oracle.
//!
//! ```
//! use skyplan_fleet::*;
//! use skyplan_airspace_store::{IntentStore, SqliteStore};
//! use skyplan_plan::{PlanRequest, Session, World};
//! let mut session = Session::new(World::fcnd_city());
//! let store = SqliteStore::open_url("sqlite::memory:")?;
//! let t: skyplan_airspace::Timestamp = "2026-03-01T12:00:00Z".parse()?;
//! let text = r#"[{"start_ne": [0, 0], "goal_ne": [420, 390]}, {"start_ne": [0, 0], "goal_ne": [420, 390]}]"#;
//! let missions = parse_missions("two.json", text, Format::Json, Clock { start: t, now: t })?;
//! let records = fly_fleet(&mut session, &store, &PlanRequest::default(), &missions, &RunOptions::default(), |_, _| {})?;
//! // The same route at the same time: the second leaves once the first is clear.
//! assert_eq!(records[1].status, Status::Accepted);
//! assert!(records[1].delay_s.unwrap_or(0.0) > 0.0);
//! assert!(binding_conflicts(&store.list()?, skyplan_airspace::PriorityRule::EqualOrHigher).is_empty());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod flight;
mod mission;
mod run;
pub mod sipp;
mod space_time;

pub use flight::{
    DEPARTURE_STEP_MS, FieldError, FlightError, FlightRequest, HORIZON_MS, PAST_SLACK_MS,
    ReservedFlight, check_window, departure_window, flight_volumes, refuse_plan_departure,
    reserve_flight, reserve_plan,
};
pub use mission::{
    Clock, DEFAULT_WINDOW_S, Format, MAX_NAME_CHARS, MAX_WINDOW_S, Mission, MissionsError, Place,
    RandomMissions, parse_missions, random_missions,
};
pub use run::{
    Decile, FleetError, FlightRecord, Mode, RunOptions, Status, Summary, binding_conflicts,
    fly_fleet, fly_mission, percentile,
};
pub use space_time::{
    BULGE_CELLS, CACHE_INTENTS, MAX_EXPANSIONS, READ_REACH_M, SEARCH_CELL_M, SLACK_M, STRETCH_M,
    STRETCH_S, SearchSpace, SpaceTimeCache, SpaceTimeFlight, reserve_space_time,
    reserve_space_time_cached, reserve_space_time_shared, search_grid,
};
