//! The FCND mission state machine: events in, commands out, no I/O.
//!
//! MANUAL → ARMING → TAKEOFF → WAYPOINT → LANDING → DISARMING → MANUAL, as in the FCND reference
//! client (planning happens before, while the link keeps its heartbeats). The link adapter turns
//! vehicle messages into [`Event`]s and sends the [`Command`]s back; the executor only decides.
//!
//! ```
//! use skyplan_flight::executor::{Command, Event, ExecutorConfig, FlightState, MissionExecutor, Target, Telemetry};
//! let targets = [Target { north_m: 0.0, east_m: 0.0, alt_m: 5.0, heading_rad: 0.0 }];
//! let mut ex = MissionExecutor::new(&targets, ExecutorConfig::default())?;
//! let on_ground = Telemetry::default();
//! let out = ex.handle(0.0, Event::Telemetry(on_ground));
//! assert_eq!(ex.state(), FlightState::Arming);
//! assert_eq!(out.commands, vec![Command::TakeControl]);
//! # Ok::<(), skyplan_flight::executor::ConfigError>(())
//! ```
//!
//! One [`Executor`] core (arming, landing, disarming, timeouts, link loss, stop, hold, RTL)
//! flies each mission strategy: [`MissionExecutor`] streams GUIDED position targets,
//! [`crate::auto::AutoExecutor`] follows the uploaded mission in AUTO, [`ReferenceExecutor`]
//! streams a time-parametrised [`crate::Reference`] with feed-forward.
//!
//! - `io`: states, targets, telemetry, events in and commands out;
//! - `report`: notes, failures, outcomes and the configuration;
//! - `core`: the shared state machine and its fault handling;
//! - `faults`: link-loss, hold and return-to-launch bookkeeping;
//! - `guided`: the GUIDED strategy;
//! - `tracking`: the reference-tracking strategy.

mod core;
mod faults;
mod guided;
mod interface;
mod report;
mod tracking;

pub use self::core::{Core, Executor, FlightExecutor, Strategy};
pub use guided::{GuidedTargets, MissionExecutor};
pub use interface::{
    Command, CommandKind, Event, FailsafeAction, FlightState, Target, Telemetry, VehicleMode,
    wrap_angle_rad,
};
pub use report::{
    ConfigError, ExecutorConfig, Failure, Note, Outcome, Output, Reached, TrackingReport,
};
pub use tracking::{
    AHEAD_STEP_S, REFERENCE_PERIOD_S, ReferenceExecutor, ReferenceTracking, Rereference,
    SPLICE_LEAD_S, START_SPEED_M_S, START_TOLERANCE_M,
};

#[cfg(test)]
mod tests;

#[cfg(test)]
mod replan_tests;
