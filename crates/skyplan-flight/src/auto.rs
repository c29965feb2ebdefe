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
    Command, ConfigError, Core, Event, Executor, ExecutorConfig, Failure, FlightState, Output,
    Strategy, Target, Telemetry, VehicleMode,
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
    /// The first waypoint's item; waypoint `k` is item `first_waypoint_seq + waypoint_stride · k`.
    pub first_waypoint_seq: u16,
    /// Items per waypoint (2 when each NAV_WAYPOINT is preceded by its CONDITION_YAW); the land
    /// item follows the last waypoint.
    pub waypoint_stride: u16,
    /// The NAV_LAND item.
    pub land_seq: u16,
}

impl From<&MissionPlan> for MissionLayout {
    fn from(p: &MissionPlan) -> Self {
        Self {
            takeoff_seq: p.takeoff_seq,
            first_waypoint_seq: p.first_waypoint_seq,
            waypoint_stride: p.waypoint_stride,
            land_seq: p.land_seq,
        }
    }
}

/// The uploaded mission flown in AUTO: see the module documentation.
#[derive(Debug, Clone)]
pub struct AutoMission {
    layout: MissionLayout,
    /// The item a MISSION_ITEM_REACHED said before this mission ran (ArduPilot streams the last
    /// one reached when asked to): ignored until another one comes.
    stale_reached: Option<u16>,
    seen_auto: bool,
    takeoff_done: bool,
    land_started: bool,
}

/// The AUTO executor. See the module documentation.
pub type AutoExecutor = Executor<AutoMission>;

impl Executor<AutoMission> {
    /// An executor for these waypoints, uploaded with this layout.
    pub fn new(
        targets: &[Target],
        layout: MissionLayout,
        config: ExecutorConfig,
    ) -> Result<Self, ConfigError> {
        let stride = usize::from(layout.waypoint_stride);
        if targets.is_empty()
            || usize::from(layout.land_seq)
                != usize::from(layout.first_waypoint_seq) + stride * (targets.len() - 1) + 1
            || layout.takeoff_seq >= layout.first_waypoint_seq
            || stride == 0
        {
            return Err(ConfigError(format!(
                "the mission layout (take-off item {}, first waypoint item {}, {} items a waypoint, land item {}) does not match {} waypoints",
                layout.takeoff_seq,
                layout.first_waypoint_seq,
                layout.waypoint_stride,
                layout.land_seq,
                targets.len()
            )));
        }
        let strategy = AutoMission {
            layout,
            stale_reached: None,
            seen_auto: false,
            takeoff_done: false,
            land_started: false,
        };
        Self::with_strategy(targets, config, strategy)
    }
}

impl AutoMission {
    /// Every waypoint up to item `seq` (inclusive when `inclusive`) counts as reached. A
    /// CONDITION_YAW reported reached says nothing of its waypoint (ArduCopter may finish the
    /// turn before the waypoint).
    fn passed(&mut self, core: &mut Core, now_s: f64, seq: u16, inclusive: bool, out: &mut Output) {
        let l = self.layout;
        let stride = l.waypoint_stride.max(1);
        if inclusive
            && seq > l.first_waypoint_seq
            && seq < l.land_seq
            && !(seq - l.first_waypoint_seq).is_multiple_of(stride)
        {
            return;
        }
        if seq > l.takeoff_seq || (inclusive && seq == l.takeoff_seq) {
            self.takeoff_done = true;
        }
        if seq >= l.land_seq {
            self.land_started = true;
        }
        let end = if inclusive {
            seq.saturating_add(1)
        } else {
            seq
        };
        if end <= l.first_waypoint_seq {
            return;
        }
        let upto =
            usize::from((end - l.first_waypoint_seq).div_ceil(stride)).min(core.targets.len());
        while core.reached.len() < upto {
            core.reach(now_s, core.reached.len(), out);
        }
    }

    /// The vehicle has been out of AUTO too long: the mode it is in.
    fn left_auto(&self, core: &Core, now_s: f64) -> Option<VehicleMode> {
        core.mode.filter(|&m| {
            m != VehicleMode::Auto
                && core
                    .not_auto_since_s
                    .is_some_and(|since| now_s - since >= LEFT_AUTO_GRACE_S)
        })
    }
}

impl Strategy for AutoMission {
    const DISARM_WAIT_S: f64 = AUTO_DISARM_WAIT_S;
    const COMMANDS_LANDING: bool = false;
    const REPLANS: bool = false;

    fn in_control(&self, core: &Core, t: &Telemetry) -> bool {
        match core.mode {
            Some(m) => m == VehicleMode::Guided,
            None => t.guided,
        }
    }

    fn ready_to_fly(&self, core: &Core, t: &Telemetry) -> bool {
        t.armed && (self.in_control(core, t) || core.mode == Some(VehicleMode::Auto))
    }

    fn start(&mut self, core: &mut Core, now_s: f64, out: &mut Output) -> bool {
        out.commands.push(Command::StartMission);
        core.last_send_s = Some(now_s);
        false
    }

    fn observe(&mut self, core: &mut Core, now_s: f64, event: &Event, out: &mut Output) {
        match *event {
            // Not an item of this mission (ArduPilot says 65535 before any).
            Event::MissionItemReached(seq) | Event::MissionCurrent(seq)
                if seq > self.layout.land_seq => {}
            // Before this mission runs, a report is the previous flight's (or a stream's
            // repeat of it): remembered, not counted, until another item is reported.
            Event::MissionItemReached(seq) if !self.seen_auto => self.stale_reached = Some(seq),
            Event::MissionItemReached(seq) if self.stale_reached == Some(seq) => {}
            Event::MissionItemReached(seq) => {
                self.stale_reached = None;
                self.passed(core, now_s, seq, true, out);
            }
            Event::MissionCurrent(seq) if self.seen_auto => {
                self.passed(core, now_s, seq, false, out);
            }
            Event::Ack {
                command: crate::executor::CommandKind::StartMission,
                accepted: Ok(()),
            } => self.seen_auto |= core.mode == Some(VehicleMode::Auto),
            _ => {}
        }
    }

    fn takeoff(&mut self, core: &mut Core, now_s: f64, t: &Telemetry, out: &mut Output) -> bool {
        let c = core.config;
        if core.mode == Some(VehicleMode::Auto) {
            self.seen_auto = true;
        }
        let alt_m = core.targets[0].alt_m;
        if self.takeoff_done || core.climbed(t, alt_m) {
            self.takeoff_done = true;
            core.enter(FlightState::Waypoint, now_s, out);
            core.leg_since_s = now_s;
            return true;
        }
        if !t.armed {
            core.fail(Failure::DisarmedInFlight { state: core.state }, out);
        } else if let Some(mode) = self.left_auto(core, now_s)
            && self.seen_auto
        {
            core.fail(
                Failure::LeftMission {
                    state: core.state,
                    mode,
                },
                out,
            );
        } else if now_s - core.state_since_s > c.takeoff_timeout_s {
            let awaited = if self.seen_auto {
                format!(
                    "the vehicle reached {:.1} m of the {:.1} m needed",
                    t.alt_m(),
                    c.takeoff_fraction * alt_m
                )
            } else {
                "the vehicle did not enter AUTO".to_string()
            };
            core.time_out(now_s, c.takeoff_timeout_s, &awaited, out);
        } else if !self.seen_auto && core.due(now_s, c.retry_s) {
            out.commands.push(Command::StartMission);
        }
        false
    }

    fn waypoint(&mut self, core: &mut Core, now_s: f64, t: &Telemetry, out: &mut Output) -> bool {
        let n = core.targets.len();
        let all = core.reached.len() >= n;
        // The last waypoint reached or the land item current: the vehicle lands by itself.
        if all || self.land_started {
            core.land_after_mission(now_s, Self::COMMANDS_LANDING, out);
            return true;
        }
        if !t.armed {
            core.fail(Failure::DisarmedInFlight { state: core.state }, out);
            return false;
        }
        if let Some(mode) = self.left_auto(core, now_s) {
            core.fail(
                Failure::LeftMission {
                    state: core.state,
                    mode,
                },
                out,
            );
            return false;
        }
        let i = core.reached.len().min(n - 1);
        let budget_s = core.leg_budget_s(i);
        if now_s - core.leg_since_s > budget_s {
            let w = core.targets[i];
            let awaited = format!(
                "waypoint {} of {n} not reported reached: {:.1} m away horizontally, {:.1} m vertically",
                i + 1,
                w.horizontal_error_m(t),
                w.vertical_error_m(t),
            );
            core.time_out(now_s, budget_s, &awaited, out);
        }
        false
    }
}

#[cfg(test)]
mod tests;
