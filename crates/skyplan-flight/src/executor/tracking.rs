//! The reference-tracking strategy: fly a time-parametrised [`Reference`] instead of
//! waypoint by waypoint.
//!
//! TAKEOFF as in GUIDED, to the altitude of the reference's start; then, in WAYPOINT:
//! 1. *approach*: the start point streamed as a position + yaw target until the vehicle is within
//!    [`START_TOLERANCE_M`] of it, heading within tolerance and slower than
//!    [`START_SPEED_M_S`] (at rest: the reference starts at rest); that reaches target 0 and
//!    starts the reference clock;
//! 2. *streaming*: [`Command::Track`] of `setpoint(t)` every [`REFERENCE_PERIOD_S`] until
//!    t ≥ the duration; each telemetry sample is compared with the setpoint at its own reference
//!    time (the vehicle's time stamp, [`Telemetry::sample_time_s`], when the link has it). The
//!    reference clock `t` runs on the vehicle's clock when the link has its time stamps: the
//!    latest stamp, plus the executor time since it arrived up to [`CLOCK_LEAD_GAPS`] usual gaps
//!    between samples (at least [`CLOCK_LEAD_MIN_S`]), never backwards. A vehicle that stalls
//!    (a simulator behind the wall clock) stalls its reference with it: seen against ArduCopter
//!    SITL, a 2.4 s stall on the ground station's clock made the setpoint jump 94 m ahead;
//! 3. *holding*: the last point streamed as a position target until the vehicle is within the
//!    deadband (target 1 reached: the arrival), then the landing as in GUIDED.
//!
//! With a [`Rereference`] (`fly --trajectory` with a replanner), a route watcher sees the path
//! ahead (the reference sampled every [`AHEAD_STEP_S`]) and may replace the route while
//! streaming: the new reference starts [`SPLICE_LEAD_S`] ahead on the current one's clock, in
//! its state there (position, velocity, acceleration, heading), and the two are flown as one
//! ([`Spliced`]): the vehicle switches without stopping. If no reference can be made from
//! there, the replacement is refused and the route watcher's caller holds the vehicle.

use super::core::{Core, Executor, Strategy};
use super::guided::{GuidedTargets, goto, takeoff_to_first};
use super::interface::{Command, Event, Target, Telemetry};
use super::report::{ConfigError, ExecutorConfig, Failure, Output, TrackingReport};
use crate::reference::{Reference, Setpoint, Spliced};
use std::fmt;
use std::sync::Arc;

/// Executor seconds between two setpoints streamed (20 Hz: ≥ 10 Hz even when events come late);
/// a setpoint goes out with the first event at least 90 % of it after the last one.
pub const REFERENCE_PERIOD_S: f64 = 0.05;

/// The reference clock starts once the vehicle is this close to the start, metres (and within
/// the deadband vertically)…
pub const START_TOLERANCE_M: f64 = 0.2;

/// …and slower than this, m/s: at rest, as the reference starts.
pub const START_SPEED_M_S: f64 = 0.1;

/// The reference clock runs at most this many of the usual gaps between the vehicle's time
/// stamps ahead of the latest one…
pub const CLOCK_LEAD_GAPS: f64 = 3.0;

/// …and at most this much, seconds, when that is longer.
pub const CLOCK_LEAD_MIN_S: f64 = 0.5;

/// How far ahead on the reference's clock a replaced route takes over, seconds of vehicle
/// time: the time a new trajectory may take to make (tens of milliseconds of wall time on the
/// city; a simulator sped up 20× turns 50 ms into 1 s), so the vehicle still follows the old
/// one meanwhile. At 10 m/s it flies 10 m on the old path first, well within a 30 m sensor.
pub const SPLICE_LEAD_S: f64 = 1.0;

/// Spacing of the path ahead a route watcher sees, reference seconds.
pub const AHEAD_STEP_S: f64 = 0.5;

/// Makes the reference for a new route from a state of the one being flown (its setpoint at the
/// switch, north/east/down) through `targets` (the new route, its first point where the vehicle
/// was when it was planned); or why not, in a sentence.
pub type Rereference =
    Arc<dyn Fn(&Setpoint, &[Target]) -> Result<Arc<dyn Reference>, String> + Send + Sync>;

/// Where the reference flight stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Approach,
    Streaming,
    Holding,
    /// A replanned route is flown by waypoints (no trajectory from the moving vehicle).
    Waypoints,
}

/// Reference tracking: see the module documentation.
#[derive(Clone)]
pub struct ReferenceTracking {
    reference: Arc<dyn Reference>,
    phase: Phase,
    duration_s: f64,
    clock_start_s: Option<f64>,
    arrival_s: Option<f64>,
    max_error_m: f64,
    max_path_error_m: f64,
    samples: usize,
    last_sample_s: Option<f64>,
    setpoints_sent: usize,
    /// Makes a new reference for a replaced route (none: the route is never replaced).
    rereference: Option<Rereference>,
    /// The path ahead, sampled every [`AHEAD_STEP_S`] of reference time from `ahead_from_s`.
    ahead: Vec<Target>,
    ahead_from_s: f64,
    /// Where `ahead` starts now (advanced as the clock runs).
    ahead_index: usize,
    /// Reference times at which a replaced route took over.
    switches_s: Vec<f64>,
    /// The reference time at the last step while streaming.
    t_ref_s: f64,
    /// The longest wall time a new reference took to make, milliseconds.
    slowest_switch_ms: f64,
    /// Reference time at which the flight went on by waypoints.
    by_waypoints_from_s: Option<f64>,
    /// A note to tell at the next step (why the flight went on by waypoints).
    pending_note: Option<String>,
    /// The vehicle's latest time stamp and the executor time it arrived at.
    vehicle_clock: Option<(f64, f64)>,
    /// The usual executor time between two of the vehicle's time stamps (a running mean, each
    /// gap counted at most twice the mean so that a stall does not stretch it).
    sample_gap_s: f64,
    /// The clock's latest reading: it never runs backwards.
    clock_s: f64,
}

impl fmt::Debug for ReferenceTracking {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ReferenceTracking")
            .field("phase", &self.phase)
            .field("duration_s", &self.duration_s)
            .field("clock_start_s", &self.clock_start_s)
            .field("arrival_s", &self.arrival_s)
            .field("max_error_m", &self.max_error_m)
            .field("max_path_error_m", &self.max_path_error_m)
            .finish_non_exhaustive()
    }
}

/// The executor that flies a [`Reference`].
pub type ReferenceExecutor = Executor<ReferenceTracking>;

impl Executor<ReferenceTracking> {
    /// An executor for `reference` (finite duration ≥ 0, its start above the ground). Its two
    /// targets are the reference's start and end points (headings: the setpoints' yaw).
    ///
    /// ```
    /// use std::sync::Arc;
    /// use skyplan_flight::executor::{ExecutorConfig, ReferenceExecutor};
    /// use skyplan_flight::reference::MinJerkLine;
    /// let r = MinJerkLine::new(vec![[0.0, 0.0, -5.0], [30.0, 0.0, -5.0]], vec![10.0])?;
    /// let ex = ReferenceExecutor::new(Arc::new(r), ExecutorConfig::default())?;
    /// assert_eq!(ex.targets().len(), 2);
    /// assert_eq!(ex.tracking().unwrap().duration_s, 10.0);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new(reference: Arc<dyn Reference>, config: ExecutorConfig) -> Result<Self, ConfigError> {
        let duration_s = reference.duration_s();
        if !duration_s.is_finite() || duration_s < 0.0 {
            return Err(ConfigError(format!(
                "the reference's duration {duration_s} s is not a finite time"
            )));
        }
        let (start, end) = (reference.setpoint(0.0), reference.setpoint(duration_s));
        if !start.is_finite() || !end.is_finite() {
            return Err(ConfigError(
                "the reference's start or end is not finite".into(),
            ));
        }
        let target = |s: crate::reference::Setpoint| Target {
            north_m: s.point_ned[0],
            east_m: s.point_ned[1],
            alt_m: -s.point_ned[2],
            heading_rad: s.yaw_rad,
        };
        let strategy = ReferenceTracking::approaching(reference);
        Self::with_strategy(&[target(start), target(end)], config, strategy)
    }

    /// As [`Executor::new`], and a route watcher may replace the route in flight:
    /// `rereference` makes the new reference, flown from [`SPLICE_LEAD_S`] ahead without
    /// stopping (see the module documentation).
    pub fn replanning(
        reference: Arc<dyn Reference>,
        config: ExecutorConfig,
        rereference: Rereference,
    ) -> Result<Self, ConfigError> {
        let mut ex = Self::new(reference, config)?;
        ex.strategy_mut().rereference = Some(rereference);
        Ok(ex)
    }

    /// How the reference is being followed.
    pub fn tracking(&self) -> Option<TrackingReport> {
        super::FlightExecutor::tracking(self)
    }
}

/// How far in reference time, either side of a sample's own, the path error looks for the
/// closest setpoint, seconds: a vehicle early or late by up to this much is measured by how
/// far it is from the path, not from where it should be at that instant.
pub const PATH_WINDOW_S: f64 = 3.0;

impl ReferenceTracking {
    /// Flying to the start of `reference`, its clock not started, nothing measured yet.
    fn approaching(reference: Arc<dyn Reference>) -> Self {
        Self {
            duration_s: reference.duration_s(),
            reference,
            phase: Phase::Approach,
            clock_start_s: None,
            arrival_s: None,
            max_error_m: 0.0,
            max_path_error_m: 0.0,
            samples: 0,
            last_sample_s: None,
            setpoints_sent: 0,
            rereference: None,
            ahead: Vec::new(),
            ahead_from_s: 0.0,
            ahead_index: 0,
            switches_s: Vec::new(),
            t_ref_s: 0.0,
            slowest_switch_ms: 0.0,
            by_waypoints_from_s: None,
            pending_note: None,
            vehicle_clock: None,
            sample_gap_s: 0.1,
            clock_s: f64::NEG_INFINITY,
        }
    }

    /// Takes a vehicle time stamp `sample_s` that arrived at executor time `now_s`.
    fn note_vehicle_time(&mut self, sample_s: f64, now_s: f64) {
        if let Some((last_s, at_s)) = self.vehicle_clock {
            if sample_s <= last_s {
                return;
            }
            let gap_s = now_s - at_s;
            if gap_s > 0.0 {
                self.sample_gap_s =
                    0.9 * self.sample_gap_s + 0.1 * gap_s.min(2.0 * self.sample_gap_s);
            }
        }
        self.vehicle_clock = Some((sample_s, now_s));
    }

    /// The clock the reference runs on at executor time `now_s`: the vehicle's (see the module
    /// documentation), or the executor's for a link without time stamps.
    fn clock(&mut self, now_s: f64) -> f64 {
        let reading = match self.vehicle_clock {
            None => now_s,
            Some((sample_s, at_s)) => {
                let lead_s = (CLOCK_LEAD_GAPS * self.sample_gap_s).max(CLOCK_LEAD_MIN_S);
                sample_s + (now_s - at_s).clamp(0.0, lead_s)
            }
        };
        self.clock_s = self.clock_s.max(reading);
        self.clock_s
    }

    /// The path ahead from reference time `from_s`: a target every [`AHEAD_STEP_S`] to the end.
    fn sample_ahead(&mut self, from_s: f64) {
        let n = ((self.duration_s - from_s).max(0.0) / AHEAD_STEP_S).ceil() as usize;
        self.ahead = (0..=n)
            .map(|k| {
                let s = self
                    .reference
                    .setpoint((from_s + k as f64 * AHEAD_STEP_S).min(self.duration_s));
                Target {
                    north_m: s.point_ned[0],
                    east_m: s.point_ned[1],
                    alt_m: -s.point_ned[2],
                    heading_rad: s.yaw_rad,
                }
            })
            .collect();
        self.ahead_from_s = from_s;
        self.ahead_index = 0;
    }

    /// Moves the start of the path ahead to the sample after reference time `t_ref`.
    fn advance_ahead(&mut self, t_ref: f64) {
        self.t_ref_s = t_ref;
        let k = ((t_ref - self.ahead_from_s) / AHEAD_STEP_S).floor() + 1.0;
        if k.is_finite() && k > 0.0 {
            self.ahead_index = (k as usize).min(self.ahead.len().saturating_sub(1));
        }
    }

    /// Reference times at which a replaced route took over, in order.
    pub fn switches_s(&self) -> &[f64] {
        &self.switches_s
    }

    /// The distance from `point_ned` to the reference's path within [`PATH_WINDOW_S`] of
    /// `t_ref`: the closest setpoint on a 0.01 s grid, less the most the path can move between
    /// two grid points (half a step at the fastest setpoint seen), so never more than the true
    /// distance; at most `at_instant_m`.
    fn path_error_m(&self, point_ned: [f64; 3], t_ref: f64, at_instant_m: f64) -> f64 {
        const STEP_S: f64 = 0.01;
        let from = (t_ref - PATH_WINDOW_S).max(0.0);
        let to = (t_ref + PATH_WINDOW_S).min(self.duration_s);
        let steps = ((to - from) / STEP_S).ceil() as usize;
        let (mut best, mut fastest) = (at_instant_m, 0.0_f64);
        for k in 0..=steps {
            let s = self.reference.setpoint((from + k as f64 * STEP_S).min(to));
            best = best.min(s.distance_m(point_ned));
            let v = s.vel_ned_m_s;
            fastest = fastest.max((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt());
        }
        (best - 0.5 * STEP_S * fastest).max(0.0)
    }

    /// Compares a new telemetry sample with the reference at its reference time.
    fn measure(&mut self, t: &Telemetry, now_s: f64) {
        let Some(start_s) = self.clock_start_s else {
            return;
        };
        if self.phase == Phase::Waypoints {
            return;
        }
        let sample_s = t.sample_time_s.unwrap_or(now_s);
        if self.last_sample_s == Some(sample_s) {
            return;
        }
        self.last_sample_s = Some(sample_s);
        let t_ref = sample_s - start_s;
        if (0.0..=self.duration_s).contains(&t_ref) {
            let error_m = self
                .reference
                .setpoint(t_ref)
                .distance_m([t.north_m, t.east_m, t.down_m]);
            self.max_error_m = self.max_error_m.max(error_m);
            let path_m = self.path_error_m([t.north_m, t.east_m, t.down_m], t_ref, error_m);
            self.max_path_error_m = self.max_path_error_m.max(path_m);
            self.samples += 1;
        }
    }
}

impl Strategy for ReferenceTracking {
    const DISARM_WAIT_S: f64 = 0.0;
    const COMMANDS_LANDING: bool = true;
    const REPLANS: bool = false;

    fn in_control(&self, _core: &Core, t: &Telemetry) -> bool {
        t.guided
    }

    fn ready_to_fly(&self, _core: &Core, t: &Telemetry) -> bool {
        t.guided && t.armed
    }

    fn start(&mut self, _core: &mut Core, _now_s: f64, _out: &mut Output) -> bool {
        true
    }

    fn observe(&mut self, _core: &mut Core, now_s: f64, event: &Event, out: &mut Output) {
        if let Some(reason) = self.pending_note.take() {
            out.notes.push(super::Note::ByWaypoints { reason });
        }
        if let Event::Telemetry(t) = event {
            if let Some(sample_s) = t.sample_time_s {
                self.note_vehicle_time(sample_s, now_s);
            }
            self.measure(t, now_s);
        }
    }

    fn takeoff(&mut self, core: &mut Core, now_s: f64, t: &Telemetry, out: &mut Output) -> bool {
        let entered = takeoff_to_first(core, now_s, t, out);
        if entered {
            core.first_leg_m = core.targets[0].horizontal_error_m(t);
        }
        entered
    }

    fn waypoint(&mut self, core: &mut Core, now_s: f64, t: &Telemetry, out: &mut Output) -> bool {
        if self.phase == Phase::Waypoints {
            return GuidedTargets.waypoint(core, now_s, t, out);
        }
        let c = core.config;
        if !t.armed {
            core.fail(Failure::DisarmedInFlight { state: core.state }, out);
            return false;
        }
        if !t.guided {
            core.fail(Failure::ControlLost { state: core.state }, out);
            return false;
        }
        let sample_s = t.sample_time_s.unwrap_or(now_s);
        if self.phase == Phase::Approach {
            let start = core.targets[0];
            if start.horizontal_error_m(t) <= START_TOLERANCE_M
                && start.vertical_error_m(t) <= c.vertical_deadband_m.min(START_TOLERANCE_M)
                && start.heading_error_rad(t) <= c.heading_tolerance_rad
                && t.speed_m_s() < START_SPEED_M_S
            {
                core.reach(now_s, 0, out);
                self.clock_start_s = Some(self.clock(now_s));
                self.phase = Phase::Streaming;
                core.last_send_s = None;
                if self.rereference.is_some() {
                    self.sample_ahead(0.0);
                }
            } else {
                let budget_s = core.leg_budget_s(0);
                if now_s - core.leg_since_s > budget_s {
                    let awaited = format!(
                        "the reference's start not reached at rest: {:.1} m away horizontally, {:.1} m vertically, heading off by {:.1}°, {:.1} m/s",
                        start.horizontal_error_m(t),
                        start.vertical_error_m(t),
                        start.heading_error_rad(t).to_degrees(),
                        t.speed_m_s()
                    );
                    core.time_out(now_s, budget_s, &awaited, out);
                } else if core.due(now_s, c.target_period_s) {
                    out.commands.push(goto(&start));
                }
                return false;
            }
        }
        let start_s = self.clock_start_s.unwrap_or(now_s);
        if self.phase == Phase::Streaming {
            let t_ref = self.clock(now_s) - start_s;
            self.advance_ahead(t_ref);
            if t_ref < self.duration_s {
                if core.due(now_s, 0.9 * REFERENCE_PERIOD_S) {
                    out.commands.push(Command::Track {
                        setpoint: self.reference.setpoint(t_ref),
                        // The instant it holds at, on the clock it runs on.
                        time_s: start_s + t_ref,
                    });
                    self.setpoints_sent += 1;
                }
                return false;
            }
            self.phase = Phase::Holding;
            core.leg_since_s = now_s;
            core.last_send_s = None;
        }
        // Holding at the last point.
        let end = core.targets[1];
        if self.arrival_s.is_none()
            && end.horizontal_error_m(t) <= c.deadband_m
            && end.vertical_error_m(t) <= c.vertical_deadband_m
        {
            self.arrival_s = Some(sample_s.max(start_s));
            core.reach(now_s, 1, out);
        }
        if self.arrival_s.is_some() && t.speed_m_s() < c.land_speed_m_s {
            core.land_after_mission(now_s, Self::COMMANDS_LANDING, out);
            return true;
        }
        if now_s - core.leg_since_s > c.leg_timeout_base_s {
            let awaited = format!(
                "the reference's end not reached and stopped at: {:.1} m away horizontally, {:.1} m vertically, {:.1} m/s",
                end.horizontal_error_m(t),
                end.vertical_error_m(t),
                t.speed_m_s()
            );
            core.time_out(now_s, c.leg_timeout_base_s, &awaited, out);
        } else if core.due(now_s, c.target_period_s) {
            out.commands.push(goto(&end));
        }
        false
    }

    fn replaces(&self) -> bool {
        self.rereference.is_some()
    }

    /// While streaming, and not within [`SPLICE_LEAD_S`] of the end.
    fn replaces_now(&self) -> bool {
        self.rereference.is_some()
            && (self.phase == Phase::Waypoints
                || (self.phase == Phase::Streaming
                    && self.t_ref_s + SPLICE_LEAD_S < self.duration_s))
    }

    fn route_ahead(&self) -> Option<&[Target]> {
        (self.phase == Phase::Streaming && self.rereference.is_some())
            .then(|| &self.ahead[self.ahead_index.min(self.ahead.len())..])
    }

    /// The new reference starts [`SPLICE_LEAD_S`] ahead on the clock, in the current one's
    /// state there; refused outside streaming, too near the end, or when no reference can be
    /// made from that state (the caller holds the vehicle then).
    fn replace(
        &mut self,
        core: &mut Core,
        now_s: f64,
        targets: &[Target],
    ) -> Result<(), ConfigError> {
        let (Some(make), Some(start_s)) = (self.rereference.clone(), self.clock_start_s) else {
            return Err(ConfigError(
                "this reference flight cannot change its route in flight".into(),
            ));
        };
        if self.phase == Phase::Waypoints {
            return core.start_route(now_s, targets);
        }
        if self.phase != Phase::Streaming {
            return Err(ConfigError(
                "a reference flight changes its route only while following its reference".into(),
            ));
        }
        let now_ref_s = self.clock(now_s) - start_s;
        let at_s = now_ref_s + SPLICE_LEAD_S;
        if at_s >= self.duration_s {
            return Err(ConfigError(format!(
                "the reference ends within {SPLICE_LEAD_S} s: too late to switch to a new route"
            )));
        }
        let Some(goal) = targets.last().copied() else {
            return Err(ConfigError("the new route has no waypoint".into()));
        };
        if targets
            .iter()
            .any(|t| !t.is_finite() || t.alt_m <= core.config.landed_alt_m)
        {
            return Err(ConfigError(
                "the new route has a waypoint that is not finite or not above the ground".into(),
            ));
        }
        let state = self.reference.setpoint(at_s);
        let t0 = std::time::Instant::now();
        let made = make(&state, targets);
        self.slowest_switch_ms = self
            .slowest_switch_ms
            .max(t0.elapsed().as_secs_f64() * 1000.0);
        let next = match made {
            Ok(next) => next,
            // Flown by waypoints instead: the autopilot's own limits shape the turn, as in a
            // flight without a trajectory (seen against ArduCopter SITL: a hidden box sensed
            // too close to turn within the limits; holding and landing stranded the flight).
            Err(e) => {
                core.start_route(now_s, targets)?;
                self.phase = Phase::Waypoints;
                self.by_waypoints_from_s = Some(now_ref_s);
                self.ahead.clear();
                self.pending_note = Some(format!(
                    "no trajectory for the new route from the moving vehicle ({e})"
                ));
                return Ok(());
            }
        };
        let spliced = Spliced::new(Arc::clone(&self.reference), at_s, next);
        self.duration_s = spliced.duration_s();
        self.reference = Arc::new(spliced);
        self.switches_s.push(at_s);
        let end = self.reference.setpoint(self.duration_s);
        core.targets[1] = Target {
            north_m: end.point_ned[0],
            east_m: end.point_ned[1],
            alt_m: -end.point_ned[2],
            heading_rad: goal.heading_rad,
        };
        self.sample_ahead(now_ref_s);
        Ok(())
    }

    fn tracking(&self) -> Option<TrackingReport> {
        Some(TrackingReport {
            duration_s: self.duration_s,
            started_s: self.clock_start_s,
            flown_s: (self.arrival_s.zip(self.clock_start_s)).map(|(a, s)| a - s),
            max_tracking_error_m: self.max_error_m,
            max_path_error_m: self.max_path_error_m,
            samples: self.samples,
            setpoints_sent: self.setpoints_sent,
            switches: self.switches_s.len(),
            slowest_switch_ms: self.slowest_switch_ms,
            by_waypoints_from_s: self.by_waypoints_from_s,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::executor::{FlightExecutor, FlightState, Note, Outcome};
    use crate::reference::MinJerkLine;
    use crate::sim::{SimConfig, SimVehicle};
    use crate::testkit::{apply, telemetry};

    /// A replan at `t` from `position_ned`, as a route watcher tells it.
    fn replan_event(t: f64, position_ned: [f64; 3]) -> crate::sensing::ReplanEvent {
        crate::sensing::ReplanEvent {
            time_s: t,
            position_ned,
            reason: "test".into(),
            planner: "test".into(),
            latency_ms: 0.0,
            cpu_ms: None,
            expansions: 0,
            route_length_m: 0.0,
            learned_cells: 0,
        }
    }

    /// Flies `ex` against `v` in steps of 0.05 s until the flight ends (or 400 s), handing each
    /// step's outputs (their commands already applied to `v`) to `each` with the time.
    fn fly_steps(
        ex: &mut ReferenceExecutor,
        v: &mut SimVehicle,
        mut each: impl FnMut(f64, &mut ReferenceExecutor, &SimVehicle, &[Output]),
    ) {
        let (mut t, mut pending) = (0.0, Vec::new());
        while ex.outcome().is_none() && t < 400.0 {
            for _ in 0..5 {
                v.step(0.01);
            }
            t += 0.05;
            let mut events = std::mem::take(&mut pending);
            events.push(Event::Telemetry(telemetry(v)));
            let outs: Vec<Output> = events.into_iter().map(|e| ex.handle(t, e)).collect();
            for c in outs.iter().flat_map(|o| &o.commands) {
                pending.extend(apply(v, *c));
            }
            each(t, ex, v, &outs);
        }
    }

    /// Three legs, up to 8 m/s, starting 10 m east of home (the vehicle flies there first).
    fn three_legs() -> MinJerkLine {
        let points = vec![
            [0.0, 10.0, -12.0],
            [90.0, 10.0, -12.0],
            [90.0, 80.0, -15.0],
            [20.0, 80.0, -15.0],
        ];
        MinJerkLine::at_peak_speed(points, 8.0).unwrap()
    }

    #[test]
    fn flies_a_reference_against_the_simulated_vehicle_and_tracks_it_closely() {
        let r = Arc::new(three_legs());
        let mut ex = ReferenceExecutor::new(r.clone(), ExecutorConfig::default()).unwrap();
        let mut v = SimVehicle::new(SimConfig::default());
        let mut states = vec![ex.state()];
        let mut worst: f64 = 0.0;
        fly_steps(&mut ex, &mut v, |t, ex, v, outs| {
            for out in outs {
                for n in &out.notes {
                    if let Note::State { to, .. } = n {
                        states.push(*to);
                    }
                }
            }
            // Independent check: the vehicle against the reference at the same time.
            if let Some(start) = ex.tracking().unwrap().started_s {
                let tr = t - start;
                if (0.0..=r.duration_s()).contains(&tr) {
                    worst = worst.max(r.setpoint(tr).distance_m(v.state().position_ned_m));
                }
            }
        });
        assert_eq!(
            ex.outcome(),
            Some(&Outcome::Completed),
            "{:?}",
            ex.outcome()
        );
        use FlightState::*;
        assert_eq!(
            states,
            vec![
                Manual, Arming, Takeoff, Waypoint, Landing, Disarming, Manual
            ]
        );
        let report = ex.tracking().unwrap();
        assert!(report.max_tracking_error_m <= 0.1, "{report:?}");
        // The executor's own measure never exceeds the independent one (which also counts the
        // sample at the clock's start, within START_TOLERANCE_M).
        assert!(worst <= 0.2, "{worst}");
        assert!(
            report.max_tracking_error_m <= worst + 1e-9,
            "{report:?} vs {worst}"
        );
        assert!(
            report.samples as f64 > r.duration_s() / 0.05 - 2.0,
            "{report:?}"
        );
        let ratio = report.time_ratio().unwrap();
        assert!((1.0..1.05).contains(&ratio), "{report:?}");
        let s = v.state();
        assert!(s.on_ground && !s.armed);
        assert!(
            (s.position_ned_m[0] - 20.0).hypot(s.position_ned_m[1] - 80.0) < 1.0,
            "{s:?}"
        );
    }

    /// A vehicle that stalls (a simulator behind the ground station's clock: no messages for
    /// 12 s of executor time, then its own clock runs on from where it stopped) stalls the
    /// reference with it: no setpoint leaps ahead, and the flight ends as planned.
    #[test]
    fn a_stalled_vehicle_stalls_its_reference() {
        let r = Arc::new(three_legs());
        let mut ex = ReferenceExecutor::new(r.clone(), ExecutorConfig::default()).unwrap();
        let mut v = SimVehicle::new(SimConfig::default());
        let (mut t, mut pending) = (0.0, Vec::new());
        let mut stalled = false;
        let (mut farthest_m, mut after_stall) = (0.0_f64, 0);
        while ex.outcome().is_none() && t < 400.0 {
            t += 0.05;
            let streaming_for = ex.tracking().and_then(|tr| tr.started_s).map(|s| t - s);
            if !stalled && streaming_for.is_some_and(|s| s > 15.0) {
                // Nothing arrives for 12 s; the vehicle stands still in its own time.
                stalled = true;
                t += 12.0;
            }
            for _ in 0..5 {
                v.step(0.01);
            }
            let mut events = std::mem::take(&mut pending);
            events.push(Event::Telemetry(telemetry(&v)));
            for e in events {
                let out = ex.handle(t, e);
                for c in &out.commands {
                    if let Command::Track { setpoint, .. } = c {
                        let d = setpoint.distance_m(v.state().position_ned_m);
                        farthest_m = farthest_m.max(d);
                        after_stall += usize::from(stalled);
                    }
                    pending.extend(apply(&mut v, *c));
                }
            }
        }
        assert!(stalled && after_stall > 100, "{after_stall}");
        assert_eq!(ex.outcome(), Some(&Outcome::Completed));
        // At 8 m/s the executor's clock alone would put the setpoint 96 m ahead.
        assert!(
            farthest_m < 5.0,
            "a setpoint {farthest_m:.1} m from the vehicle"
        );
        let report = ex.tracking().unwrap();
        assert!(report.max_path_error_m < 0.5, "{report:?}");
        assert!(
            (1.0..1.05).contains(&report.time_ratio().unwrap()),
            "{report:?}"
        );
    }

    /// With a re-referencer, a route watcher sees the path ahead and may replace the route
    /// while streaming: the new reference is asked for in the current one's state
    /// [`SPLICE_LEAD_S`] ahead, takes over there, and the setpoints run on without a jump to
    /// the new goal.
    #[test]
    fn a_replaced_route_is_spliced_on_ahead_in_the_references_state() {
        use crate::reference::Setpoint;
        use std::sync::Mutex;
        let r: Arc<dyn Reference> = Arc::new(three_legs());
        let asked: Arc<Mutex<Vec<Setpoint>>> = Arc::default();
        let asked2 = Arc::clone(&asked);
        let make: Rereference = Arc::new(move |s: &Setpoint, targets: &[Target]| {
            asked2.lock().unwrap().push(*s);
            let g = targets.last().unwrap();
            Ok(Arc::new(Hermite {
                from: *s,
                to: [g.north_m, g.east_m, -g.alt_m],
                t_s: 12.0,
            }) as Arc<dyn Reference>)
        });
        let plain = ReferenceExecutor::new(Arc::clone(&r), ExecutorConfig::default()).unwrap();
        assert!(!FlightExecutor::replans(&plain));
        let mut ex =
            ReferenceExecutor::replanning(Arc::clone(&r), ExecutorConfig::default(), make).unwrap();
        assert!(FlightExecutor::replans(&ex));
        let mut v = SimVehicle::new(SimConfig::default());
        let mut tracks: Vec<[f64; 3]> = Vec::new();
        let goal = Target {
            north_m: 40.0,
            east_m: 30.0,
            alt_m: 12.0,
            heading_rad: 0.0,
        };
        let mut switched_at = None;
        fly_steps(&mut ex, &mut v, |t, ex, v, outs| {
            for c in outs.iter().flat_map(|o| &o.commands) {
                if let Command::Track { setpoint, .. } = c {
                    tracks.push(setpoint.point_ned);
                }
            }
            let Some(start) = ex.tracking().unwrap().started_s else {
                assert!(!ex.accepts_route_change());
                return;
            };
            if switched_at.is_none() && t - start > 6.0 {
                assert!(ex.accepts_route_change());
                // The path ahead: the reference every AHEAD_STEP_S after now, to its end.
                let ahead = ex.remaining_targets().to_vec();
                let next =
                    r.setpoint(((t - start) / AHEAD_STEP_S).floor() * AHEAD_STEP_S + AHEAD_STEP_S);
                assert!(
                    (ahead[0].north_m - next.point_ned[0]).abs() < 1e-9,
                    "{ahead:?}"
                );
                let end = ahead.last().unwrap();
                assert!((end.north_m - 20.0).abs() < 1e-9 && (end.east_m - 80.0).abs() < 1e-9);
                let here = Target {
                    north_m: v.state().position_ned_m[0],
                    east_m: v.state().position_ned_m[1],
                    alt_m: 12.0,
                    heading_rad: 0.0,
                };
                let ev = replan_event(t, v.state().position_ned_m);
                let out = ex.replace_route(t, &[here, goal], ev).unwrap();
                assert!(
                    out.notes
                        .iter()
                        .any(|n| matches!(n, Note::Replanned { .. }))
                );
                let at = t - start + SPLICE_LEAD_S;
                // Asked in the reference's state then (to rounding: the clock is the vehicle's).
                let asked_at = *asked.lock().unwrap().last().unwrap();
                assert!(
                    asked_at.distance_m(r.setpoint(at).point_ned) < 1e-9,
                    "{asked_at:?}"
                );
                let dv: f64 = (0..3)
                    .map(|i| (asked_at.vel_ned_m_s[i] - r.setpoint(at).vel_ned_m_s[i]).abs())
                    .sum();
                assert!(dv < 1e-9, "{asked_at:?}");
                let report = ex.tracking().unwrap();
                assert_eq!(report.switches, 1);
                assert!((report.duration_s - (at + 12.0)).abs() < 1e-9, "{report:?}");
                switched_at = Some(at);
            }
        });
        assert!(switched_at.is_some());
        assert_eq!(
            ex.outcome(),
            Some(&Outcome::Completed),
            "{:?}",
            ex.outcome()
        );
        // No jump between two setpoints: at most the fastest speed (8 m/s peak, ≤ 1.875 × the
        // new leg's mean) over a period and a half.
        let jump = tracks
            .windows(2)
            .map(|w| {
                ((w[1][0] - w[0][0]).powi(2)
                    + (w[1][1] - w[0][1]).powi(2)
                    + (w[1][2] - w[0][2]).powi(2))
                .sqrt()
            })
            .fold(0.0, f64::max);
        assert!(jump < 8.0 * 1.5 * REFERENCE_PERIOD_S, "{jump}");
        let s = v.state();
        assert!(
            (s.position_ned_m[0] - 40.0).hypot(s.position_ned_m[1] - 30.0) < 1.0,
            "{s:?}"
        );
        assert!(ex.tracking().unwrap().max_tracking_error_m < 0.3);
    }

    /// A re-referencer that cannot make a trajectory from the moving vehicle: the replaced
    /// route is flown by waypoints instead — told once, the reference no longer measured — and
    /// the flight lands at the new goal, completed.
    #[test]
    fn a_route_with_no_trajectory_from_the_moving_vehicle_is_flown_by_waypoints() {
        let r: Arc<dyn Reference> = Arc::new(three_legs());
        let make: Rereference = Arc::new(|_: &Setpoint, _: &[Target]| Err("too close".into()));
        let mut ex = ReferenceExecutor::replanning(r, ExecutorConfig::default(), make).unwrap();
        let mut v = SimVehicle::new(SimConfig::default());
        let goal = Target {
            north_m: 40.0,
            east_m: 30.0,
            alt_m: 12.0,
            heading_rad: 0.0,
        };
        let (mut replaced, mut told) = (false, 0);
        fly_steps(&mut ex, &mut v, |t, ex, v, outs| {
            told += outs
                .iter()
                .flat_map(|o| &o.notes)
                .filter(
                    |n| matches!(n, Note::ByWaypoints { reason } if reason.contains("too close")),
                )
                .count();
            let Some(start) = ex.tracking().unwrap().started_s else {
                return;
            };
            if !replaced && t - start > 6.0 {
                let p = v.state().position_ned_m;
                let here = Target {
                    north_m: p[0],
                    east_m: p[1],
                    alt_m: 12.0,
                    heading_rad: 0.0,
                };
                let ev = replan_event(t, p);
                ex.replace_route(t, &[here, goal], ev).unwrap();
                replaced = true;
                // Replanning goes on, by waypoints.
                assert!(ex.accepts_route_change());
                assert_eq!(ex.remaining_targets().last(), Some(&goal));
            }
        });
        assert!(replaced);
        assert_eq!(told, 1);
        assert_eq!(
            ex.outcome(),
            Some(&Outcome::Completed),
            "{:?}",
            ex.outcome()
        );
        let report = ex.tracking().unwrap();
        assert!(
            report.by_waypoints_from_s.is_some_and(|s| s > 6.0),
            "{report:?}"
        );
        assert!(report.max_path_error_m < 0.3, "{report:?}");
        let s = v.state();
        assert!(
            (s.position_ned_m[0] - 40.0).hypot(s.position_ned_m[1] - 30.0) < 1.5,
            "{s:?}"
        );
    }

    /// A cubic from a setpoint's position and velocity to rest at `to` over `t_s`.
    struct Hermite {
        from: crate::reference::Setpoint,
        to: [f64; 3],
        t_s: f64,
    }

    impl Reference for Hermite {
        fn duration_s(&self) -> f64 {
            self.t_s
        }

        fn setpoint(&self, t_s: f64) -> crate::reference::Setpoint {
            let (t, u) = (self.t_s, (t_s / self.t_s).clamp(0.0, 1.0));
            let (p0, v0, p1) = (self.from.point_ned, self.from.vel_ned_m_s, self.to);
            // The Hermite basis (p0, T v0, p1; no end velocity) and its derivatives in u.
            let basis = [
                [
                    2.0 * u.powi(3) - 3.0 * u * u + 1.0,
                    u.powi(3) - 2.0 * u * u + u,
                    -2.0 * u.powi(3) + 3.0 * u * u,
                ],
                [
                    6.0 * u * u - 6.0 * u,
                    3.0 * u * u - 4.0 * u + 1.0,
                    -6.0 * u * u + 6.0 * u,
                ],
                [12.0 * u - 6.0, 6.0 * u - 4.0, -12.0 * u + 6.0],
            ];
            let at = |d: usize| {
                let h = basis[d];
                [0, 1, 2]
                    .map(|k| (h[0] * p0[k] + h[1] * t * v0[k] + h[2] * p1[k]) / t.powi(d as i32))
            };
            crate::reference::Setpoint {
                point_ned: at(0),
                vel_ned_m_s: at(1),
                accel_ned_m_s2: at(2),
                yaw_rad: self.from.yaw_rad,
            }
        }
    }

    /// A vehicle that never gets to the start at rest: the approach times out (its leg budget)
    /// and the executor lands; the reference clock never started.
    #[test]
    fn an_unreached_start_times_out_and_lands_without_starting_the_clock() {
        let r = MinJerkLine::new(vec![[50.0, 0.0, -5.0], [80.0, 0.0, -5.0]], vec![10.0]).unwrap();
        let config = ExecutorConfig {
            leg_timeout_base_s: 5.0,
            leg_timeout_per_m_s: 0.1,
            ..ExecutorConfig::default()
        };
        let mut ex = ReferenceExecutor::new(Arc::new(r), config).unwrap();
        let hovering = crate::testkit::hovering();
        let mut commands = Vec::new();
        for k in 0..200 {
            let t = f64::from(k) * 0.1;
            commands.extend(ex.handle(t, Event::Telemetry(hovering)).commands);
        }
        assert!(commands.contains(&Command::GoTo {
            north_m: 50.0,
            east_m: 0.0,
            down_m: -5.0,
            yaw_rad: 0.0
        }));
        assert!(!commands.iter().any(|c| matches!(c, Command::Track { .. })));
        assert_eq!(commands.last(), Some(&Command::Land), "{commands:?}");
        assert_eq!(ex.state(), FlightState::Landing);
        let report = ex.tracking().unwrap();
        assert_eq!(
            (report.started_s, report.flown_s, report.samples),
            (None, None, 0)
        );
    }

    #[test]
    fn a_reference_that_is_not_finite_is_refused() {
        struct Bad;
        impl Reference for Bad {
            fn duration_s(&self) -> f64 {
                f64::INFINITY
            }
            fn setpoint(&self, _t_s: f64) -> crate::reference::Setpoint {
                crate::reference::Setpoint::at_rest([0.0, 0.0, -5.0], 0.0)
            }
        }
        assert!(ReferenceExecutor::new(Arc::new(Bad), ExecutorConfig::default()).is_err());
    }

    /// A vehicle on the reference's path but a second late is far from where it should be at
    /// that instant and nowhere off the path; one beside the path is off it by that distance.
    #[test]
    fn the_path_error_forgives_being_late_not_being_beside() {
        let r: Arc<dyn Reference> = Arc::new(
            MinJerkLine::new(vec![[0.0, 0.0, -5.0], [100.0, 0.0, -5.0]], vec![20.0]).unwrap(),
        );
        let tracking = ReferenceTracking::approaching(Arc::clone(&r));
        let late = r.setpoint(9.0).point_ned;
        let instant = r.setpoint(10.0).distance_m(late);
        assert!(instant > 5.0, "{instant}");
        let path = tracking.path_error_m(late, 10.0, instant);
        assert!(path < 0.05, "{path}");
        let mut beside = r.setpoint(10.0).point_ned;
        beside[1] += 2.0;
        let path = tracking.path_error_m(beside, 10.0, 2.0);
        assert!((1.9..=2.0).contains(&path), "{path}");
    }
}
