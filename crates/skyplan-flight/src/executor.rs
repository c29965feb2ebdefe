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

use std::f64::consts::PI;
use std::fmt;

/// The states of the FCND client (PLANNING runs before the executor starts).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlightState {
    /// Not in control: before the flight, and after it (control released).
    Manual,
    /// Taking control (guided/offboard mode) and arming.
    Arming,
    /// Climbing to the mission altitude.
    Takeoff,
    /// Flying to the waypoints one after another.
    Waypoint,
    /// Descending to the ground.
    Landing,
    /// On the ground, disarming.
    Disarming,
}

impl FlightState {
    /// The FCND name, upper case.
    pub fn name(self) -> &'static str {
        match self {
            FlightState::Manual => "MANUAL",
            FlightState::Arming => "ARMING",
            FlightState::Takeoff => "TAKEOFF",
            FlightState::Waypoint => "WAYPOINT",
            FlightState::Landing => "LANDING",
            FlightState::Disarming => "DISARMING",
        }
    }
}

impl fmt::Display for FlightState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A waypoint to fly to, in the mission's local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// Metres north of home.
    pub north_m: f64,
    /// Metres east of home.
    pub east_m: f64,
    /// Altitude above home, metres (positive up).
    pub alt_m: f64,
    /// Heading to hold, radians clockwise from north.
    pub heading_rad: f64,
}

impl From<&skyplan_mission::Waypoint> for Target {
    fn from(w: &skyplan_mission::Waypoint) -> Self {
        Target {
            north_m: w.north_m,
            east_m: w.east_m,
            alt_m: w.alt_m,
            heading_rad: w.heading_rad,
        }
    }
}

/// What the vehicle reports, merged from its telemetry, in the mission's local frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Telemetry {
    /// Metres north of home.
    pub north_m: f64,
    /// Metres east of home.
    pub east_m: f64,
    /// Metres below home (negative in the air).
    pub down_m: f64,
    /// Velocity north, east, down, m/s.
    pub velocity_ned_m_s: [f64; 3],
    /// Heading, radians clockwise from north.
    pub yaw_rad: f64,
    /// Motors armed.
    pub armed: bool,
    /// The vehicle is in the mode that obeys position targets (GUIDED / OFFBOARD).
    pub guided: bool,
    /// The vehicle's own landed flag, when it sends one (EXTENDED_SYS_STATE).
    pub on_ground: Option<bool>,
}

impl Telemetry {
    /// Altitude above home, metres.
    pub fn alt_m(&self) -> f64 {
        -self.down_m
    }
    /// Horizontal speed, m/s.
    pub fn ground_speed_m_s(&self) -> f64 {
        self.velocity_ned_m_s[0].hypot(self.velocity_ned_m_s[1])
    }
    /// Speed, m/s.
    pub fn speed_m_s(&self) -> f64 {
        self.ground_speed_m_s().hypot(self.velocity_ned_m_s[2])
    }
}

/// The commands that the vehicle acknowledges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommandKind {
    /// Enter the guided/offboard mode.
    TakeControl,
    /// Arm the motors.
    Arm,
    /// Take off.
    Takeoff,
    /// Land.
    Land,
    /// Disarm the motors.
    Disarm,
    /// Start the uploaded mission (AUTO, MISSION_START).
    StartMission,
    /// Hold position (LOITER / PX4 HOLD).
    Hold,
    /// Return to launch (RTL).
    ReturnToLaunch,
}

impl fmt::Display for CommandKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CommandKind::TakeControl => "guided mode",
            CommandKind::Arm => "arming",
            CommandKind::Takeoff => "takeoff",
            CommandKind::Land => "landing",
            CommandKind::Disarm => "disarming",
            CommandKind::StartMission => "mission start",
            CommandKind::Hold => "hold",
            CommandKind::ReturnToLaunch => "return to launch",
        })
    }
}

/// What the executor asks the link to send.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Switch to the mode that obeys position targets (GUIDED / OFFBOARD).
    TakeControl,
    /// Arm.
    Arm,
    /// Take off to this altitude above home.
    Takeoff {
        /// Metres above home.
        alt_m: f64,
    },
    /// Fly to a position and hold a heading (SET_POSITION_TARGET_LOCAL_NED, position + yaw).
    GoTo {
        /// Metres north of home.
        north_m: f64,
        /// Metres east of home.
        east_m: f64,
        /// Metres below home.
        down_m: f64,
        /// Heading, radians clockwise from north.
        yaw_rad: f64,
    },
    /// Land where the vehicle is.
    Land,
    /// Disarm.
    Disarm,
    /// Fly the uploaded mission: AUTO mode, then MISSION_START.
    StartMission,
    /// Hold the position (ArduCopter LOITER, PX4 AUTO.LOITER).
    Hold,
    /// Return to launch and land there (RTL).
    ReturnToLaunch,
}

/// The vehicle's flight mode, as far as the executors care.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VehicleMode {
    /// Obeys position targets (ArduCopter GUIDED, PX4 OFFBOARD).
    Guided,
    /// Flies the uploaded mission (ArduCopter AUTO, PX4 AUTO.MISSION).
    Auto,
    /// Landing (LAND).
    Land,
    /// Holding position (LOITER, BRAKE, PX4 AUTO.LOITER).
    Hold,
    /// Returning to launch (RTL).
    ReturnToLaunch,
    /// Anything else (a pilot mode such as STABILIZE); the number is the custom mode.
    Other(u32),
}

impl fmt::Display for VehicleMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VehicleMode::Guided => f.write_str("GUIDED"),
            VehicleMode::Auto => f.write_str("AUTO"),
            VehicleMode::Land => f.write_str("LAND"),
            VehicleMode::Hold => f.write_str("HOLD"),
            VehicleMode::ReturnToLaunch => f.write_str("RTL"),
            VehicleMode::Other(m) => write!(f, "custom mode {m}"),
        }
    }
}

/// What the executor tells the vehicle to do when it stops a flight early: on a Ctrl-C
/// ([`Event::Stop`]) or when a lost link comes back ([`ExecutorConfig::failsafe`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FailsafeAction {
    /// Land where it is (NAV_LAND), then disarm.
    Land,
    /// Return to the launch point and land there (RTL), then disarm.
    ReturnToLaunch,
    /// Hold the position in the air (LOITER / PX4 HOLD); the flight ends once the vehicle
    /// confirms, leaving it to the pilot.
    Hold,
}

impl fmt::Display for FailsafeAction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FailsafeAction::Land => "land",
            FailsafeAction::ReturnToLaunch => "rtl",
            FailsafeAction::Hold => "hold",
        })
    }
}

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
    /// The flight ended; see [`MissionExecutor::outcome`].
    Finished,
}

/// A reached waypoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reached {
    /// Index of the waypoint in the mission.
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
    /// Budget of LANDING, seconds.
    pub landing_timeout_s: f64,
    /// Budget of DISARMING, seconds.
    pub disarming_timeout_s: f64,
    /// What to command when a lost link comes back; `None`: a lost link ends the flight at once
    /// (nothing more can be commanded). Only in the air (TAKEOFF, WAYPOINT; LANDING and
    /// DISARMING resume): on the ground a lost link always ends the flight.
    pub failsafe: Option<FailsafeAction>,
    /// With `failsafe`: how long to wait for the link to come back, in the clock of
    /// [`Event::LinkLost`]'s `silent_s` (the link layer's wall clock) before giving up.
    pub link_regain_wait_s: f64,
    /// A commanded hold not confirmed (acknowledged, or the mode reported) within this many
    /// seconds becomes a landing.
    pub hold_confirm_s: f64,
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
            landing_timeout_s: 120.0,
            disarming_timeout_s: 20.0,
            failsafe: None,
            link_regain_wait_s: 30.0,
            hold_confirm_s: 10.0,
        }
    }
}

/// A mission the executor cannot fly.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigError(pub String);

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ConfigError {}

/// Angle difference wrapped to (−π, π].
pub fn wrap_angle_rad(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI { w + 2.0 * PI } else { w }
}

/// A commanded hold awaiting the vehicle's confirmation.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PendingHold {
    pub(crate) reason: String,
    pub(crate) state: FlightState,
    pub(crate) since_s: f64,
    pub(crate) last_send_s: f64,
    pub(crate) confirmed: bool,
}

/// Link-loss, hold and return-to-launch bookkeeping, shared by both executors.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Faults {
    /// The link is lost (waiting for it): the state then.
    pub(crate) lost: Option<FlightState>,
    /// A hold was commanded.
    pub(crate) hold: Option<PendingHold>,
    /// The landing is a return to launch, with this LANDING budget (seconds).
    pub(crate) rtl_budget_s: Option<f64>,
}

impl Faults {
    /// Confirms a pending hold from an accepted ack or the reported mode.
    pub(crate) fn observe(&mut self, event: &Event) {
        if let Some(h) = &mut self.hold
            && matches!(
                event,
                Event::Ack {
                    command: CommandKind::Hold,
                    accepted: Ok(())
                } | Event::Mode(VehicleMode::Hold)
            )
        {
            h.confirmed = true;
        }
    }

    /// A lost link: `Some(failure)` ends the flight now; `None` waits for the link.
    pub(crate) fn link_lost(
        &mut self,
        state: FlightState,
        silent_s: f64,
        c: &ExecutorConfig,
        out: &mut Output,
    ) -> Option<Failure> {
        if let Some(lost_in) = self.lost {
            return (silent_s > c.link_regain_wait_s).then_some(Failure::LinkLost {
                state: lost_in,
                silent_s,
            });
        }
        match c.failsafe {
            Some(action) if !matches!(state, FlightState::Manual | FlightState::Arming) => {
                self.lost = Some(state);
                out.notes.push(Note::LinkLost {
                    state,
                    silent_s,
                    wait_s: c.link_regain_wait_s,
                    action,
                });
                None
            }
            _ => Some(Failure::LinkLost { state, silent_s }),
        }
    }

    /// The link came back: the reason and action to stop the flight with, if it was lost.
    pub(crate) fn link_regained(
        &mut self,
        silent_s: f64,
        c: &ExecutorConfig,
        out: &mut Output,
    ) -> Option<(String, FailsafeAction)> {
        let state = self.lost.take()?;
        let action = c.failsafe.unwrap_or(FailsafeAction::Land);
        out.notes.push(Note::LinkRegained { silent_s, action });
        Some((
            format!("link lost in {state} for {silent_s:.1} s; --failsafe {action} on its return"),
            action,
        ))
    }

    /// The LANDING budget: longer for a return to launch.
    pub(crate) fn landing_budget_s(&self, c: &ExecutorConfig) -> f64 {
        self.rtl_budget_s.unwrap_or(c.landing_timeout_s)
    }

    /// Starts a return to launch from `t` toward the launch point `home`.
    pub(crate) fn start_rtl(&mut self, c: &ExecutorConfig, t: Option<&Telemetry>, home: &Target) {
        let far_m = t.map_or(0.0, |t| {
            (home.north_m - t.north_m).hypot(home.east_m - t.east_m)
        });
        self.rtl_budget_s =
            Some(c.landing_timeout_s + c.leg_timeout_base_s + c.leg_timeout_per_m_s * far_m);
    }

    /// Drives a pending hold: `Err(reason)` when unconfirmed too long (land instead), the
    /// failure once confirmed, else the commands to repeat.
    pub(crate) fn step_hold(
        &mut self,
        now_s: f64,
        c: &ExecutorConfig,
        out: &mut Output,
    ) -> Option<Result<Failure, String>> {
        let h = self.hold.as_mut()?;
        if h.confirmed {
            return Some(Ok(Failure::Held {
                reason: h.reason.clone(),
                state: h.state,
            }));
        }
        if now_s - h.since_s > c.hold_confirm_s {
            let reason = format!(
                "{}; the hold was not confirmed within {:.0} s, landing instead",
                h.reason, c.hold_confirm_s
            );
            self.hold = None;
            return Some(Err(reason));
        }
        if now_s - h.last_send_s >= c.retry_s || now_s < h.last_send_s {
            h.last_send_s = now_s;
            out.commands.push(Command::Hold);
        }
        None
    }
}

/// The state machine. See the module documentation.
#[derive(Debug, Clone)]
pub struct MissionExecutor {
    config: ExecutorConfig,
    targets: Vec<Target>,
    state: FlightState,
    state_since_s: f64,
    /// Index of the waypoint being flown to.
    next: usize,
    leg_since_s: f64,
    reached: Vec<Reached>,
    last: Option<Telemetry>,
    last_send_s: Option<f64>,
    acked: bool,
    last_refusal: Option<String>,
    last_text: Option<String>,
    abort: Option<String>,
    outcome: Option<Outcome>,
    started: bool,
    faults: Faults,
}

impl MissionExecutor {
    /// An executor for these waypoints (at least one, at a positive altitude).
    pub fn new(targets: &[Target], config: ExecutorConfig) -> Result<Self, ConfigError> {
        let Some(first) = targets.first() else {
            return Err(ConfigError("the mission has no waypoint".into()));
        };
        if targets.iter().any(|t| {
            !(t.north_m.is_finite()
                && t.east_m.is_finite()
                && t.alt_m.is_finite()
                && t.heading_rad.is_finite())
        }) {
            return Err(ConfigError("a waypoint is not a finite number".into()));
        }
        if first.alt_m <= config.landed_alt_m {
            return Err(ConfigError(format!(
                "the flight altitude {} m is not above the ground (> {} m)",
                first.alt_m, config.landed_alt_m
            )));
        }
        Ok(Self {
            config,
            targets: targets.to_vec(),
            state: FlightState::Manual,
            state_since_s: 0.0,
            next: 0,
            leg_since_s: 0.0,
            reached: Vec::new(),
            last: None,
            last_send_s: None,
            acked: false,
            last_refusal: None,
            last_text: None,
            abort: None,
            outcome: None,
            started: false,
            faults: Faults::default(),
        })
    }

    /// The current state.
    pub fn state(&self) -> FlightState {
        self.state
    }

    /// The waypoints.
    pub fn targets(&self) -> &[Target] {
        &self.targets
    }

    /// The waypoint being flown to (in WAYPOINT), if any.
    pub fn current_target(&self) -> Option<(usize, Target)> {
        match self.state {
            FlightState::Waypoint => {
                let i = self.next.min(self.targets.len() - 1);
                Some((i, self.targets[i]))
            }
            _ => None,
        }
    }

    /// The waypoints reached so far, in order.
    pub fn reached(&self) -> &[Reached] {
        &self.reached
    }

    /// How the flight ended, once it has.
    pub fn outcome(&self) -> Option<&Outcome> {
        self.outcome.as_ref()
    }

    /// The last telemetry seen.
    pub fn last_telemetry(&self) -> Option<&Telemetry> {
        self.last.as_ref()
    }

    /// Distance still to fly along the route from the vehicle, metres (horizontal).
    pub fn distance_left_m(&self) -> f64 {
        let Some(t) = &self.last else {
            return self.route_length_from(0);
        };
        let i = match self.state {
            FlightState::Manual if self.outcome.is_none() => 0,
            FlightState::Manual | FlightState::Landing | FlightState::Disarming => {
                return 0.0;
            }
            FlightState::Arming | FlightState::Takeoff => 0,
            FlightState::Waypoint => self.next.min(self.targets.len() - 1),
        };
        let w = self.targets[i];
        (w.north_m - t.north_m).hypot(w.east_m - t.east_m) + self.route_length_from(i)
    }

    fn route_length_from(&self, i: usize) -> f64 {
        self.targets[i..]
            .windows(2)
            .map(|w| (w[1].north_m - w[0].north_m).hypot(w[1].east_m - w[0].east_m))
            .sum()
    }

    /// Feeds one event at executor time `now_s` (seconds, monotonic) and returns what to send.
    pub fn handle(&mut self, now_s: f64, event: Event) -> Output {
        let mut out = Output::default();
        if self.outcome.is_some() {
            return out;
        }
        self.faults.observe(&event);
        match event {
            Event::Telemetry(t) => self.last = Some(t),
            Event::Ack { command, accepted } => match accepted {
                Ok(()) => {
                    if self.expects(command) {
                        self.acked = true;
                    }
                }
                Err(answer) => {
                    let reason = match &self.last_text {
                        Some(text) => format!("{answer}: {text}"),
                        None => answer,
                    };
                    self.last_refusal = Some(format!("{command} refused ({reason})"));
                    out.notes.push(Note::Refused { command, reason });
                }
            },
            Event::StatusText(text) => self.last_text = Some(text),
            Event::LinkLost { silent_s } => {
                if let Some(failure) =
                    self.faults
                        .link_lost(self.state, silent_s, &self.config, &mut out)
                {
                    self.finish(Outcome::Failed(failure), &mut out);
                }
                return out;
            }
            Event::LinkRegained { silent_s } => {
                if let Some((reason, action)) =
                    self.faults.link_regained(silent_s, &self.config, &mut out)
                    && matches!(self.state, FlightState::Takeoff | FlightState::Waypoint)
                    && self.stop(now_s, reason, action, &mut out)
                {
                    return out;
                }
            }
            Event::Abort(reason) => {
                if self.stop(now_s, reason, FailsafeAction::Land, &mut out) {
                    return out;
                }
            }
            Event::Stop { reason, action } => {
                if self.stop(now_s, reason, action, &mut out) {
                    return out;
                }
            }
            Event::Mode(_)
            | Event::MissionItemReached(_)
            | Event::MissionCurrent(_)
            | Event::Tick => {}
        }
        if self.faults.lost.is_some() {
            return out;
        }
        if self.faults.hold.is_some() {
            match self.faults.step_hold(now_s, &self.config, &mut out) {
                Some(Ok(failure)) => self.finish(Outcome::Failed(failure), &mut out),
                Some(Err(reason)) => {
                    self.abort = Some(reason);
                    self.enter(FlightState::Landing, now_s, &mut out);
                    out.commands.push(Command::Land);
                    self.last_send_s = Some(now_s);
                }
                None => {}
            }
            return out;
        }
        self.step(now_s, &mut out);
        out
    }

    /// Stops the flight early with `action`; `true` when the caller should return at once.
    fn stop(
        &mut self,
        now_s: f64,
        reason: String,
        action: FailsafeAction,
        out: &mut Output,
    ) -> bool {
        if self.abort.is_some() || self.faults.hold.is_some() {
            return false;
        }
        match self.state {
            FlightState::Manual | FlightState::Arming => {
                self.abort = Some(reason.clone());
                self.finish(Outcome::Failed(Failure::Aborted { reason }), out);
                if self.last.is_some_and(|t| t.armed) {
                    out.commands.push(Command::Disarm);
                }
                true
            }
            FlightState::Takeoff | FlightState::Waypoint => {
                match action {
                    FailsafeAction::Hold => {
                        self.faults.hold = Some(PendingHold {
                            reason,
                            state: self.state,
                            since_s: now_s,
                            last_send_s: now_s,
                            confirmed: false,
                        });
                        out.commands.push(Command::Hold);
                        return true;
                    }
                    FailsafeAction::Land => {
                        self.enter(FlightState::Landing, now_s, out);
                        out.commands.push(Command::Land);
                    }
                    FailsafeAction::ReturnToLaunch => {
                        self.faults
                            .start_rtl(&self.config, self.last.as_ref(), &self.targets[0]);
                        self.enter(FlightState::Landing, now_s, out);
                        out.commands.push(Command::ReturnToLaunch);
                    }
                }
                self.abort = Some(reason);
                self.last_send_s = Some(now_s);
                true
            }
            FlightState::Landing | FlightState::Disarming => {
                self.abort = Some(reason);
                false
            }
        }
    }

    fn expects(&self, command: CommandKind) -> bool {
        matches!(
            (self.state, command),
            (FlightState::Takeoff, CommandKind::Takeoff)
                | (FlightState::Landing, CommandKind::Land)
                | (FlightState::Landing, CommandKind::ReturnToLaunch)
                | (FlightState::Disarming, CommandKind::Disarm)
        )
    }

    fn enter(&mut self, to: FlightState, now_s: f64, out: &mut Output) {
        out.notes.push(Note::State {
            from: self.state,
            to,
        });
        self.state = to;
        self.state_since_s = now_s;
        self.last_send_s = None;
        self.acked = false;
        self.last_refusal = None;
    }

    fn finish(&mut self, outcome: Outcome, out: &mut Output) {
        self.outcome = Some(outcome);
        out.notes.push(Note::Finished);
    }

    /// Fails with a timeout, landing first if the vehicle may be in the air.
    fn time_out(&mut self, now_s: f64, after_s: f64, awaited: &str, out: &mut Output) {
        let detail = match &self.last_refusal {
            Some(r) => format!("{awaited}; last answer: {r}"),
            None => awaited.to_string(),
        };
        let state = self.state;
        if matches!(state, FlightState::Takeoff | FlightState::Waypoint) {
            out.commands.push(Command::Land);
        }
        let _ = now_s;
        self.finish(
            Outcome::Failed(Failure::Timeout {
                state,
                after_s,
                detail,
            }),
            out,
        );
    }

    fn due(&mut self, now_s: f64, period_s: f64) -> bool {
        let due = self
            .last_send_s
            .is_none_or(|t| now_s - t >= period_s || now_s < t);
        if due {
            self.last_send_s = Some(now_s);
        }
        due
    }

    fn goto(&self, i: usize) -> Command {
        let w = self.targets[i];
        Command::GoTo {
            north_m: w.north_m,
            east_m: w.east_m,
            down_m: -w.alt_m,
            yaw_rad: w.heading_rad,
        }
    }

    fn on_ground(&self, t: &Telemetry) -> bool {
        match t.on_ground {
            Some(flag) => flag,
            None => {
                t.alt_m() < self.config.landed_alt_m
                    && t.velocity_ned_m_s[2].abs() < self.config.landed_vertical_speed_m_s
            }
        }
    }

    fn step(&mut self, now_s: f64, out: &mut Output) {
        let Some(t) = self.last else {
            return;
        };
        let c = self.config;
        let in_state_s = now_s - self.state_since_s;
        match self.state {
            FlightState::Manual => {
                if !self.started {
                    self.started = true;
                    self.enter(FlightState::Arming, now_s, out);
                    self.step(now_s, out);
                }
            }
            FlightState::Arming => {
                if t.guided && t.armed {
                    self.enter(FlightState::Takeoff, now_s, out);
                    self.step(now_s, out);
                } else if in_state_s > c.arming_timeout_s {
                    let awaited = if t.guided {
                        "the vehicle did not arm"
                    } else {
                        "the vehicle did not enter guided mode"
                    };
                    self.time_out(now_s, c.arming_timeout_s, awaited, out);
                } else if self.due(now_s, c.retry_s) {
                    out.commands.push(if t.guided {
                        Command::Arm
                    } else {
                        Command::TakeControl
                    });
                }
            }
            FlightState::Takeoff => {
                let alt_m = self.targets[0].alt_m;
                if !t.armed {
                    self.finish(
                        Outcome::Failed(Failure::DisarmedInFlight { state: self.state }),
                        out,
                    );
                } else if !t.guided {
                    self.finish(
                        Outcome::Failed(Failure::ControlLost { state: self.state }),
                        out,
                    );
                } else if t.alt_m() >= c.takeoff_fraction * alt_m {
                    self.enter(FlightState::Waypoint, now_s, out);
                    self.next = 0;
                    self.leg_since_s = now_s;
                    self.step(now_s, out);
                } else if in_state_s > c.takeoff_timeout_s {
                    let awaited = format!(
                        "the vehicle reached {:.1} m of the {:.1} m needed",
                        t.alt_m(),
                        c.takeoff_fraction * alt_m
                    );
                    self.time_out(now_s, c.takeoff_timeout_s, &awaited, out);
                } else if !self.acked && self.due(now_s, c.retry_s) {
                    out.commands.push(Command::Takeoff { alt_m });
                }
            }
            FlightState::Waypoint => {
                if !t.armed {
                    self.finish(
                        Outcome::Failed(Failure::DisarmedInFlight { state: self.state }),
                        out,
                    );
                    return;
                }
                if !t.guided {
                    self.finish(
                        Outcome::Failed(Failure::ControlLost { state: self.state }),
                        out,
                    );
                    return;
                }
                let n = self.targets.len();
                // Reach as many waypoints as the vehicle is already at (a repeated point).
                while self.next < n {
                    let w = self.targets[self.next];
                    let h = (w.north_m - t.north_m).hypot(w.east_m - t.east_m);
                    let v = (w.alt_m - t.alt_m()).abs();
                    let yaw = wrap_angle_rad(w.heading_rad - t.yaw_rad).abs();
                    let deadband = c.deadband_m + c.deadband_per_speed_s * t.ground_speed_m_s();
                    if h <= deadband && v <= c.vertical_deadband_m && yaw <= c.heading_tolerance_rad
                    {
                        let r = Reached {
                            index: self.next,
                            time_s: now_s,
                            horizontal_error_m: h,
                            vertical_error_m: v,
                            heading_error_rad: yaw,
                        };
                        self.reached.push(r);
                        out.notes.push(Note::Reached(r));
                        self.next += 1;
                        self.leg_since_s = now_s;
                        self.last_send_s = None;
                    } else {
                        break;
                    }
                }
                if self.next >= n && t.speed_m_s() < c.land_speed_m_s {
                    self.enter(FlightState::Landing, now_s, out);
                    self.step(now_s, out);
                    return;
                }
                let i = self.next.min(n - 1);
                let leg_m = if i == 0 {
                    0.0
                } else {
                    let (a, b) = (self.targets[i - 1], self.targets[i]);
                    (b.north_m - a.north_m).hypot(b.east_m - a.east_m)
                };
                let budget_s = c.leg_timeout_base_s + c.leg_timeout_per_m_s * leg_m;
                if now_s - self.leg_since_s > budget_s {
                    let w = self.targets[i];
                    let awaited = if self.next >= n {
                        format!(
                            "the vehicle did not slow below {} m/s at the last waypoint",
                            c.land_speed_m_s
                        )
                    } else {
                        format!(
                            "waypoint {} of {n} not reached: {:.1} m away horizontally, {:.1} m vertically, heading off by {:.1}°",
                            i + 1,
                            (w.north_m - t.north_m).hypot(w.east_m - t.east_m),
                            (w.alt_m - t.alt_m()).abs(),
                            wrap_angle_rad(w.heading_rad - t.yaw_rad).abs().to_degrees()
                        )
                    };
                    self.time_out(now_s, budget_s, &awaited, out);
                } else if self.due(now_s, c.target_period_s) {
                    out.commands.push(self.goto(i));
                }
            }
            FlightState::Landing => {
                let budget_s = self.faults.landing_budget_s(&c);
                if self.on_ground(&t) || !t.armed {
                    self.enter(FlightState::Disarming, now_s, out);
                    self.step(now_s, out);
                } else if in_state_s > budget_s {
                    let awaited = format!("still {:.1} m above home", t.alt_m());
                    self.time_out(now_s, budget_s, &awaited, out);
                } else if !self.acked && self.due(now_s, c.retry_s) {
                    out.commands.push(if self.faults.rtl_budget_s.is_some() {
                        Command::ReturnToLaunch
                    } else {
                        Command::Land
                    });
                }
            }
            FlightState::Disarming => {
                if !t.armed {
                    self.enter(FlightState::Manual, now_s, out);
                    let outcome = match self.abort.take() {
                        Some(reason) => Outcome::Failed(Failure::Aborted { reason }),
                        None if self.reached.len() == self.targets.len() => Outcome::Completed,
                        None => Outcome::Failed(Failure::Aborted {
                            reason: "landed before the last waypoint".into(),
                        }),
                    };
                    self.finish(outcome, out);
                } else if in_state_s > c.disarming_timeout_s {
                    self.time_out(
                        now_s,
                        c.disarming_timeout_s,
                        "the vehicle did not disarm",
                        out,
                    );
                } else if self.due(now_s, c.retry_s) {
                    out.commands.push(Command::Disarm);
                }
            }
        }
    }
}

/// What the executor is told.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// New telemetry (the merged latest state of the vehicle).
    Telemetry(Telemetry),
    /// The vehicle answered a command: `Ok` if accepted, else its answer (e.g. "DENIED").
    Ack {
        /// The command.
        command: CommandKind,
        /// Accepted, or the answer.
        accepted: Result<(), String>,
    },
    /// A status text from the vehicle (kept to explain refusals).
    StatusText(String),
    /// No heartbeat from the vehicle for this long: the flight is over.
    LinkLost {
        /// Seconds without a heartbeat.
        silent_s: f64,
    },
    /// Stop the flight: land if in the air (Ctrl-C, overall timeout).
    Abort(String),
    /// Stop the flight with this action if in the air (Ctrl-C with `--on-interrupt hold`);
    /// on the ground it ends the flight (disarming) whatever the action.
    Stop {
        /// Why.
        reason: String,
        /// Land, return to launch or hold.
        action: FailsafeAction,
    },
    /// A heartbeat came back after [`Event::LinkLost`]: with [`ExecutorConfig::failsafe`],
    /// the executor commands it.
    LinkRegained {
        /// Seconds the vehicle was silent.
        silent_s: f64,
    },
    /// The vehicle's mode, from each of its heartbeats.
    Mode(VehicleMode),
    /// MISSION_ITEM_REACHED: the vehicle reached this item of the uploaded mission.
    MissionItemReached(u16),
    /// MISSION_CURRENT: the vehicle is flying to this item of the uploaded mission.
    MissionCurrent(u16),
    /// Time passes.
    Tick,
}

/// What the link layer needs from an executor: [`MissionExecutor`] (position targets in GUIDED)
/// and [`crate::auto::AutoExecutor`] (the uploaded mission in AUTO) both fly through it.
pub trait FlightExecutor {
    /// Feeds one event at executor time `now_s` (seconds, monotonic) and returns what to send.
    fn handle(&mut self, now_s: f64, event: Event) -> Output;
    /// The current state.
    fn state(&self) -> FlightState;
    /// How the flight ended, once it has.
    fn outcome(&self) -> Option<&Outcome>;
    /// The last telemetry seen.
    fn last_telemetry(&self) -> Option<&Telemetry>;
    /// The waypoint being flown to (in WAYPOINT), with its index.
    fn current_target(&self) -> Option<(usize, Target)>;
    /// The waypoints reached so far, in order.
    fn reached(&self) -> &[Reached];
    /// The waypoints.
    fn targets(&self) -> &[Target];
    /// Horizontal distance still to fly along the route, metres.
    fn distance_left_m(&self) -> f64;
}

impl FlightExecutor for MissionExecutor {
    fn handle(&mut self, now_s: f64, event: Event) -> Output {
        MissionExecutor::handle(self, now_s, event)
    }
    fn state(&self) -> FlightState {
        MissionExecutor::state(self)
    }
    fn outcome(&self) -> Option<&Outcome> {
        MissionExecutor::outcome(self)
    }
    fn last_telemetry(&self) -> Option<&Telemetry> {
        MissionExecutor::last_telemetry(self)
    }
    fn current_target(&self) -> Option<(usize, Target)> {
        MissionExecutor::current_target(self)
    }
    fn reached(&self) -> &[Reached] {
        MissionExecutor::reached(self)
    }
    fn targets(&self) -> &[Target] {
        MissionExecutor::targets(self)
    }
    fn distance_left_m(&self) -> f64 {
        MissionExecutor::distance_left_m(self)
    }
}

#[cfg(test)]
mod tests;
