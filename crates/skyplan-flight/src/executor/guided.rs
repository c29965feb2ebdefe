//! The GUIDED strategy: take off with NAV_TAKEOFF, then stream each waypoint as a position +
//! yaw target until the vehicle is within the deadband, land after the last one.

use super::core::{Core, Executor, Strategy};
use super::interface::{Command, Event, FlightState, Target, Telemetry};
use super::report::{ConfigError, ExecutorConfig, Failure, Output};

/// GUIDED position targets: see the module documentation.
#[derive(Debug, Clone, Default)]
pub struct GuidedTargets;

/// The GUIDED executor (position targets streamed to a vehicle in GUIDED / OFFBOARD).
pub type MissionExecutor = Executor<GuidedTargets>;

impl Executor<GuidedTargets> {
    /// An executor for these waypoints (at least one, at a positive altitude).
    pub fn new(targets: &[Target], config: ExecutorConfig) -> Result<Self, ConfigError> {
        Self::with_strategy(targets, config, GuidedTargets)
    }
}

/// The target to stream for waypoint `w`.
pub(super) fn goto(w: &Target) -> Command {
    Command::GoTo {
        north_m: w.north_m,
        east_m: w.east_m,
        down_m: -w.alt_m,
        yaw_rad: w.heading_rad,
    }
}

impl Strategy for GuidedTargets {
    const DISARM_WAIT_S: f64 = 0.0;
    const COMMANDS_LANDING: bool = true;
    const REPLANS: bool = true;

    fn in_control(&self, _core: &Core, t: &Telemetry) -> bool {
        t.guided
    }

    fn ready_to_fly(&self, _core: &Core, t: &Telemetry) -> bool {
        t.guided && t.armed
    }

    fn start(&mut self, _core: &mut Core, _now_s: f64, _out: &mut Output) -> bool {
        true
    }

    fn observe(&mut self, _core: &mut Core, _now_s: f64, _event: &Event, _out: &mut Output) {}

    fn takeoff(&mut self, core: &mut Core, now_s: f64, t: &Telemetry, out: &mut Output) -> bool {
        takeoff_to_first(core, now_s, t, out)
    }

    fn waypoint(&mut self, core: &mut Core, now_s: f64, t: &Telemetry, out: &mut Output) -> bool {
        let c = core.config;
        if !t.armed {
            core.fail(Failure::DisarmedInFlight { state: core.state }, out);
            return false;
        }
        if !t.guided {
            core.fail(Failure::ControlLost { state: core.state }, out);
            return false;
        }
        let n = core.targets.len();
        // Reach as many waypoints as the vehicle is already at (a repeated point).
        while let Some(w) = core.targets.get(core.next_index()) {
            let deadband = c.deadband_m + c.deadband_per_speed_s * t.ground_speed_m_s();
            if w.horizontal_error_m(t) <= deadband
                && w.vertical_error_m(t) <= c.vertical_deadband_m
                && w.heading_error_rad(t) <= c.heading_tolerance_rad
            {
                core.reach(now_s, core.next_index(), out);
                core.last_send_s = None;
            } else {
                break;
            }
        }
        let all = core.next_index() >= n;
        if all && t.speed_m_s() < c.land_speed_m_s {
            core.land_after_mission(now_s, Self::COMMANDS_LANDING, out);
            return true;
        }
        let i = core.next_index().min(n - 1);
        let budget_s = core.leg_budget_s(i);
        let w = core.targets[i];
        if now_s - core.leg_since_s > budget_s {
            let awaited = if all {
                format!(
                    "the vehicle did not slow below {} m/s at the last waypoint",
                    c.land_speed_m_s
                )
            } else {
                format!(
                    "waypoint {} of {n} not reached: {:.1} m away horizontally, {:.1} m vertically, heading off by {:.1}°",
                    i + 1,
                    w.horizontal_error_m(t),
                    w.vertical_error_m(t),
                    w.heading_error_rad(t).to_degrees()
                )
            };
            core.time_out(now_s, budget_s, &awaited, out);
        } else if core.due(now_s, c.target_period_s) {
            out.commands.push(goto(&w));
        }
        false
    }
}

/// TAKEOFF in GUIDED: NAV_TAKEOFF to the first target's altitude, re-sent until accepted;
/// `true` once WAYPOINT is entered (at the take-off fraction of the altitude).
pub(super) fn takeoff_to_first(
    core: &mut Core,
    now_s: f64,
    t: &Telemetry,
    out: &mut Output,
) -> bool {
    let c = core.config;
    let alt_m = core.targets[0].alt_m;
    if !t.armed {
        core.fail(Failure::DisarmedInFlight { state: core.state }, out);
    } else if !t.guided {
        core.fail(Failure::ControlLost { state: core.state }, out);
    } else if core.climbed(t, alt_m) {
        core.enter(FlightState::Waypoint, now_s, out);
        core.leg_since_s = now_s;
        return true;
    } else if now_s - core.state_since_s > c.takeoff_timeout_s {
        let awaited = format!(
            "the vehicle reached {:.1} m of the {:.1} m needed",
            t.alt_m(),
            c.takeoff_fraction * alt_m
        );
        core.time_out(now_s, c.takeoff_timeout_s, &awaited, out);
    } else if !core.acked() && core.due(now_s, c.retry_s) {
        out.commands.push(Command::Takeoff { alt_m });
    }
    false
}
