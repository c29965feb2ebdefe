//! The executor core: one state machine, its fault handling and its budgets, shared by both
//! mission strategies (GUIDED position targets in [`super::guided`], the uploaded mission in AUTO
//! in [`crate::auto`]). A strategy decides only TAKEOFF and WAYPOINT and reads mission progress.

use super::faults::{Faults, PendingHold};
use super::interface::{
    Command, CommandKind, Event, FailsafeAction, FlightState, Target, Telemetry, VehicleMode,
};
use super::report::{
    ConfigError, ExecutorConfig, Failure, Note, Outcome, Output, Reached, TrackingReport,
};
use crate::sensing::{ReplanEvent, WayHome};
use std::fmt;

/// How a mission is flown between the take-off and the landing: the part in which the GUIDED
/// and the AUTO executors differ. Everything else (arming, landing, disarming, timeouts, link
/// loss, stop, hold, RTL) is the [`Core`]'s.
pub trait Strategy: Clone + fmt::Debug {
    /// After touchdown, vehicle seconds to wait for the autopilot's own disarm before commanding
    /// one (0: command it at once).
    const DISARM_WAIT_S: f64;
    /// Whether the normal landing (after the last waypoint) is commanded by the executor (GUIDED)
    /// rather than flown by the vehicle from its mission (AUTO).
    const COMMANDS_LANDING: bool;
    /// Whether the route can be replaced in flight ([`Executor::replace_route`]).
    const REPLANS: bool;

    /// The vehicle is in the mode that obeys us (GUIDED / OFFBOARD).
    fn in_control(&self, core: &Core, t: &Telemetry) -> bool;
    /// ARMING is over: armed, in a mode to start the mission from.
    fn ready_to_fly(&self, core: &Core, t: &Telemetry) -> bool;
    /// TAKEOFF was just entered; `true`: step again at once.
    fn start(&mut self, core: &mut Core, now_s: f64, out: &mut Output) -> bool;
    /// One step in TAKEOFF; `true` when it changed the state and the core should step again.
    fn takeoff(&mut self, core: &mut Core, now_s: f64, t: &Telemetry, out: &mut Output) -> bool;
    /// One step in WAYPOINT; `true` when it changed the state and the core should step again.
    fn waypoint(&mut self, core: &mut Core, now_s: f64, t: &Telemetry, out: &mut Output) -> bool;
    /// Sees every event first (mission progress, acknowledgements).
    fn observe(&mut self, core: &mut Core, now_s: f64, event: &Event, out: &mut Output);
    /// How a reference is being followed, for a strategy that flies one.
    fn tracking(&self) -> Option<TrackingReport> {
        None
    }
    /// Whether this strategy can replace its route in flight ([`Executor::replace_route`]):
    /// [`Strategy::REPLANS`], unless the strategy decides per flight.
    fn replaces(&self) -> bool {
        Self::REPLANS
    }
    /// Whether the strategy can replace its route at this moment (by default whenever it
    /// [`Strategy::replaces`]).
    fn replaces_now(&self) -> bool {
        self.replaces()
    }
    /// Replaces the route still to fly with `targets` (from where the vehicle is; the last is
    /// the goal): by default the targets become the route, flown from the first.
    fn replace(
        &mut self,
        core: &mut Core,
        now_s: f64,
        targets: &[Target],
    ) -> Result<(), ConfigError> {
        core.start_route(now_s, targets)
    }
    /// The route still to fly as a route watcher should see it, when it is not the targets
    /// (a reference's path ahead); `None`: the targets from the current one.
    fn route_ahead(&self) -> Option<&[Target]> {
        None
    }
}

/// The state every executor keeps, and the steps all of them share.
#[derive(Debug, Clone)]
pub struct Core {
    pub(crate) config: ExecutorConfig,
    pub(crate) targets: Vec<Target>,
    pub(crate) state: FlightState,
    pub(crate) state_since_s: f64,
    pub(crate) leg_since_s: f64,
    pub(crate) reached: Vec<Reached>,
    pub(crate) last: Option<Telemetry>,
    pub(crate) mode: Option<VehicleMode>,
    /// Since when the vehicle reports a mode other than AUTO (vehicle seconds).
    pub(crate) not_auto_since_s: Option<f64>,
    pub(crate) last_send_s: Option<f64>,
    acked: bool,
    last_refusal: Option<String>,
    last_text: Option<String>,
    /// How the flight ends once the vehicle is down: a stop or a timeout in the air.
    ending: Option<Failure>,
    /// Altitude when LANDING began, metres.
    landing_alt_m: f64,
    /// The altitude the vehicle took off from (its telemetry when the climb began): 0 on flat
    /// ground, the takeoff ground's height above home over terrain.
    takeoff_ground_alt_m: f64,
    outcome: Option<Outcome>,
    started: bool,
    faults: Faults,
    /// A landing the executor commanded (LAND or RTL), re-sent until acknowledged.
    landing_command: Option<Command>,
    /// Entries of `reached` that belong to routes flown before the current one (replans).
    pub(crate) route_start: usize,
    /// Length of the current route's first leg (from the vehicle when it was replanned), metres.
    pub(crate) first_leg_m: f64,
    /// No route to fly: holding here before landing.
    no_route: Option<NoRouteHold>,
    /// Stopped with [`FailsafeAction::Return`]: waiting for the way home, or flying it.
    homing: Option<Homing>,
}

/// A stop with [`FailsafeAction::Return`] in WAYPOINT.
#[derive(Debug, Clone, PartialEq)]
enum Homing {
    /// Holding at `target` (where the vehicle was stopped): first until it is at rest there —
    /// a vehicle stopped at speed overshoots and comes back, and a way home flown from a point it
    /// is still moving through would be skipped past — at most
    /// [`ExecutorConfig::leg_timeout_base_s`]; then until the way home comes, at most
    /// [`ExecutorConfig::replan_hold_s`] (`since_s` restarts when it settles).
    Wanted {
        since_s: f64,
        target: Command,
        from_ned: [f64; 3],
        settled: bool,
    },
    /// Flying the way home, which may take this long (its legs' budgets), seconds.
    Flying { budget_s: f64 },
}

/// The hold after a route watcher found no route.
#[derive(Debug, Clone, PartialEq)]
struct NoRouteHold {
    reason: String,
    since_s: f64,
    target: Command,
}

/// An executor: the [`Core`] with a mission strategy. See [`super::MissionExecutor`] (GUIDED)
/// and [`crate::auto::AutoExecutor`] (AUTO).
#[derive(Debug, Clone)]
pub struct Executor<S> {
    core: Core,
    strategy: S,
}

impl Core {
    fn new(targets: &[Target], config: ExecutorConfig) -> Result<Self, ConfigError> {
        let Some(first) = targets.first() else {
            return Err(ConfigError("the mission has no waypoint".into()));
        };
        if !targets.iter().all(Target::is_finite) {
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
            leg_since_s: 0.0,
            reached: Vec::new(),
            last: None,
            mode: None,
            not_auto_since_s: None,
            last_send_s: None,
            acked: false,
            last_refusal: None,
            last_text: None,
            ending: None,
            landing_alt_m: 0.0,
            takeoff_ground_alt_m: 0.0,
            outcome: None,
            started: false,
            faults: Faults::default(),
            landing_command: None,
            route_start: 0,
            first_leg_m: 0.0,
            no_route: None,
            homing: None,
        })
    }

    /// Enters a state: its clock, sends and acknowledgement start afresh.
    pub(crate) fn enter(&mut self, to: FlightState, now_s: f64, out: &mut Output) {
        out.notes.push(Note::State {
            from: self.state,
            to,
        });
        self.state = to;
        self.state_since_s = now_s;
        self.last_send_s = None;
        self.acked = false;
        self.last_refusal = None;
        if to == FlightState::Takeoff {
            self.takeoff_ground_alt_m = self.last.map_or(0.0, |t| t.alt_m());
        }
        if to == FlightState::Landing {
            // The descent ahead: from here to the ground, which over terrain may be lower
            // than home or than where the vehicle took off; the route's first height above its
            // takeoff ground stands for the height it keeps above the ground.
            let here_m = self.last.map_or(0.0, |t| t.alt_m());
            let above_takeoff_m = here_m - self.takeoff_ground_alt_m;
            let route_m = self.targets.first().map_or(0.0, |t| t.alt_m) - self.takeoff_ground_alt_m;
            self.landing_alt_m = here_m.max(above_takeoff_m).max(route_m).max(0.0);
        }
    }

    /// Whether the climb to a first altitude of `alt_m` is far enough along to go on
    /// (`takeoff_fraction` of the way up from where it began, whatever the ground's height).
    pub(crate) fn climbed(&self, t: &Telemetry, alt_m: f64) -> bool {
        let ground_m = self.takeoff_ground_alt_m;
        t.alt_m() - ground_m >= self.config.takeoff_fraction * (alt_m - ground_m)
    }

    pub(crate) fn finish(&mut self, outcome: Outcome, out: &mut Output) {
        self.outcome = Some(outcome);
        out.notes.push(Note::Finished);
    }

    /// Index in the current route of the waypoint being flown to (== its length once all are
    /// reached).
    pub(crate) fn next_index(&self) -> usize {
        self.reached.len() - self.route_start
    }

    /// Whether the vehicle accepted the command of this state.
    pub(crate) fn acked(&self) -> bool {
        self.acked
    }

    /// Ends the flight with this failure.
    pub(crate) fn fail(&mut self, failure: Failure, out: &mut Output) {
        self.finish(Outcome::Failed(failure), out);
    }

    /// Whether a command with this period is due (and marks it sent).
    pub(crate) fn due(&mut self, now_s: f64, period_s: f64) -> bool {
        let due = self
            .last_send_s
            .is_none_or(|t| now_s - t >= period_s || now_s < t);
        if due {
            self.last_send_s = Some(now_s);
        }
        due
    }

    /// On the ground: the vehicle's landed flag, else low and not moving vertically.
    pub(crate) fn on_ground(&self, t: &Telemetry) -> bool {
        match t.on_ground {
            Some(flag) => flag,
            None => {
                t.alt_m() < self.config.landed_alt_m
                    && t.velocity_ned_m_s[2].abs() < self.config.landed_vertical_speed_m_s
            }
        }
    }

    /// The budget of the leg to waypoint `i`, seconds.
    pub(crate) fn leg_budget_s(&self, i: usize) -> f64 {
        let leg_m = match i {
            0 => self.first_leg_m,
            _ => self.targets[i - 1].horizontal_distance_m(&self.targets[i]),
        };
        self.config.leg_timeout_base_s + self.config.leg_timeout_per_m_s * leg_m
    }

    /// Records waypoint `index` as reached now, with the vehicle's errors (NaN without telemetry).
    pub(crate) fn reach(&mut self, now_s: f64, index: usize, out: &mut Output) {
        let w = self.targets[index];
        let (h, v, yaw) = match &self.last {
            Some(t) => (
                w.horizontal_error_m(t),
                w.vertical_error_m(t),
                w.heading_error_rad(t),
            ),
            None => (f64::NAN, f64::NAN, f64::NAN),
        };
        let r = Reached {
            index,
            time_s: now_s,
            horizontal_error_m: h,
            vertical_error_m: v,
            heading_error_rad: yaw,
        };
        self.reached.push(r);
        out.notes.push(Note::Reached(r));
        self.leg_since_s = now_s;
    }

    /// A state ran out of time. In the air (TAKEOFF, WAYPOINT) the vehicle is told to land and
    /// the flight fails once it is down and disarmed; on the ground, or when the landing itself
    /// runs out, it fails now, saying why.
    pub(crate) fn time_out(&mut self, now_s: f64, after_s: f64, awaited: &str, out: &mut Output) {
        let mut detail = match &self.last_refusal {
            Some(r) => format!("{awaited}; last answer: {r}"),
            None => awaited.to_string(),
        };
        let state = self.state;
        if let Some(ending) = self.ending.take() {
            detail = format!("{ending}; then {state} timed out after {after_s:.1} s: {detail}");
        }
        let failure = Failure::Timeout {
            state,
            after_s,
            detail,
        };
        if matches!(state, FlightState::Takeoff | FlightState::Waypoint) {
            self.ending = Some(failure);
            self.command_landing(now_s, Command::Land, out);
        } else {
            self.fail(failure, out);
        }
    }

    /// Records the vehicle's mode (and since when it is out of AUTO).
    fn set_mode(&mut self, now_s: f64, m: VehicleMode) {
        if m == VehicleMode::Auto {
            self.not_auto_since_s = None;
        } else if self.not_auto_since_s.is_none() {
            self.not_auto_since_s = Some(now_s);
        }
        self.mode = Some(m);
    }

    fn ack(&mut self, command: CommandKind, accepted: Result<(), String>, out: &mut Output) {
        match accepted {
            Ok(()) => {
                let expected = matches!(
                    (self.state, command),
                    (FlightState::Takeoff, CommandKind::Takeoff)
                        | (FlightState::Landing, CommandKind::Land)
                        | (FlightState::Landing, CommandKind::ReturnToLaunch)
                        | (FlightState::Disarming, CommandKind::Disarm)
                );
                self.acked |= expected;
            }
            Err(answer) => {
                let reason = match &self.last_text {
                    Some(text) => format!("{answer}: {text}"),
                    None => answer,
                };
                self.last_refusal = Some(format!("{command} refused ({reason})"));
                out.notes.push(Note::Refused { command, reason });
            }
        }
    }

    /// Lands now (the executor commands it): LANDING, the command sent and re-sent until acked.
    fn command_landing(&mut self, now_s: f64, command: Command, out: &mut Output) {
        self.enter(FlightState::Landing, now_s, out);
        self.landing_command = Some(command);
        out.commands.push(command);
        self.last_send_s = Some(now_s);
    }

    /// Stops the flight early with `action`; `true` when the caller should return at once.
    /// `replans`: the strategy can fly another route ([`FailsafeAction::Return`] needs it; the
    /// others fall back to the autopilot's RTL).
    fn stop(
        &mut self,
        now_s: f64,
        reason: String,
        action: FailsafeAction,
        replans: bool,
        out: &mut Output,
    ) -> bool {
        if self.ending.is_some() || self.faults.hold.is_some() {
            return false;
        }
        match self.state {
            FlightState::Manual | FlightState::Arming => {
                self.fail(Failure::Aborted { reason }, out);
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
                    FailsafeAction::Land => self.command_landing(now_s, Command::Land, out),
                    // Still climbing over the launch point: landing is the way home.
                    FailsafeAction::Return if self.state == FlightState::Takeoff => {
                        self.command_landing(now_s, Command::Land, out)
                    }
                    FailsafeAction::Return if replans && self.last.is_some() => {
                        self.want_way_home(now_s, &reason, out);
                    }
                    FailsafeAction::ReturnToLaunch | FailsafeAction::Return => {
                        self.faults
                            .start_rtl(&self.config, self.last.as_ref(), &self.targets[0]);
                        self.command_landing(now_s, Command::ReturnToLaunch, out);
                    }
                }
                self.ending = Some(Failure::Aborted { reason });
                true
            }
            FlightState::Landing | FlightState::Disarming => {
                self.ending = Some(Failure::Aborted { reason });
                false
            }
        }
    }

    /// One step in ARMING; `true` when TAKEOFF was entered and the strategy should start.
    fn arming<S: Strategy>(&mut self, s: &S, now_s: f64, t: &Telemetry, out: &mut Output) -> bool {
        let c = self.config;
        let guided = s.in_control(self, t);
        if s.ready_to_fly(self, t) {
            self.enter(FlightState::Takeoff, now_s, out);
            return true;
        }
        if now_s - self.state_since_s > c.arming_timeout_s {
            let awaited = if guided {
                "the vehicle did not arm"
            } else {
                "the vehicle did not enter guided mode"
            };
            self.time_out(now_s, c.arming_timeout_s, awaited, out);
        } else if self.due(now_s, c.retry_s) {
            out.commands.push(if guided {
                Command::Arm
            } else {
                Command::TakeControl
            });
        }
        false
    }

    /// One step of the hold after "no route": the held position re-sent, then the landing.
    fn hold_no_route(&mut self, now_s: f64, out: &mut Output) {
        let Some(h) = &self.no_route else {
            return;
        };
        // Held long enough, and at rest: a vehicle stopped at speed brakes past the point and
        // comes back (seen against ArduCopter SITL: told to land 1.8 s after the hold while
        // still at 4.4 m/s, it landed 17 m on, towards what it had sensed), within the leg
        // timeout.
        let moving = self
            .last
            .is_some_and(|t| t.speed_m_s() >= self.config.land_speed_m_s);
        let held_s = now_s - h.since_s;
        if held_s >= self.config.replan_hold_s
            && (!moving || held_s >= self.config.leg_timeout_base_s)
        {
            let reason = h.reason.clone();
            self.no_route = None;
            self.ending = Some(Failure::NoRoute { reason });
            self.command_landing(now_s, Command::Land, out);
        } else {
            let target = h.target;
            if self.due(now_s, self.config.target_period_s) {
                out.commands.push(target);
            }
        }
    }

    /// Makes `targets` the route to fly from where the vehicle is now (a replan, the way home):
    /// the current target restarts at its first, the leg clock restarts. Refused (nothing
    /// changes) for an empty route or a waypoint not finite or not above the ground.
    pub(crate) fn start_route(
        &mut self,
        now_s: f64,
        targets: &[Target],
    ) -> Result<(), ConfigError> {
        if targets.is_empty() {
            return Err(ConfigError("the new route has no waypoint".into()));
        }
        if targets
            .iter()
            .any(|t| !t.is_finite() || t.alt_m <= self.config.landed_alt_m)
        {
            return Err(ConfigError(
                "the new route has a waypoint that is not finite or not above the ground".into(),
            ));
        }
        self.route_start = self.reached.len();
        self.targets = targets.to_vec();
        self.first_leg_m = self
            .last
            .as_ref()
            .map_or(0.0, |t| targets[0].horizontal_error_m(t));
        self.leg_since_s = now_s;
        self.last_send_s = None;
        Ok(())
    }

    /// Holds where the vehicle is and asks for the way home ([`Note::WayHomeWanted`]).
    fn want_way_home(&mut self, now_s: f64, reason: &str, out: &mut Output) {
        let Some(t) = self.last else {
            return;
        };
        let target = Command::GoTo {
            north_m: t.north_m,
            east_m: t.east_m,
            down_m: t.down_m,
            yaw_rad: t.yaw_rad,
        };
        self.homing = Some(Homing::Wanted {
            since_s: now_s,
            target,
            from_ned: [t.north_m, t.east_m, t.down_m],
            settled: false,
        });
        self.no_route = None;
        out.notes.push(Note::WayHomeWanted {
            reason: reason.to_string(),
        });
        self.last_send_s = Some(now_s);
        out.commands.push(target);
    }

    /// One step of the hold while the way home is awaited: the held position re-sent; past
    /// [`ExecutorConfig::replan_hold_s`] without a route, the landing.
    fn hold_for_way_home(&mut self, now_s: f64, out: &mut Output) {
        let Some(Homing::Wanted {
            since_s,
            target,
            from_ned,
            settled,
        }) = self.homing
        else {
            return;
        };
        if !settled {
            let c = self.config;
            let at_rest = self.last.is_some_and(|t| {
                let (dn, de) = (t.north_m - from_ned[0], t.east_m - from_ned[1]);
                dn.hypot(de) <= c.deadband_m
                    && (t.down_m - from_ned[2]).abs() <= c.vertical_deadband_m
                    && t.speed_m_s() < c.land_speed_m_s
            });
            if at_rest {
                self.homing = Some(Homing::Wanted {
                    since_s: now_s,
                    target,
                    from_ned,
                    settled: true,
                });
            } else if now_s - since_s >= c.leg_timeout_base_s {
                let wait_s = c.leg_timeout_base_s;
                self.land_without_way_home(
                    now_s,
                    format!(
                        "the vehicle did not come to rest where it was stopped within {wait_s:.0} s"
                    ),
                    out,
                );
                return;
            }
            if self.due(now_s, c.target_period_s) {
                out.commands.push(target);
            }
            return;
        }
        if now_s - since_s >= self.config.replan_hold_s {
            let hold_s = self.config.replan_hold_s;
            self.land_without_way_home(
                now_s,
                format!("no way home came within {hold_s:.0} s"),
                out,
            );
        } else if self.due(now_s, self.config.target_period_s) {
            out.commands.push(target);
        }
    }

    /// No way home: land where the vehicle is, saying why.
    fn land_without_way_home(&mut self, now_s: f64, why: String, out: &mut Output) {
        self.homing = None;
        if let Some(Failure::Aborted { reason }) = &mut self.ending {
            *reason = format!("{reason}; no way home ({why}): landed where it was");
        }
        out.notes.push(Note::NoWayHome { reason: why });
        self.command_landing(now_s, Command::Land, out);
    }

    /// Whether the flight is in WAYPOINT with nothing else going on (no stop, hold, lost link).
    fn flying_route(&self) -> bool {
        self.state == FlightState::Waypoint
            && self.outcome.is_none()
            && self.ending.is_none()
            && self.faults.hold.is_none()
            && self.faults.lost.is_none()
            && self.no_route.is_none()
    }

    /// Enters LANDING after the last waypoint; the GUIDED strategy commands the landing.
    pub(crate) fn land_after_mission(&mut self, now_s: f64, commanded: bool, out: &mut Output) {
        self.enter(FlightState::Landing, now_s, out);
        self.landing_command = commanded.then_some(Command::Land);
    }

    /// How long LANDING may last before the executor gives up on the touchdown, executor
    /// seconds: the landing timeout and the time to descend, and for a return to launch the
    /// time to fly back too.
    pub(crate) fn landing_budget_s(&self) -> f64 {
        let homing_s = match self.homing {
            None => 0.0,
            Some(Homing::Wanted { .. }) => {
                self.config.leg_timeout_base_s + self.config.replan_hold_s
            }
            Some(Homing::Flying { budget_s }) => budget_s,
        };
        self.faults.landing_budget_s(&self.config)
            + self.landing_alt_m / self.config.landing_descent_m_s.max(0.1)
            + homing_s
    }

    /// One step in LANDING; `true` when DISARMING was entered.
    fn landing(&mut self, now_s: f64, t: &Telemetry, out: &mut Output) -> bool {
        let budget_s = self.landing_budget_s();
        if self.on_ground(t) || !t.armed {
            self.enter(FlightState::Disarming, now_s, out);
            return true;
        }
        if now_s - self.state_since_s > budget_s {
            let awaited = format!(
                "still {:.1} m above home, {}; it was {:.1} m up when the landing began",
                t.alt_m(),
                if t.armed { "armed" } else { "disarmed" },
                self.landing_alt_m
            );
            self.time_out(now_s, budget_s, &awaited, out);
        } else if let Some(command) = self.landing_command
            && !self.acked
            && self.due(now_s, self.config.retry_s)
        {
            out.commands.push(command);
        }
        false
    }

    /// One step in DISARMING: the outcome once disarmed.
    fn disarming(&mut self, now_s: f64, t: &Telemetry, wait_s: f64, out: &mut Output) {
        let c = self.config;
        let in_state_s = now_s - self.state_since_s;
        if !t.armed {
            self.enter(FlightState::Manual, now_s, out);
            let outcome = match self.ending.take() {
                Some(Failure::Timeout {
                    state,
                    after_s,
                    detail,
                }) => Outcome::Failed(Failure::Timeout {
                    state,
                    after_s,
                    detail: format!("{detail}; the vehicle then landed and disarmed"),
                }),
                Some(failure) => Outcome::Failed(failure),
                None if self.next_index() == self.targets.len() => Outcome::Completed,
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
        } else if in_state_s >= wait_s && self.due(now_s, c.retry_s) {
            out.commands.push(Command::Disarm);
        }
    }
}

impl<S: Strategy> Executor<S> {
    pub(crate) fn with_strategy(
        targets: &[Target],
        config: ExecutorConfig,
        strategy: S,
    ) -> Result<Self, ConfigError> {
        Ok(Self {
            core: Core::new(targets, config)?,
            strategy,
        })
    }

    /// The strategy, to set it up after construction.
    pub(crate) fn strategy_mut(&mut self) -> &mut S {
        &mut self.strategy
    }

    /// The current state.
    pub fn state(&self) -> FlightState {
        self.core.state
    }

    /// The waypoints.
    pub fn targets(&self) -> &[Target] {
        &self.core.targets
    }

    /// The vehicle's last reported mode.
    pub fn mode(&self) -> Option<VehicleMode> {
        self.core.mode
    }

    /// The waypoint being flown to (in WAYPOINT), if any.
    pub fn current_target(&self) -> Option<(usize, Target)> {
        match self.core.state {
            FlightState::Waypoint => {
                let i = self.core.next_index().min(self.core.targets.len() - 1);
                Some((i, self.core.targets[i]))
            }
            _ => None,
        }
    }

    /// The waypoints reached so far, in order (after a replan, earlier routes' first).
    pub fn reached(&self) -> &[Reached] {
        &self.core.reached
    }

    /// The targets still to fly (the current one first; empty outside WAYPOINT).
    pub fn remaining_targets(&self) -> &[Target] {
        match self.core.state {
            FlightState::Waypoint if self.core.no_route.is_none() => {
                if let Some(ahead) = self.strategy.route_ahead() {
                    return ahead;
                }
                let i = self.core.next_index().min(self.core.targets.len() - 1);
                &self.core.targets[i..]
            }
            _ => &[],
        }
    }

    /// Whether a route watcher may act now: in WAYPOINT, flying the route (no stop, hold,
    /// lost link or landing under way), with a strategy that can replace its route.
    pub fn accepts_route_change(&self) -> bool {
        self.strategy.replaces_now() && self.core.flying_route()
    }

    /// Replaces the route still to fly with `targets` (from where the vehicle is now; the last
    /// one is the goal) without landing: the current target restarts at the new list's first,
    /// the leg clock restarts, and a [`Note::Replanned`] tells it. Refused (nothing changes)
    /// outside WAYPOINT, by a strategy that cannot replan (AUTO), or for an unusable route.
    pub fn replace_route(
        &mut self,
        now_s: f64,
        targets: &[Target],
        event: ReplanEvent,
    ) -> Result<Output, ConfigError> {
        if !self.strategy.replaces() {
            return Err(ConfigError(
                "this mission strategy cannot change its route in flight".into(),
            ));
        }
        if !self.core.flying_route() {
            return Err(ConfigError(format!(
                "the route can be replaced only while flying it (WAYPOINT), not in {}",
                self.core.state
            )));
        }
        self.strategy.replace(&mut self.core, now_s, targets)?;
        let mut out = Output::default();
        out.notes.push(Note::Replanned {
            event,
            targets: targets.to_vec(),
        });
        self.step(now_s, &mut out);
        Ok(out)
    }

    /// No route can be flown (`reason`): hold the vehicle where it is (its position streamed as
    /// the target, so it stays in GUIDED) for [`ExecutorConfig::replan_hold_s`], then land; the
    /// flight ends in [`Failure::NoRoute`]. Ignored outside WAYPOINT.
    pub fn hold_no_route(&mut self, now_s: f64, reason: String) -> Output {
        let mut out = Output::default();
        let core = &mut self.core;
        if !core.flying_route() {
            return out;
        }
        let Some(t) = core.last else {
            return out;
        };
        let target = Command::GoTo {
            north_m: t.north_m,
            east_m: t.east_m,
            down_m: t.down_m,
            yaw_rad: t.yaw_rad,
        };
        out.notes.push(Note::Holding {
            reason: reason.clone(),
            hold_s: core.config.replan_hold_s,
        });
        core.no_route = Some(NoRouteHold {
            reason,
            since_s: now_s,
            target,
        });
        core.last_send_s = Some(now_s);
        out.commands.push(target);
        out
    }

    /// Where the vehicle was when it stopped with [`FailsafeAction::Return`] and now holds at
    /// rest, waiting for the way home (north, east, down about home, metres); `None` otherwise,
    /// and while it is still braking or coming back to that point.
    pub fn way_home_wanted(&self) -> Option<[f64; 3]> {
        match (&self.core.homing, self.core.state) {
            (
                Some(Homing::Wanted {
                    from_ned,
                    settled: true,
                    ..
                }),
                FlightState::Waypoint,
            ) => Some(*from_ned),
            _ => None,
        }
    }

    /// Flies `way` home (from where the vehicle holds, see [`Executor::way_home_wanted`]) and
    /// lands at its last target; the flight still ends as stopped ([`Failure::Aborted`]),
    /// saying it flew the way home. Refused (nothing changes) unless the way home is wanted or
    /// for an unusable route.
    pub fn return_home(&mut self, now_s: f64, way: &WayHome) -> Result<Output, ConfigError> {
        if self.way_home_wanted().is_none() {
            return Err(ConfigError(
                "no way home is wanted: the flight was not stopped with the return action".into(),
            ));
        }
        let targets = &way.targets;
        let core = &mut self.core;
        core.start_route(now_s, targets)?;
        let budget_s = (0..targets.len()).map(|i| core.leg_budget_s(i)).sum();
        core.homing = Some(Homing::Flying { budget_s });
        if let Some(Failure::Aborted { reason }) = &mut core.ending {
            *reason = format!("{reason}; flew the planned way home");
        }
        let mut out = Output::default();
        out.notes.push(Note::ReturningHome {
            targets: targets.clone(),
            length_m: way.length_m,
            planner: way.planner.clone(),
        });
        self.step(now_s, &mut out);
        Ok(out)
    }

    /// Whether the vehicle was sent on a planned way home ([`Executor::return_home`]).
    pub fn flew_way_home(&self) -> bool {
        matches!(self.core.homing, Some(Homing::Flying { .. }))
    }

    /// No way home (`reason`): the vehicle lands where it is. Ignored unless the way home is
    /// wanted.
    pub fn no_way_home(&mut self, now_s: f64, reason: String) -> Output {
        let mut out = Output::default();
        if self.way_home_wanted().is_some() {
            self.core.land_without_way_home(now_s, reason, &mut out);
        }
        out
    }

    /// How the flight ended, once it has.
    pub fn outcome(&self) -> Option<&Outcome> {
        self.core.outcome.as_ref()
    }

    /// The last telemetry seen.
    pub fn last_telemetry(&self) -> Option<&Telemetry> {
        self.core.last.as_ref()
    }

    /// Distance still to fly along the route from the vehicle, metres (horizontal).
    pub fn distance_left_m(&self) -> f64 {
        let c = &self.core;
        let route_from = |i: usize| -> f64 {
            c.targets[i..]
                .windows(2)
                .map(|w| w[0].horizontal_distance_m(&w[1]))
                .sum()
        };
        let Some(t) = &c.last else {
            return route_from(0);
        };
        let i = match c.state {
            FlightState::Manual if c.outcome.is_none() => 0,
            FlightState::Manual | FlightState::Landing | FlightState::Disarming => return 0.0,
            FlightState::Arming | FlightState::Takeoff => 0,
            FlightState::Waypoint => c.next_index().min(c.targets.len() - 1),
        };
        c.targets[i].horizontal_error_m(t) + route_from(i)
    }

    /// Feeds one event at executor time `now_s` (seconds, monotonic) and returns what to send.
    pub fn handle(&mut self, now_s: f64, event: Event) -> Output {
        let mut out = Output::default();
        let core = &mut self.core;
        if core.outcome.is_some() {
            return out;
        }
        core.faults.observe(&event);
        self.strategy.observe(core, now_s, &event, &mut out);
        match event {
            Event::Telemetry(t) => core.last = Some(t),
            Event::Mode(m) => core.set_mode(now_s, m),
            Event::Ack { command, accepted } => core.ack(command, accepted, &mut out),
            Event::StatusText(text) => core.last_text = Some(text),
            Event::LinkLost { silent_s } => {
                if let Some(failure) =
                    core.faults
                        .link_lost(core.state, silent_s, &core.config, &mut out)
                {
                    core.fail(failure, &mut out);
                }
                return out;
            }
            Event::LinkRegained { silent_s } => {
                if let Some((reason, action)) =
                    core.faults.link_regained(silent_s, &core.config, &mut out)
                    && matches!(core.state, FlightState::Takeoff | FlightState::Waypoint)
                    && core.stop(now_s, reason, action, S::REPLANS, &mut out)
                {
                    return out;
                }
            }
            Event::Abort(reason) => {
                if core.stop(now_s, reason, FailsafeAction::Land, S::REPLANS, &mut out) {
                    return out;
                }
            }
            Event::Stop { reason, action } => {
                if core.stop(now_s, reason, action, S::REPLANS, &mut out) {
                    return out;
                }
            }
            Event::MissionItemReached(_) | Event::MissionCurrent(_) | Event::Tick => {}
        }
        if core.faults.lost.is_some() {
            return out;
        }
        if core.faults.hold.is_some() {
            match core.faults.step_hold(now_s, &core.config, &mut out) {
                Some(Ok(failure)) => core.fail(failure, &mut out),
                Some(Err(reason)) => {
                    core.ending = Some(Failure::Aborted { reason });
                    core.command_landing(now_s, Command::Land, &mut out);
                }
                None => {}
            }
            return out;
        }
        self.step(now_s, &mut out);
        out
    }

    fn step(&mut self, now_s: f64, out: &mut Output) {
        let core = &mut self.core;
        let Some(t) = core.last else {
            return;
        };
        let again = match core.state {
            FlightState::Manual => {
                let first = !core.started;
                if first {
                    core.started = true;
                    core.enter(FlightState::Arming, now_s, out);
                }
                first
            }
            FlightState::Arming => {
                core.arming(&self.strategy, now_s, &t, out) && self.strategy.start(core, now_s, out)
            }
            FlightState::Takeoff => self.strategy.takeoff(core, now_s, &t, out),
            FlightState::Waypoint if core.no_route.is_some() => {
                core.hold_no_route(now_s, out);
                false
            }
            FlightState::Waypoint if matches!(core.homing, Some(Homing::Wanted { .. })) => {
                core.hold_for_way_home(now_s, out);
                false
            }
            FlightState::Waypoint => self.strategy.waypoint(core, now_s, &t, out),
            FlightState::Landing => core.landing(now_s, &t, out),
            FlightState::Disarming => {
                core.disarming(now_s, &t, S::DISARM_WAIT_S, out);
                false
            }
        };
        if again {
            self.step(now_s, out);
        }
    }
}

/// What the link layer needs from an executor: [`super::MissionExecutor`] (position targets in
/// GUIDED) and [`crate::auto::AutoExecutor`] (the uploaded mission in AUTO) both fly through it.
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
    /// How long LANDING may last before the executor gives up on the touchdown, executor
    /// seconds (longer for a return to launch: the way back is in it).
    fn landing_budget_s(&self) -> f64;
    /// The targets still to fly, the current one first (empty outside WAYPOINT).
    fn remaining_targets(&self) -> &[Target];
    /// Whether the route can be changed now ([`Executor::accepts_route_change`]).
    fn accepts_route_change(&self) -> bool;
    /// Whether this executor can ever change its route in flight (GUIDED: yes; AUTO: no).
    fn replans(&self) -> bool;
    /// See [`Executor::replace_route`].
    fn replace_route(
        &mut self,
        now_s: f64,
        targets: &[Target],
        event: ReplanEvent,
    ) -> Result<Output, ConfigError>;
    /// See [`Executor::hold_no_route`].
    fn hold_no_route(&mut self, now_s: f64, reason: String) -> Output;
    /// See [`Executor::way_home_wanted`].
    fn way_home_wanted(&self) -> Option<[f64; 3]>;
    /// See [`Executor::return_home`].
    fn return_home(&mut self, now_s: f64, way: &WayHome) -> Result<Output, ConfigError>;
    /// See [`Executor::no_way_home`].
    fn no_way_home(&mut self, now_s: f64, reason: String) -> Output;
    /// See [`Executor::flew_way_home`].
    fn flew_way_home(&self) -> bool;
    /// How the reference is being followed, for an executor that flies one
    /// ([`super::ReferenceExecutor`]); `None` for the others.
    fn tracking(&self) -> Option<TrackingReport> {
        None
    }
}

impl<S: Strategy> FlightExecutor for Executor<S> {
    fn handle(&mut self, now_s: f64, event: Event) -> Output {
        Executor::handle(self, now_s, event)
    }
    fn state(&self) -> FlightState {
        Executor::state(self)
    }
    fn outcome(&self) -> Option<&Outcome> {
        Executor::outcome(self)
    }
    fn last_telemetry(&self) -> Option<&Telemetry> {
        Executor::last_telemetry(self)
    }
    fn current_target(&self) -> Option<(usize, Target)> {
        Executor::current_target(self)
    }
    fn reached(&self) -> &[Reached] {
        Executor::reached(self)
    }
    fn targets(&self) -> &[Target] {
        Executor::targets(self)
    }
    fn distance_left_m(&self) -> f64 {
        Executor::distance_left_m(self)
    }
    fn landing_budget_s(&self) -> f64 {
        self.core.landing_budget_s()
    }
    fn remaining_targets(&self) -> &[Target] {
        Executor::remaining_targets(self)
    }
    fn accepts_route_change(&self) -> bool {
        Executor::accepts_route_change(self)
    }
    fn replans(&self) -> bool {
        self.strategy.replaces()
    }
    fn replace_route(
        &mut self,
        now_s: f64,
        targets: &[Target],
        event: ReplanEvent,
    ) -> Result<Output, ConfigError> {
        Executor::replace_route(self, now_s, targets, event)
    }
    fn hold_no_route(&mut self, now_s: f64, reason: String) -> Output {
        Executor::hold_no_route(self, now_s, reason)
    }
    fn way_home_wanted(&self) -> Option<[f64; 3]> {
        Executor::way_home_wanted(self)
    }
    fn return_home(&mut self, now_s: f64, way: &WayHome) -> Result<Output, ConfigError> {
        Executor::return_home(self, now_s, way)
    }
    fn no_way_home(&mut self, now_s: f64, reason: String) -> Output {
        Executor::no_way_home(self, now_s, reason)
    }
    fn flew_way_home(&self) -> bool {
        Executor::flew_way_home(self)
    }
    fn tracking(&self) -> Option<TrackingReport> {
        self.strategy.tracking()
    }
}
