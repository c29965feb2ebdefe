//! Flying a skyplan mission, without I/O.
//!
//! - [`executor`]: the FCND mission state machine (MANUAL → ARMING → TAKEOFF → WAYPOINT →
//!   LANDING → DISARMING → MANUAL): telemetry, acknowledgements and link events in, commands out.
//! - [`sim`]: a simulated multicopter (first-order velocity response, speed, acceleration and
//!   yaw-rate limits, ArduCopter-like modes, take-off, landing, position targets, missions).
//! - [`collision`]: the flown track checked against the map's obstacle boxes.
//!
//! The MAVLink link that connects these to sockets is `skyplan-link`; this crate never touches
//! the network, a clock or the terminal, so everything here is tested deterministically.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod collision;
pub mod executor;
pub mod sim;
