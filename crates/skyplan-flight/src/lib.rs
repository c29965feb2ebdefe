//! Flying a skyplan mission, without I/O.
//!
//! - [`executor`]: the FCND mission state machine (MANUAL → ARMING → TAKEOFF → WAYPOINT →
//!   LANDING → DISARMING → MANUAL): telemetry, acknowledgements and link events in, commands out.
//! - [`sim`]: a simulated multicopter (first-order velocity response, speed, acceleration and
//!   yaw-rate limits, ArduCopter-like modes, take-off, landing, position targets, missions).
//! - [`collision`]: the flown track checked against the map's obstacle boxes.
//! - [`upload`]: the mission as MAVLink items, and the ground side of the upload protocol.
//! - [`fence`]: no-fly zones as the vehicle's fence (what a fence can carry, the items, the
//!   read-back and its check).
//! - [`sensing`]: range-sensor readings and the [`sensing::RouteWatcher`] hook that replans in flight.
//! - [`sensor`]: the simulated range sensor (rays against the true world's boxes).
//! - [`reference`](mod@reference): a time-parametrised reference ([`Setpoint`], [`Reference`]) and a simple
//!   one, [`reference::MinJerkLine`], that [`executor::ReferenceExecutor`] flies.
//! - [`modes`]: the one table of autopilot mode numbers (ArduCopter's, PX4's).
//! - [`auto`]: flying the uploaded mission in AUTO (`skyplan fly --upload`), same states and
//!   outcomes as [`executor`].
//!
//! The MAVLink link that connects these to sockets is `skyplan-link`; this crate never touches
//! the network, a clock or the terminal, so everything here is tested deterministically.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod auto;
pub mod collision;
pub mod executor;
pub mod fence;
pub mod flat_earth;
pub mod modes;
pub mod reference;
pub mod sensing;
pub mod sensor;
pub mod sim;
pub mod upload;

pub use reference::{Reference, Setpoint};

#[cfg(test)]
mod testkit;
