//! What an executor reports: notes, reached waypoints, failures and outcomes; its configuration.

use super::interface::{Command, CommandKind, FailsafeAction, FlightState, Target, VehicleMode};
use crate::sensing::ReplanEvent;
use std::fmt;

/// What happened to the executor since the last event, for printing and logging.
#[derive(Debug, Clone, PartialEq)]
pub enum Note {
    /// A state transition.
    State {
        /// The state left.
        from: FlightState,
        /// The state entered.
        to: FlightState,
    },
    /// A waypoint was reached.
    Reached(Reached),
    /// The vehicle refused a command (it is retried until the state times out).
    Refused {
        /// The command.
        command: CommandKind,
        /// The vehicle's answer and its last status text.
        reason: String,
    },
    /// The link was lost and the executor waits for it to come back (with
    /// [`ExecutorConfig::failsafe`] set); it sends nothing meanwhile.
    LinkLost {
        /// The state when the link was lost.
        state: FlightState,
        /// Seconds without a heartbeat so far.
        silent_s: f64,
        /// How long it waits for the link ([`ExecutorConfig::link_regain_wait_s`]).
        wait_s: f64,
        /// What it will command when the link returns.
        action: FailsafeAction,
    },
    /// The lost link came back after this many seconds; the failsafe action is commanded (or,
    /// when the vehicle was already landing, the landing goes on).
    LinkRegained {
        /// Seconds without a heartbeat.
        silent_s: f64,
        /// The action commanded.
        action: FailsafeAction,
    },
    /// The route still to fly was replaced in flight (a [`crate::sensing::RouteWatcher`]
    /// replanned it); waypoint indices of later notes count in the new route.
    Replanned {
        /// What happened.
        event: ReplanEvent,
        /// The new route, first target first.
        targets: Vec<Target>,
    },
    /// A replanned route could not be made a trajectory from the moving vehicle (`reason`):
    /// the flight flies it by waypoints instead, as a flight without a trajectory does.
    ByWaypoints {
        /// Why, in the user's words.
        reason: String,
    },
    /// No route can be flown: the vehicle holds its position for
    /// [`ExecutorConfig::replan_hold_s`] (and until it is at rest), then lands, and the flight
    /// fails with [`Failure::NoRoute`].
    Holding {
        /// Why, in the user's words.
        reason: String,
        /// How long it holds before landing, seconds.
        hold_s: f64,
    },
    /// The flight was stopped with [`FailsafeAction::Return`]: the vehicle holds where it is
    /// while the way home is planned.
    WayHomeWanted {
        /// Why the flight stopped.
        reason: String,
    },
    /// The way home was planned: the vehicle flies it and lands at the launch point.
    ReturningHome {
        /// The route home, first target first.
        targets: Vec<Target>,
        /// Its length, metres.
        length_m: f64,
        /// The planner that found it.
        planner: String,
    },
    /// No way home could be planned: the vehicle lands where it is.
    NoWayHome {
        /// Why, in the user's words.
        reason: String,
    },
    /// The flight ended; see [`Executor::outcome`](super::Executor::outcome).
    Finished,
}

/// A reached waypoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reached {
    /// Index of the waypoint in the route flown then (after a replan: in the new route).
    pub index: usize,
    /// Executor time when it was reached, seconds.
    pub time_s: f64,
    /// Horizontal distance to the waypoint then, metres.
    pub horizontal_error_m: f64,
    /// Altitude error then, metres.
    pub vertical_error_m: f64,
    /// Heading error then, radians (absolute).
    pub heading_error_rad: f64,
}

/// Why a flight failed.
#[derive(Debug, Clone, PartialEq)]
pub enum Failure {
    /// A state took longer than its budget.
    Timeout {
        /// The state.
        state: FlightState,
        /// Its budget, seconds.
        after_s: f64,
        /// What was awaited, and the vehicle's last refusal if any.
        detail: String,
    },
    /// No heartbeat from the vehicle.
    LinkLost {
        /// The state when the link was lost.
        state: FlightState,
        /// How long the vehicle has been silent, seconds.
        silent_s: f64,
    },
    /// The vehicle disarmed while the executor needed it armed.
    DisarmedInFlight {
        /// The state.
        state: FlightState,
    },
    /// The vehicle left the guided mode (a pilot or failsafe took over).
    ControlLost {
        /// The state.
        state: FlightState,
    },
    /// The operator stopped the flight; the vehicle landed.
    Aborted {
        /// Why.
        reason: String,
    },
    /// The operator (or a failsafe) stopped the flight and the vehicle confirmed it holds its
    /// position in the air: a pilot must take over.
    Held {
        /// Why.
        reason: String,
        /// The state when the hold was commanded.
        state: FlightState,
    },
    /// The route watcher found no route to fly: the vehicle held its position, then landed.
    NoRoute {
        /// Why, in the watcher's words.
        reason: String,
    },
    /// The vehicle left AUTO while flying the uploaded mission (a pilot or failsafe took over).
    LeftMission {
        /// The state.
        state: FlightState,
        /// The mode it entered.
        mode: VehicleMode,
    },
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::Timeout {
                state,
                after_s,
                detail,
            } => write!(f, "{state} timed out after {after_s:.1} s: {detail}"),
            Failure::LinkLost { state, silent_s } => write!(
                f,
                "link lost in {state}: no heartbeat from the vehicle for {silent_s:.1} s"
            ),
            Failure::DisarmedInFlight { state } => {
                write!(f, "the vehicle disarmed during {state}")
            }
            Failure::ControlLost { state } => write!(
                f,
                "the vehicle left guided mode during {state} (pilot or failsafe took over)"
            ),
            Failure::Aborted { reason } => write!(f, "aborted ({reason}); the vehicle landed"),
            Failure::Held { reason, state } => write!(
                f,
                "stopped in {state} ({reason}); the vehicle is holding its position in the air: take over"
            ),
            Failure::NoRoute { reason } => {
                write!(f, "no route to fly ({reason}): held position, then landed")
            }
            Failure::LeftMission { state, mode } => write!(
                f,
                "the vehicle left AUTO for {mode} during {state} (pilot or failsafe took over)"
            ),
        }
    }
}

/// How the flight ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Every waypoint reached, landed, disarmed.
    Completed,
    /// It failed; the executor commanded a landing if it still could.
    Failed(Failure),
}

/// The executor's output for one event.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Output {
    /// Commands to send, in order.
    pub commands: Vec<Command>,
    /// What happened.
    pub notes: Vec<Note>,
}

/// Tolerances, periods and budgets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExecutorConfig {
    /// Take-off ends at this fraction of the target altitude (FCND: 0.95).
    pub takeoff_fraction: f64,
    /// A waypoint is reached within this horizontal distance, metres (FCND: 1).
    pub deadband_m: f64,
    /// The deadband grows by this many metres per m/s of ground speed (0: fixed).
    pub deadband_per_speed_s: f64,
    /// And within this altitude error, metres.
    pub vertical_deadband_m: f64,
    /// And within this heading error, radians.
    pub heading_tolerance_rad: f64,
    /// Landing starts when the last waypoint is reached and the speed is below this, m/s.
    pub land_speed_m_s: f64,
    /// Without the vehicle's landed flag: on the ground below this altitude, metres…
    pub landed_alt_m: f64,
    /// …with a vertical speed below this, m/s.
    pub landed_vertical_speed_m_s: f64,
    /// Unanswered commands are repeated this often, seconds.
    pub retry_s: f64,
    /// Position targets are re-sent this often, seconds (PX4 needs more than 2 Hz).
    pub target_period_s: f64,
    /// Budget of ARMING, seconds.
    pub arming_timeout_s: f64,
    /// Budget of TAKEOFF, seconds.
    pub takeoff_timeout_s: f64,
    /// Budget of one leg: this many seconds…
    pub leg_timeout_base_s: f64,
    /// …plus this many per metre of the leg.
    pub leg_timeout_per_m_s: f64,
    /// Budget of LANDING beyond the descent itself, seconds: LANDING may take the altitude
    /// when it began ÷ [`ExecutorConfig::landing_descent_m_s`] plus this.
    pub landing_timeout_s: f64,
    /// The slowest descent rate the budget of LANDING allows for, m/s (ArduCopter's
    /// `LAND_SPEED`, 0.5 m/s, in its last 10 m; it descends faster above).
    pub landing_descent_m_s: f64,
    /// Budget of DISARMING, seconds.
    pub disarming_timeout_s: f64,
    /// What to command when a lost link comes back; `None`: a lost link ends the flight at once
    /// (nothing more can be commanded). Only in the air (TAKEOFF, WAYPOINT; LANDING and
    /// DISARMING resume): on the ground a lost link always ends the flight.
    pub failsafe: Option<FailsafeAction>,
    /// With `failsafe`: how long to wait for the link to come back, in the clock of
    /// [`Event::LinkLost`](super::Event::LinkLost)'s `silent_s` (the link layer's wall clock) before giving up.
    pub link_regain_wait_s: f64,
    /// A commanded hold not confirmed (acknowledged, or the mode reported) within this many
    /// seconds becomes a landing.
    pub hold_confirm_s: f64,
    /// When a route watcher finds no route, the vehicle holds its position this many seconds
    /// before landing.
    pub replan_hold_s: f64,
    /// The autopilot's RTL altitude above home, metres, when known (`fly` sets `RTL_ALT`): a
    /// return to launch climbs to it first and descends from it, which its budget counts.
    pub rtl_alt_m: Option<f64>,
}

impl Default for ExecutorConfig {
    fn default() -> Self {
        Self {
            takeoff_fraction: 0.95,
            deadband_m: 1.0,
            deadband_per_speed_s: 0.0,
            vertical_deadband_m: 1.0,
            heading_tolerance_rad: 10f64.to_radians(),
            land_speed_m_s: 0.5,
            landed_alt_m: 0.3,
            landed_vertical_speed_m_s: 0.2,
            retry_s: 1.0,
            target_period_s: 0.2,
            arming_timeout_s: 60.0,
            takeoff_timeout_s: 60.0,
            leg_timeout_base_s: 30.0,
            leg_timeout_per_m_s: 1.0,
            landing_timeout_s: 60.0,
            landing_descent_m_s: 0.5,
            disarming_timeout_s: 20.0,
            failsafe: None,
            link_regain_wait_s: 30.0,
            hold_confirm_s: 10.0,
            replan_hold_s: 2.0,
            rtl_alt_m: None,
        }
    }
}

/// How a reference was followed ([`super::ReferenceExecutor`]). Times are executor seconds;
/// with the vehicle's time stamps (`Telemetry::sample_time_s`) they are the vehicle's own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingReport {
    /// The reference's duration, seconds.
    pub duration_s: f64,
    /// When the reference clock started (the vehicle at rest over the start), if it has.
    pub started_s: Option<f64>,
    /// From the clock's start to the arrival within the deadband of the last point, seconds,
    /// once arrived.
    pub flown_s: Option<f64>,
    /// The largest distance between the vehicle and the reference's setpoint at the same
    /// reference time while streaming, metres (0 before any sample).
    pub max_tracking_error_m: f64,
    /// The largest distance between the vehicle and the reference's path near its own time
    /// (the closest setpoint within `tracking::PATH_WINDOW_S`): how far off the
    /// proven trajectory the vehicle flew, early or late aside, metres.
    pub max_path_error_m: f64,
    /// Telemetry samples compared with the reference.
    pub samples: usize,
    /// Setpoints sent.
    pub setpoints_sent: usize,
    /// Routes replaced in flight, each a new reference flown on from the old one's state
    /// without stopping (the duration counts the old one up to each switch).
    pub switches: usize,
    /// The longest wall time one of those new references took to make, milliseconds (0
    /// without switches): it must stay under [`super::SPLICE_LEAD_S`] of vehicle time.
    pub slowest_switch_ms: f64,
    /// Reference time at which a replanned route could not be made a trajectory from the
    /// moving vehicle, and the flight went on by waypoints (position targets) instead.
    pub by_waypoints_from_s: Option<f64>,
}

impl TrackingReport {
    /// Flown time over the reference's duration (`None` before the arrival or for a reference
    /// of no duration).
    pub fn time_ratio(&self) -> Option<f64> {
        self.flown_s
            .filter(|_| self.duration_s > 0.0)
            .map(|f| f / self.duration_s)
    }
}

/// A mission the executor cannot fly.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ConfigError(pub String);
