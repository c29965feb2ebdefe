//! # Replanning in flight
//!
//! The library core of receding-horizon replanning (no I/O, no printing):
//!
//! * [`DStarLite`]: incremental shortest paths on the grid, with the grid planners' moves, costs
//!   and corner rule, reused across replans as the vehicle moves and cells change.
//! * [`WorldModel`]: the known grid at the flight altitude plus cells learned from range
//!   readings (grown by the margin; cleared along free rays; the map's obstacles never clear).
//! * [`Replanner`]: the [`skyplan_flight::sensing::RouteWatcher`] that checks the route still to
//!   fly against what was learned and replans from the vehicle to the goal (D\* Lite or JPS from
//!   scratch; climbing when the altitude is walled off; holding when nothing can be flown).
//! * [`bench`]: the scenarios and the numbers of `skyplan bench --replan`; [`bench::SharedReplanner`].
//! * [`hidden`]: random hidden buildings on or near a route, and the true world they make.
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod bench;
mod clock;
mod dstar;
pub mod hidden;
mod replanner;
mod world_model;

pub use clock::thread_cpu_s;
pub use dstar::{BudgetSpent, DStarError, DStarLite, DStarPath};
pub use replanner::{
    ReplanOptions, ReplanSample, ReplanStats, Replanner, ReplannerKind, Spread, UnknownReplanner,
};
pub use world_model::WorldModel;
