//! What the executor tests share: a route, the simulated vehicle's telemetry, and commands
//! applied to it the way the link layer does.

use crate::executor::{Command, CommandKind, Event, Target, Telemetry, VehicleMode};
use crate::sim::{SimMode, SimRefusal, SimVehicle};

/// A waypoint at 5 m.
pub(crate) fn wp(n: f64, e: f64, heading_deg: f64) -> Target {
    Target {
        north_m: n,
        east_m: e,
        alt_m: 5.0,
        heading_rad: heading_deg.to_radians(),
    }
}

/// A 20 m square, three legs, turning at each corner.
pub(crate) fn route() -> Vec<Target> {
    vec![
        wp(0.0, 0.0, 0.0),
        wp(20.0, 0.0, 0.0),
        wp(20.0, 20.0, 90.0),
        wp(0.0, 20.0, 180.0),
    ]
}

/// The vehicle's state as the link reports it.
pub(crate) fn telemetry(v: &SimVehicle) -> Telemetry {
    let s = v.state();
    Telemetry {
        north_m: s.position_ned_m[0],
        east_m: s.position_ned_m[1],
        down_m: s.position_ned_m[2],
        velocity_ned_m_s: s.velocity_ned_m_s,
        yaw_rad: s.yaw_rad,
        armed: s.armed,
        guided: s.mode == SimMode::Guided,
        on_ground: Some(s.on_ground),
        sample_time_s: Some(s.time_s),
    }
}

/// The executor's view of a simulated mode.
pub(crate) fn mode_of(m: SimMode) -> VehicleMode {
    match m {
        SimMode::Guided => VehicleMode::Guided,
        SimMode::Auto => VehicleMode::Auto,
        SimMode::Land => VehicleMode::Land,
        SimMode::Loiter => VehicleMode::Hold,
        SimMode::Rtl => VehicleMode::ReturnToLaunch,
        other => VehicleMode::Other(other.arducopter_custom_mode()),
    }
}

/// Applies a command to the simulated vehicle the way the link does, returning the ack.
pub(crate) fn apply(v: &mut SimVehicle, c: Command) -> Option<Event> {
    let ack = |command, r: Result<(), SimRefusal>| Event::Ack {
        command,
        accepted: r.map_err(|e| format!("DENIED: {e}")),
    };
    match c {
        Command::TakeControl => {
            v.set_mode(SimMode::Guided);
            Some(ack(CommandKind::TakeControl, Ok(())))
        }
        Command::Arm => Some(ack(CommandKind::Arm, v.arm())),
        Command::Takeoff { alt_m } => Some(ack(CommandKind::Takeoff, v.takeoff(alt_m))),
        Command::GoTo { .. } => {
            if let Some((position_ned_m, yaw_rad)) = c.position_target() {
                let _ = v.set_position_target(position_ned_m, yaw_rad);
            }
            None
        }
        Command::Track { setpoint, time_s } => {
            let target = crate::sim::SimTarget {
                position_ned_m: setpoint.point_ned,
                velocity_ned_m_s: Some(setpoint.vel_ned_m_s),
                accel_ned_m_s2: Some(setpoint.accel_ned_m_s2),
                yaw_rad: setpoint.yaw_rad,
            };
            // Vehicle time is executor time here: brought to the vehicle's now.
            let _ = v.set_target(target.advanced(v.state().time_s - time_s));
            None
        }
        Command::Land => {
            v.land();
            Some(ack(CommandKind::Land, Ok(())))
        }
        Command::Disarm => Some(ack(CommandKind::Disarm, v.disarm())),
        Command::StartMission => {
            v.set_mode(SimMode::Auto);
            Some(ack(CommandKind::StartMission, Ok(())))
        }
        Command::Hold => {
            v.set_mode(SimMode::Loiter);
            Some(ack(CommandKind::Hold, Ok(())))
        }
        Command::ReturnToLaunch => {
            v.set_mode(SimMode::Rtl);
            Some(ack(CommandKind::ReturnToLaunch, Ok(())))
        }
    }
}

/// Telemetry of a vehicle hovering armed in GUIDED at 5 m over home.
pub(crate) fn hovering() -> Telemetry {
    Telemetry {
        armed: true,
        guided: true,
        down_m: -5.0,
        on_ground: Some(false),
        ..Telemetry::default()
    }
}

/// A link lost between `from_s` and `to_s` (vehicle time = link time here), silent since
/// `from_s - 1`, regained in the 0.1 s after `to_s`.
pub(crate) fn link_gap(t: f64, from_s: f64, to_s: f64) -> Option<Event> {
    if t > from_s && t < to_s {
        Some(Event::LinkLost {
            silent_s: t - (from_s - 1.0),
        })
    } else if (to_s..to_s + 0.1).contains(&t) {
        Some(Event::LinkRegained {
            silent_s: to_s - (from_s - 1.0),
        })
    } else {
        None
    }
}

/// A Ctrl-C with `--on-interrupt hold` at `now_s`: the executor commands the hold at once.
pub(crate) fn ctrl_c_hold<E: crate::executor::FlightExecutor>(ex: &mut E, now_s: f64) {
    let out = ex.handle(
        now_s,
        Event::Stop {
            reason: "interrupted by Ctrl-C".into(),
            action: crate::executor::FailsafeAction::Hold,
        },
    );
    assert_eq!(out.commands, vec![Command::Hold]);
}
