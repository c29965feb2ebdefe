//! Flying an uploaded mission in AUTO, without I/O: the `--upload` counterpart of
//! [`MissionExecutor`](crate::executor::MissionExecutor).
//!
//! The vehicle flies the items itself (see [`crate::upload`]); the executor takes control
//! (GUIDED), arms, starts the mission (AUTO + MISSION_START), follows its progress from
//! MISSION_ITEM_REACHED and MISSION_CURRENT, and watches the landing and the disarm. Its states
//! are the FCND ones, so logs and output read the same as a GUIDED flight: MANUAL → ARMING →
//! TAKEOFF (the take-off item) → WAYPOINT (the waypoint items) → LANDING (the land item) →
//! DISARMING → MANUAL. It fails on the same faults: a state's timeout, a lost link, a disarm in
//! flight, the vehicle leaving AUTO (a pilot or failsafe took over), and lands on an abort.

use crate::executor::{
    Command, CommandKind, ConfigError, Event, ExecutorConfig, FailsafeAction, Failure, Faults,
    FlightExecutor, FlightState, Note, Outcome, Output, PendingHold, Reached, Target, Telemetry,
    VehicleMode, wrap_angle_rad,
};
use crate::upload::MissionPlan;

/// After touchdown, wait this long (vehicle seconds) for the autopilot's own disarm before
/// commanding one.
pub const AUTO_DISARM_WAIT_S: f64 = 3.0;

/// A vehicle out of AUTO for this long (vehicle seconds) mid-mission has been taken over; the
/// grace covers the vehicle switching to LAND for the land item (as `skyplan sim` does) a moment
/// before its MISSION_CURRENT says so.
pub const LEFT_AUTO_GRACE_S: f64 = 1.5;

/// Where the flown parts are in the uploaded mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MissionLayout {
    /// The NAV_TAKEOFF item.
    pub takeoff_seq: u16,
    /// The first waypoint's item; waypoint `k` is item `first_waypoint_seq + k`.
    pub first_waypoint_seq: u16,
    /// The NAV_LAND item.
    pub land_seq: u16,
}

impl From<&MissionPlan> for MissionLayout {
    fn from(p: &MissionPlan) -> Self {
        Self {
            takeoff_seq: p.takeoff_seq,
            first_waypoint_seq: p.first_waypoint_seq,
            land_seq: p.land_seq,
        }
    }
}

/// The AUTO executor. See the module documentation.
#[derive(Debug, Clone)]
pub struct AutoExecutor {
    config: ExecutorConfig,
    targets: Vec<Target>,
    layout: MissionLayout,
    state: FlightState,
    state_since_s: f64,
    leg_since_s: f64,
    last: Option<Telemetry>,
    mode: Option<VehicleMode>,
    not_auto_since_s: Option<f64>,
    seen_auto: bool,
    takeoff_done: bool,
    land_started: bool,
    reached: Vec<Reached>,
    last_send_s: Option<f64>,
    last_refusal: Option<String>,
    last_text: Option<String>,
    abort: Option<String>,
    outcome: Option<Outcome>,
    started: bool,
    faults: Faults,
}

impl AutoExecutor {
    /// An executor for these waypoints, uploaded with this layout.
    pub fn new(
        targets: &[Target],
        layout: MissionLayout,
        config: ExecutorConfig,
    ) -> Result<Self, ConfigError> {
        let Some(first) = targets.first() else {
            return Err(ConfigError("the mission has no waypoint".into()));
        };
        if usize::from(layout.land_seq) != usize::from(layout.first_waypoint_seq) + targets.len()
            || layout.takeoff_seq >= layout.first_waypoint_seq
        {
            return Err(ConfigError(format!(
                "the mission layout {layout:?} does not match {} waypoints",
                targets.len()
            )));
        }
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
            layout,
            state: FlightState::Manual,
            state_since_s: 0.0,
            leg_since_s: 0.0,
            last: None,
            mode: None,
            not_auto_since_s: None,
            seen_auto: false,
            takeoff_done: false,
            land_started: false,
            reached: Vec::new(),
            last_send_s: None,
            last_refusal: None,
            last_text: None,
            abort: None,
            outcome: None,
            started: false,
            faults: Faults::default(),
        })
    }

    /// The vehicle's last reported mode.
    pub fn mode(&self) -> Option<VehicleMode> {
        self.mode
    }

    fn enter(&mut self, to: FlightState, now_s: f64, out: &mut Output) {
        out.notes.push(Note::State {
            from: self.state,
            to,
        });
        self.state = to;
        self.state_since_s = now_s;
        self.last_send_s = None;
        self.last_refusal = None;
    }

    fn finish(&mut self, outcome: Outcome, out: &mut Output) {
        self.outcome = Some(outcome);
        out.notes.push(Note::Finished);
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

    fn time_out(&mut self, after_s: f64, awaited: &str, out: &mut Output) {
        let detail = match &self.last_refusal {
            Some(r) => format!("{awaited}; last answer: {r}"),
            None => awaited.to_string(),
        };
        let state = self.state;
        if matches!(state, FlightState::Takeoff | FlightState::Waypoint) {
            out.commands.push(Command::Land);
        }
        self.finish(
            Outcome::Failed(Failure::Timeout {
                state,
                after_s,
                detail,
            }),
            out,
        );
    }

    /// Every waypoint up to item `seq` (inclusive when `inclusive`) counts as reached.
    fn passed(&mut self, now_s: f64, seq: u16, inclusive: bool, out: &mut Output) {
        if seq > self.layout.takeoff_seq || (inclusive && seq == self.layout.takeoff_seq) {
            self.takeoff_done = true;
        }
        if seq >= self.layout.land_seq {
            self.land_started = true;
        }
        let end = if inclusive {
            seq.saturating_add(1)
        } else {
            seq
        };
        let upto =
            usize::from(end.saturating_sub(self.layout.first_waypoint_seq)).min(self.targets.len());
        if end <= self.layout.first_waypoint_seq {
            return;
        }
        while self.reached.len() < upto {
            let index = self.reached.len();
            let w = self.targets[index];
            let (h, v, yaw) = match &self.last {
                Some(t) => (
                    (w.north_m - t.north_m).hypot(w.east_m - t.east_m),
                    (w.alt_m - t.alt_m()).abs(),
                    wrap_angle_rad(w.heading_rad - t.yaw_rad).abs(),
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
                true
            }
            FlightState::Landing | FlightState::Disarming => {
                self.abort = Some(reason);
                false
            }
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

    fn guided(&self, t: &Telemetry) -> bool {
        match self.mode {
            Some(m) => m == VehicleMode::Guided,
            None => t.guided,
        }
    }

    fn step(&mut self, now_s: f64, out: &mut Output) {
        let Some(t) = self.last else {
            return;
        };
        let c = self.config;
        let in_state_s = now_s - self.state_since_s;
        let n = self.targets.len();
        match self.state {
            FlightState::Manual => {
                if !self.started {
                    self.started = true;
                    self.enter(FlightState::Arming, now_s, out);
                    self.step(now_s, out);
                }
            }
            FlightState::Arming => {
                let guided = self.guided(&t);
                if t.armed && (guided || self.mode == Some(VehicleMode::Auto)) {
                    self.enter(FlightState::Takeoff, now_s, out);
                    out.commands.push(Command::StartMission);
                    self.last_send_s = Some(now_s);
                } else if in_state_s > c.arming_timeout_s {
                    let awaited = if guided {
                        "the vehicle did not arm"
                    } else {
                        "the vehicle did not enter guided mode"
                    };
                    self.time_out(c.arming_timeout_s, awaited, out);
                } else if self.due(now_s, c.retry_s) {
                    out.commands.push(if guided {
                        Command::Arm
                    } else {
                        Command::TakeControl
                    });
                }
            }
            FlightState::Takeoff => {
                if self.mode == Some(VehicleMode::Auto) {
                    self.seen_auto = true;
                }
                let alt_m = self.targets[0].alt_m;
                if self.takeoff_done || t.alt_m() >= c.takeoff_fraction * alt_m {
                    self.takeoff_done = true;
                    self.enter(FlightState::Waypoint, now_s, out);
                    self.leg_since_s = now_s;
                    self.step(now_s, out);
                } else if !t.armed {
                    self.finish(
                        Outcome::Failed(Failure::DisarmedInFlight { state: self.state }),
                        out,
                    );
                } else if let Some(mode) = self.mode
                    && self.seen_auto
                    && mode != VehicleMode::Auto
                    && self
                        .not_auto_since_s
                        .is_some_and(|since| now_s - since >= LEFT_AUTO_GRACE_S)
                {
                    self.finish(
                        Outcome::Failed(Failure::LeftMission {
                            state: self.state,
                            mode,
                        }),
                        out,
                    );
                } else if in_state_s > c.takeoff_timeout_s {
                    let awaited = if self.seen_auto {
                        format!(
                            "the vehicle reached {:.1} m of the {:.1} m needed",
                            t.alt_m(),
                            c.takeoff_fraction * alt_m
                        )
                    } else {
                        "the vehicle did not enter AUTO".to_string()
                    };
                    self.time_out(c.takeoff_timeout_s, &awaited, out);
                } else if !self.seen_auto && self.due(now_s, c.retry_s) {
                    out.commands.push(Command::StartMission);
                }
            }
            FlightState::Waypoint => {
                let all = self.reached.len() >= n;
                let landing = self.land_started
                    || self.mode == Some(VehicleMode::Land)
                    || !t.armed
                    || self.on_ground(&t);
                if all && landing {
                    self.enter(FlightState::Landing, now_s, out);
                    self.step(now_s, out);
                    return;
                }
                if !t.armed {
                    self.finish(
                        Outcome::Failed(Failure::DisarmedInFlight { state: self.state }),
                        out,
                    );
                    return;
                }
                if let Some(mode) = self.mode
                    && mode != VehicleMode::Auto
                    && self
                        .not_auto_since_s
                        .is_some_and(|since| now_s - since >= LEFT_AUTO_GRACE_S)
                {
                    self.finish(
                        Outcome::Failed(Failure::LeftMission {
                            state: self.state,
                            mode,
                        }),
                        out,
                    );
                    return;
                }
                let i = self.reached.len().min(n - 1);
                let leg_m = if i == 0 {
                    0.0
                } else {
                    let (a, b) = (self.targets[i - 1], self.targets[i]);
                    (b.north_m - a.north_m).hypot(b.east_m - a.east_m)
                };
                let budget_s = c.leg_timeout_base_s + c.leg_timeout_per_m_s * leg_m;
                if now_s - self.leg_since_s > budget_s {
                    let awaited = if all {
                        "the vehicle did not start the land item".to_string()
                    } else {
                        let w = self.targets[i];
                        format!(
                            "waypoint {} of {n} not reported reached: {:.1} m away horizontally, {:.1} m vertically",
                            i + 1,
                            (w.north_m - t.north_m).hypot(w.east_m - t.east_m),
                            (w.alt_m - t.alt_m()).abs(),
                        )
                    };
                    self.time_out(budget_s, &awaited, out);
                }
            }
            FlightState::Landing => {
                let budget_s = self.faults.landing_budget_s(&c);
                if self.on_ground(&t) || !t.armed {
                    self.enter(FlightState::Disarming, now_s, out);
                    self.step(now_s, out);
                } else if in_state_s > budget_s {
                    let awaited = format!("still {:.1} m above home", t.alt_m());
                    self.time_out(budget_s, &awaited, out);
                }
            }
            FlightState::Disarming => {
                if !t.armed {
                    self.enter(FlightState::Manual, now_s, out);
                    let outcome = match self.abort.take() {
                        Some(reason) => Outcome::Failed(Failure::Aborted { reason }),
                        None if self.reached.len() == n => Outcome::Completed,
                        None => Outcome::Failed(Failure::Aborted {
                            reason: "landed before the last waypoint".into(),
                        }),
                    };
                    self.finish(outcome, out);
                } else if in_state_s > c.disarming_timeout_s {
                    self.time_out(c.disarming_timeout_s, "the vehicle did not disarm", out);
                } else if in_state_s >= AUTO_DISARM_WAIT_S && self.due(now_s, c.retry_s) {
                    out.commands.push(Command::Disarm);
                }
            }
        }
    }
}

impl FlightExecutor for AutoExecutor {
    fn handle(&mut self, now_s: f64, event: Event) -> Output {
        let mut out = Output::default();
        if self.outcome.is_some() {
            return out;
        }
        self.faults.observe(&event);
        match event {
            Event::Telemetry(t) => self.last = Some(t),
            Event::Mode(m) => {
                if m == VehicleMode::Auto {
                    self.not_auto_since_s = None;
                } else if self.not_auto_since_s.is_none() {
                    self.not_auto_since_s = Some(now_s);
                }
                self.mode = Some(m);
            }
            Event::MissionItemReached(seq) => {
                if self.state != FlightState::Manual && self.state != FlightState::Arming {
                    self.passed(now_s, seq, true, &mut out);
                }
            }
            Event::MissionCurrent(seq) => {
                // Only once the mission runs: before, it is the previous flight's or 0.
                if self.seen_auto {
                    self.passed(now_s, seq, false, &mut out);
                }
            }
            Event::Ack { command, accepted } => {
                if let Err(answer) = accepted {
                    let reason = match &self.last_text {
                        Some(text) => format!("{answer}: {text}"),
                        None => answer,
                    };
                    self.last_refusal = Some(format!("{command} refused ({reason})"));
                    out.notes.push(Note::Refused { command, reason });
                } else if command == CommandKind::StartMission {
                    self.seen_auto |= self.mode == Some(VehicleMode::Auto);
                }
            }
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
            Event::Tick => {}
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
                }
                None => {}
            }
            return out;
        }
        self.step(now_s, &mut out);
        out
    }

    fn state(&self) -> FlightState {
        self.state
    }

    fn outcome(&self) -> Option<&Outcome> {
        self.outcome.as_ref()
    }

    fn last_telemetry(&self) -> Option<&Telemetry> {
        self.last.as_ref()
    }

    fn current_target(&self) -> Option<(usize, Target)> {
        match self.state {
            FlightState::Waypoint => {
                let i = self.reached.len().min(self.targets.len() - 1);
                Some((i, self.targets[i]))
            }
            _ => None,
        }
    }

    fn reached(&self) -> &[Reached] {
        &self.reached
    }

    fn targets(&self) -> &[Target] {
        &self.targets
    }

    fn distance_left_m(&self) -> f64 {
        let route_from = |i: usize| -> f64 {
            self.targets[i..]
                .windows(2)
                .map(|w| (w[1].north_m - w[0].north_m).hypot(w[1].east_m - w[0].east_m))
                .sum()
        };
        let Some(t) = &self.last else {
            return route_from(0);
        };
        let i = match self.state {
            FlightState::Manual if self.outcome.is_none() => 0,
            FlightState::Manual | FlightState::Landing | FlightState::Disarming => return 0.0,
            FlightState::Arming | FlightState::Takeoff => 0,
            FlightState::Waypoint => self.reached.len().min(self.targets.len() - 1),
        };
        let w = self.targets[i];
        (w.north_m - t.north_m).hypot(w.east_m - t.east_m) + route_from(i)
    }
}

#[cfg(test)]
mod tests;
