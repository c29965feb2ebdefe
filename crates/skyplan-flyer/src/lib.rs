//! The flight application of skyplan, for any front end (`skyplan fly`, `skyplan bench
//! --replan`): what a flight is for, on top of the link layer ([`skyplan_link`]) that carries it.
//!
//! - [`runner`]: a whole run: the simulator started, the vehicle waited for, the plan (a
//!   replanner watching), the upload or the flight, the verdict; `bench --replan`'s flights and
//!   the hidden buildings placed on a route.
//! - [`home`]: the way home planned in flight (interrupt and failsafe `return`).
//! - [`flight`]: one flight, told line by line to an [`flight::Observer`] and summed up.
//! - [`mission`]: a planned mission as a vehicle's autopilot gets it (items, true-north headings).
//! - [`words`]: the printers: the flight told in lines (notes, updates) and the flight log as CSV.
//!
//! Nothing here prints or writes files: lines go to the caller's observer.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod flight;
pub mod home;
pub mod mission;
pub mod runner;
pub mod trajectory;
pub mod words;
pub mod zones;
