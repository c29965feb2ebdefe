use super::*;
use crate::executor::{CommandKind, Note, Outcome};
use crate::sim::{SimConfig, SimMode, SimVehicle};
use crate::testkit::{apply, ctrl_c_hold, hovering, link_gap, route, telemetry, wp};
use std::f64::consts::PI;

struct Flight {
    states: Vec<FlightState>,
    commands: Vec<Command>,
    end_s: f64,
}

/// Flies the executor against the simulated vehicle, telemetry at 10 Hz, until it finishes.
/// `fault(t, vehicle) -> Some(event)` can inject an event.
fn fly(
    ex: &mut MissionExecutor,
    v: &mut SimVehicle,
    limit_s: f64,
    fault: impl FnMut(f64, &mut SimVehicle) -> Option<Event>,
) -> Flight {
    fly_homing(ex, v, limit_s, fault, |_, _, _| None)
}

/// As [`fly`]; when the executor wants the way home, `home(executor, t, from_ned)` may answer
/// (with [`MissionExecutor::return_home`] or [`MissionExecutor::no_way_home`]).
fn fly_homing(
    ex: &mut MissionExecutor,
    v: &mut SimVehicle,
    limit_s: f64,
    mut fault: impl FnMut(f64, &mut SimVehicle) -> Option<Event>,
    mut home: impl FnMut(&mut MissionExecutor, f64, [f64; 3]) -> Option<Output>,
) -> Flight {
    let mut f = Flight {
        states: vec![ex.state()],
        commands: Vec::new(),
        end_s: 0.0,
    };
    let mut t = 0.0;
    let mut pending = Vec::new();
    while ex.outcome().is_none() && t < limit_s {
        for _ in 0..5 {
            v.step(0.02);
        }
        t += 0.1;
        let mut events = std::mem::take(&mut pending);
        events.extend(fault(t, v));
        events.push(Event::Telemetry(telemetry(v)));
        let mut outputs: Vec<Output> = events.into_iter().map(|e| ex.handle(t, e)).collect();
        if let Some(from_ned) = ex.way_home_wanted() {
            outputs.extend(home(ex, t, from_ned));
        }
        for out in outputs {
            for n in &out.notes {
                if let Note::State { to, .. } = n {
                    f.states.push(*to);
                }
            }
            for c in out.commands {
                f.commands.push(c);
                pending.extend(apply(v, c));
            }
        }
    }
    f.end_s = t;
    f
}

#[test]
fn flies_the_fcnd_sequence_against_the_simulated_vehicle() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let f = fly(&mut ex, &mut v, 300.0, |_, _| None);
    assert_eq!(
        ex.outcome(),
        Some(&Outcome::Completed),
        "{:?}",
        ex.outcome()
    );
    use FlightState::*;
    assert_eq!(
        f.states,
        vec![
            Manual, Arming, Takeoff, Waypoint, Landing, Disarming, Manual
        ]
    );
    assert_eq!(ex.reached().len(), 4);
    for (i, r) in ex.reached().iter().enumerate() {
        assert_eq!(r.index, i);
        assert!(r.horizontal_error_m <= 1.0 && r.heading_error_rad <= 10f64.to_radians());
    }
    let s = v.state();
    assert!(s.on_ground && !s.armed);
    assert!((s.position_ned_m[0]).abs() < 1.5 && (s.position_ned_m[1] - 20.0).abs() < 1.5);
    // Position targets were streamed at ≥ 2 Hz: about one per 0.2 s of WAYPOINT.
    let gotos = f
        .commands
        .iter()
        .filter(|c| matches!(c, Command::GoTo { .. }))
        .count();
    assert!(
        gotos as f64 > 2.0 * 20.0,
        "{gotos} position targets in {} s",
        f.end_s
    );
    assert!(f.end_s < 80.0, "{}", f.end_s);
}

#[test]
fn takeoff_ends_at_95_percent_of_the_altitude() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut t = Telemetry {
        armed: true,
        guided: true,
        on_ground: Some(true),
        ..Telemetry::default()
    };
    let out = ex.handle(0.0, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Takeoff);
    assert_eq!(out.commands, vec![Command::Takeoff { alt_m: 5.0 }]);
    t.on_ground = Some(false);
    t.down_m = -4.74;
    ex.handle(0.5, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Takeoff);
    t.down_m = -4.76;
    let out = ex.handle(0.6, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Waypoint);
    // The first waypoint is right here, facing north: reached at once; the second is commanded.
    assert_eq!(ex.reached().len(), 1);
    assert!(out.commands.contains(&Command::GoTo {
        north_m: 20.0,
        east_m: 0.0,
        down_m: -5.0,
        yaw_rad: 0.0
    }));
}

fn at_waypoint_state() -> (MissionExecutor, Telemetry) {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let t = hovering();
    ex.handle(0.0, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Waypoint);
    assert_eq!(ex.reached().len(), 1);
    (ex, t)
}

#[test]
fn waypoint_needs_the_deadband_the_altitude_and_the_heading() {
    let (mut ex, mut t) = at_waypoint_state();
    t.north_m = 18.9; // 1.1 m short
    ex.handle(1.0, Event::Telemetry(t));
    assert_eq!(ex.reached().len(), 1);
    t.north_m = 19.1;
    t.yaw_rad = 30f64.to_radians(); // within the deadband, heading off
    ex.handle(2.0, Event::Telemetry(t));
    assert_eq!(ex.reached().len(), 1);
    t.yaw_rad = 0.0;
    t.down_m = -6.5; // 1.5 m too high
    ex.handle(3.0, Event::Telemetry(t));
    assert_eq!(ex.reached().len(), 1);
    t.down_m = -5.2;
    let out = ex.handle(4.0, Event::Telemetry(t));
    assert_eq!(ex.reached().len(), 2);
    let r = ex.reached()[1];
    assert!((r.horizontal_error_m - 0.9).abs() < 1e-9 && r.index == 1 && r.time_s == 4.0);
    assert!(matches!(out.notes[0], Note::Reached(_)));
    assert_eq!(ex.current_target().map(|(i, _)| i), Some(2));
}

#[test]
fn deadband_can_grow_with_speed() {
    let config = ExecutorConfig {
        deadband_per_speed_s: 0.5,
        ..ExecutorConfig::default()
    };
    let mut ex = MissionExecutor::new(&route(), config).unwrap();
    let mut t = hovering();
    ex.handle(0.0, Event::Telemetry(t));
    t.north_m = 17.5; // 2.5 m short, at 4 m/s: deadband 1 + 2 = 3 m
    t.velocity_ned_m_s = [4.0, 0.0, 0.0];
    ex.handle(1.0, Event::Telemetry(t));
    assert_eq!(ex.reached().len(), 2);
}

#[test]
fn lands_only_when_the_last_waypoint_is_reached_and_slow() {
    let targets = [wp(0.0, 0.0, 0.0)];
    let mut ex = MissionExecutor::new(&targets, ExecutorConfig::default()).unwrap();
    let mut t = Telemetry {
        armed: true,
        guided: true,
        down_m: -5.0,
        velocity_ned_m_s: [1.0, 0.0, 0.0],
        on_ground: Some(false),
        ..Telemetry::default()
    };
    ex.handle(0.0, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Waypoint);
    assert_eq!(ex.reached().len(), 1);
    t.velocity_ned_m_s = [0.3, 0.0, 0.0];
    let out = ex.handle(1.0, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Landing);
    assert_eq!(out.commands, vec![Command::Land]);
    // Without the vehicle's landed flag: low and not descending means on the ground.
    t.on_ground = None;
    t.down_m = -0.1;
    t.velocity_ned_m_s = [0.0, 0.0, 0.5];
    ex.handle(5.0, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Landing);
    t.velocity_ned_m_s = [0.0; 3];
    let out = ex.handle(6.0, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Disarming);
    assert_eq!(out.commands, vec![Command::Disarm]);
    t.armed = false;
    let out = ex.handle(7.0, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Manual);
    assert_eq!(ex.outcome(), Some(&Outcome::Completed));
    assert!(out.notes.contains(&Note::Finished));
}

#[test]
fn arming_refusal_is_shown_and_times_out_with_the_vehicle_reason() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let t = Telemetry {
        guided: true,
        on_ground: Some(true),
        ..Telemetry::default()
    };
    let out = ex.handle(0.0, Event::Telemetry(t));
    assert_eq!(out.commands, vec![Command::Arm]);
    ex.handle(0.1, Event::StatusText("Arm: Accels inconsistent".into()));
    let out = ex.handle(
        0.2,
        Event::Ack {
            command: CommandKind::Arm,
            accepted: Err("DENIED".into()),
        },
    );
    assert_eq!(
        out.notes,
        vec![Note::Refused {
            command: CommandKind::Arm,
            reason: "DENIED: Arm: Accels inconsistent".into()
        }]
    );
    // Retried once a second.
    assert!(ex.handle(0.5, Event::Tick).commands.is_empty());
    assert_eq!(ex.handle(1.0, Event::Tick).commands, vec![Command::Arm]);
    let out = ex.handle(61.0, Event::Tick);
    assert!(out.commands.is_empty());
    let Some(Outcome::Failed(failure)) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    let text = failure.to_string();
    assert!(
        text.contains("ARMING timed out") && text.contains("Accels inconsistent"),
        "{text}"
    );
}

#[test]
fn link_loss_ends_the_flight_without_commands() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let f = fly(&mut ex, &mut v, 300.0, |t, _| {
        (t > 15.0).then_some(Event::LinkLost { silent_s: 5.0 })
    });
    let Some(Outcome::Failed(failure)) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert_eq!(
        failure,
        &Failure::LinkLost {
            state: FlightState::Waypoint,
            silent_s: 5.0
        }
    );
    assert!(failure.to_string().contains("link lost in WAYPOINT"));
    assert!(f.end_s < 15.2);
    // Nothing more is sent after the end.
    assert!(ex.handle(16.0, Event::Tick).commands.is_empty());
}

#[test]
fn abort_lands_and_reports() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let mut sent = false;
    let f = fly(&mut ex, &mut v, 300.0, |t, _| {
        (t > 12.0 && !std::mem::replace(&mut sent, true)).then(|| Event::Abort("Ctrl-C".into()))
    });
    use FlightState::*;
    assert_eq!(
        f.states,
        vec![
            Manual, Arming, Takeoff, Waypoint, Landing, Disarming, Manual
        ]
    );
    assert_eq!(
        ex.outcome(),
        Some(&Outcome::Failed(Failure::Aborted {
            reason: "Ctrl-C".into()
        }))
    );
    assert!(v.state().on_ground && !v.state().armed);
}

#[test]
fn stuck_leg_times_out_and_lands() {
    let (mut ex, t) = at_waypoint_state();
    // Leg 1 is 20 m: budget 30 + 20 s.
    assert!(ex.handle(49.0, Event::Telemetry(t)).notes.is_empty());
    let out = ex.handle(51.0, Event::Telemetry(t));
    assert_eq!(out.commands, vec![Command::Land]);
    // The flight is not over until the vehicle is down and disarmed.
    assert_eq!(ex.state(), FlightState::Landing);
    assert_eq!(ex.outcome(), None);
    let down = Telemetry {
        down_m: 0.0,
        on_ground: Some(true),
        ..t
    };
    assert_eq!(
        ex.handle(60.0, Event::Telemetry(down)).commands,
        vec![Command::Disarm]
    );
    assert_eq!(ex.outcome(), None);
    let disarmed = Telemetry {
        armed: false,
        ..down
    };
    ex.handle(61.0, Event::Telemetry(disarmed));
    let Some(Outcome::Failed(Failure::Timeout { state, detail, .. })) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert_eq!(*state, FlightState::Waypoint);
    assert!(
        detail.contains("waypoint 2 of 4 not reached: 20.0 m away"),
        "{detail}"
    );
    assert!(
        detail.ends_with("the vehicle then landed and disarmed"),
        "{detail}"
    );
}

#[test]
fn disarm_or_mode_change_in_flight_fails() {
    let (mut ex, mut t) = at_waypoint_state();
    t.guided = false;
    ex.handle(1.0, Event::Telemetry(t));
    assert_eq!(
        ex.outcome(),
        Some(&Outcome::Failed(Failure::ControlLost {
            state: FlightState::Waypoint
        }))
    );
    let (mut ex, mut t) = at_waypoint_state();
    t.armed = false;
    ex.handle(1.0, Event::Telemetry(t));
    assert!(matches!(
        ex.outcome(),
        Some(Outcome::Failed(Failure::DisarmedInFlight { .. }))
    ));
}

#[test]
fn bad_missions_are_refused() {
    assert!(MissionExecutor::new(&[], ExecutorConfig::default()).is_err());
    let low = [Target {
        alt_m: 0.0,
        ..wp(0.0, 0.0, 0.0)
    }];
    assert!(MissionExecutor::new(&low, ExecutorConfig::default()).is_err());
    let nan = [Target {
        north_m: f64::NAN,
        ..wp(0.0, 0.0, 0.0)
    }];
    assert!(MissionExecutor::new(&nan, ExecutorConfig::default()).is_err());
}

#[test]
fn wraps_angles() {
    assert!((wrap_angle_rad(3.0 * PI) - PI).abs() < 1e-12);
    assert!((wrap_angle_rad(-PI) - PI).abs() < 1e-12);
    assert!((wrap_angle_rad(0.1 - 2.0 * PI) - 0.1).abs() < 1e-12);
}

fn with_failsafe(action: FailsafeAction) -> ExecutorConfig {
    ExecutorConfig {
        failsafe: Some(action),
        link_regain_wait_s: 10.0,
        ..ExecutorConfig::default()
    }
}

/// A link lost from `t` = 15 s to 18 s (vehicle time = link time here).
fn gap(t: f64) -> Option<Event> {
    link_gap(t, 15.0, 18.0)
}

#[test]
fn a_lost_link_is_waited_for_silently_and_given_up_on() {
    let (mut ex, t) = at_waypoint_state();
    let mut ex_fs = MissionExecutor::new(&route(), with_failsafe(FailsafeAction::Land)).unwrap();
    for (i, e) in [
        Event::Telemetry(Telemetry {
            on_ground: Some(true),
            ..t
        }),
        Event::Telemetry(t),
    ]
    .into_iter()
    .enumerate()
    {
        ex_fs.handle(i as f64 * 0.1, e);
    }
    assert_eq!(ex_fs.state(), FlightState::Waypoint);
    // Without --failsafe: the flight ends at once.
    ex.handle(1.0, Event::LinkLost { silent_s: 5.0 });
    assert!(matches!(
        ex.outcome(),
        Some(Outcome::Failed(Failure::LinkLost { .. }))
    ));
    // With it: a note, then nothing is sent (not even the position target that is due).
    let out = ex_fs.handle(1.0, Event::LinkLost { silent_s: 5.0 });
    assert!(out.commands.is_empty() && ex_fs.outcome().is_none());
    assert!(matches!(
        out.notes[..],
        [Note::LinkLost {
            state: FlightState::Waypoint,
            wait_s: 10.0,
            action: FailsafeAction::Land,
            ..
        }]
    ));
    for k in 0..20 {
        let tt = 1.1 + f64::from(k) * 0.2;
        assert!(ex_fs.handle(tt, Event::Telemetry(t)).commands.is_empty());
        assert!(ex_fs.handle(tt, Event::Tick).commands.is_empty());
    }
    assert!(
        ex_fs
            .handle(5.0, Event::LinkLost { silent_s: 9.9 })
            .notes
            .is_empty()
    );
    // Past the wait: lost for good, reported in the state it was lost in.
    ex_fs.handle(6.0, Event::LinkLost { silent_s: 10.1 });
    assert_eq!(
        ex_fs.outcome(),
        Some(&Outcome::Failed(Failure::LinkLost {
            state: FlightState::Waypoint,
            silent_s: 10.1
        }))
    );
}

#[test]
fn on_the_ground_a_lost_link_ends_the_flight_even_with_a_failsafe() {
    let mut ex = MissionExecutor::new(&route(), with_failsafe(FailsafeAction::Hold)).unwrap();
    ex.handle(0.0, Event::Telemetry(Telemetry::default()));
    assert_eq!(ex.state(), FlightState::Arming);
    ex.handle(0.5, Event::LinkLost { silent_s: 5.0 });
    assert!(matches!(
        ex.outcome(),
        Some(Outcome::Failed(Failure::LinkLost {
            state: FlightState::Arming,
            ..
        }))
    ));
}

#[test]
fn failsafe_land_when_the_link_returns() {
    let mut ex = MissionExecutor::new(&route(), with_failsafe(FailsafeAction::Land)).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let f = fly(&mut ex, &mut v, 300.0, |t, _| gap(t));
    use FlightState::*;
    assert_eq!(
        f.states,
        vec![
            Manual, Arming, Takeoff, Waypoint, Landing, Disarming, Manual
        ]
    );
    let Some(Outcome::Failed(Failure::Aborted { reason })) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert!(
        reason.contains("link lost in WAYPOINT for 4.0 s; --failsafe land on its return"),
        "{reason}"
    );
    assert!(v.state().on_ground && !v.state().armed);
    assert!(ex.reached().len() < 4);
}

#[test]
fn failsafe_rtl_flies_home_and_lands_there() {
    let mut ex =
        MissionExecutor::new(&route(), with_failsafe(FailsafeAction::ReturnToLaunch)).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let f = fly(&mut ex, &mut v, 300.0, |t, _| gap(t));
    assert!(f.commands.contains(&Command::ReturnToLaunch));
    assert!(!f.commands.contains(&Command::Land));
    let Some(Outcome::Failed(Failure::Aborted { reason })) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert!(reason.contains("--failsafe rtl"), "{reason}");
    let s = v.state();
    assert!(s.on_ground && !s.armed, "{s:?}");
    // Home is where it took off: the first waypoint, (0, 0).
    assert!(
        s.position_ned_m[0].hypot(s.position_ned_m[1]) < 1.5,
        "{s:?}"
    );
}

#[test]
fn failsafe_hold_and_ctrl_c_hold_leave_the_vehicle_holding() {
    let mut ex = MissionExecutor::new(&route(), with_failsafe(FailsafeAction::Hold)).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    fly(&mut ex, &mut v, 300.0, |t, _| gap(t));
    let Some(Outcome::Failed(failure)) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert!(
        matches!(failure, Failure::Held { state: FlightState::Waypoint, reason } if reason.contains("--failsafe hold")),
        "{failure:?}"
    );
    assert!(
        failure
            .to_string()
            .contains("holding its position in the air")
    );
    let s = v.state();
    assert!(
        s.armed && !s.on_ground && s.mode == SimMode::Loiter,
        "{s:?}"
    );

    // Ctrl-C with --on-interrupt hold.
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let mut sent = false;
    let f = fly(&mut ex, &mut v, 300.0, |t, _| {
        (t > 12.0 && !std::mem::replace(&mut sent, true)).then(|| Event::Stop {
            reason: "interrupted by Ctrl-C".into(),
            action: FailsafeAction::Hold,
        })
    });
    assert_eq!(f.commands.last(), Some(&Command::Hold));
    assert!(matches!(
        ex.outcome(),
        Some(Outcome::Failed(Failure::Held { .. }))
    ));
    assert!(v.state().armed && !v.state().on_ground);
}

#[test]
fn an_unconfirmed_hold_is_retried_then_becomes_a_landing() {
    let (mut ex, t) = at_waypoint_state();
    ctrl_c_hold(&mut ex, 1.0);
    assert!(ex.handle(1.5, Event::Telemetry(t)).commands.is_empty());
    assert_eq!(
        ex.handle(2.1, Event::Telemetry(t)).commands,
        vec![Command::Hold]
    );
    let out = ex.handle(
        2.2,
        Event::Ack {
            command: CommandKind::Hold,
            accepted: Err("DENIED".into()),
        },
    );
    assert!(matches!(out.notes[..], [Note::Refused { .. }]));
    let out = ex.handle(11.5, Event::Telemetry(t));
    assert_eq!(out.commands, vec![Command::Land]);
    assert_eq!(ex.state(), FlightState::Landing);
    let mut down = t;
    down.on_ground = Some(true);
    down.armed = false;
    ex.handle(20.0, Event::Telemetry(down));
    let Some(Outcome::Failed(Failure::Aborted { reason })) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert!(
        reason.contains("hold was not confirmed within 10 s, landing instead"),
        "{reason}"
    );
}

#[test]
fn a_link_lost_while_landing_resumes_the_landing_when_it_returns() {
    let mut ex = MissionExecutor::new(&route(), with_failsafe(FailsafeAction::Hold)).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let mut lost_at = None;
    let f = fly(&mut ex, &mut v, 300.0, |t, v| {
        if v.state().mode == SimMode::Land && lost_at.is_none() {
            lost_at = Some(t);
        }
        let since = t - lost_at?;
        if since < 1.0 {
            Some(Event::LinkLost {
                silent_s: since + 5.0,
            })
        } else if since < 1.1 {
            Some(Event::LinkRegained { silent_s: 6.0 })
        } else {
            None
        }
    });
    assert!(!f.commands.contains(&Command::Hold));
    assert_eq!(ex.outcome(), Some(&Outcome::Completed));
}

/// Drives an executor through an unconfirmed hold in WAYPOINT and returns the times at which it
/// sent LAND afterwards (hovering telemetry every 0.1 s, nothing acknowledged).
fn land_times_after_an_unconfirmed_hold<E: FlightExecutor>(ex: &mut E) -> Vec<f64> {
    let t = hovering();
    ex.handle(0.0, Event::Mode(VehicleMode::Guided));
    ex.handle(0.0, Event::Telemetry(t));
    ex.handle(0.1, Event::Mode(VehicleMode::Auto));
    ex.handle(0.1, Event::Telemetry(t));
    assert_eq!(ex.state(), FlightState::Waypoint);
    ctrl_c_hold(ex, 1.0);
    let mut lands = Vec::new();
    for k in 11..=150 {
        let now_s = f64::from(k) * 0.1;
        let out = ex.handle(now_s, Event::Telemetry(t));
        if out.commands.contains(&Command::Land) {
            lands.push(now_s);
        }
    }
    assert_eq!(ex.state(), FlightState::Landing);
    lands
}

#[test]
fn both_executors_resend_the_landing_after_a_failed_hold_only_after_the_retry_period() {
    let config = ExecutorConfig::default();
    let targets = [wp(0.0, 0.0, 0.0), wp(20.0, 0.0, 0.0)];
    let mut guided = MissionExecutor::new(&targets, config).unwrap();
    let layout = crate::auto::MissionLayout {
        takeoff_seq: 1,
        first_waypoint_seq: 2,
        waypoint_stride: 1,
        land_seq: 4,
    };
    let mut auto = crate::auto::AutoExecutor::new(&targets, layout, config).unwrap();
    let a = land_times_after_an_unconfirmed_hold(&mut guided);
    let b = land_times_after_an_unconfirmed_hold(&mut auto);
    // The hold (at 1.0 s) is given up after 10 s: LAND then, and again every retry period
    // while unacknowledged — the same in both executors.
    assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-9, "{a:?} vs {b:?}");
    }
    assert!((a[0] - 11.1).abs() < 1e-9, "{a:?}");
    assert!(
        a.windows(2).all(|w| w[1] - w[0] >= config.retry_s - 1e-9),
        "{a:?}"
    );
}

#[test]
fn the_landing_budget_grows_with_the_altitude() {
    // LANDING from 40 m may take 40 / 0.5 + 60 = 140 s; from 5 m, 10 + 60 = 70 s.
    let config = ExecutorConfig::default();
    for (alt_m, budget_s) in [(40.0, 140.0), (5.0, 70.0)] {
        let high = Target {
            alt_m,
            ..wp(0.0, 0.0, 0.0)
        };
        let mut ex = MissionExecutor::new(&[high], config).unwrap();
        let t = Telemetry {
            down_m: -alt_m,
            ..hovering()
        };
        ex.handle(0.0, Event::Telemetry(t));
        assert_eq!(ex.state(), FlightState::Landing);
        let hovering_still = Telemetry {
            down_m: -alt_m + 1.0,
            ..t
        };
        ex.handle(budget_s - 0.5, Event::Telemetry(hovering_still));
        assert_eq!(ex.outcome(), None, "{alt_m}");
        ex.handle(budget_s + 0.5, Event::Telemetry(hovering_still));
        let Some(Outcome::Failed(Failure::Timeout {
            state,
            after_s,
            detail,
        })) = ex.outcome()
        else {
            panic!("{:?}", ex.outcome())
        };
        assert_eq!(*state, FlightState::Landing);
        assert!((after_s - budget_s).abs() < 1e-9, "{after_s}");
        assert!(
            detail.contains(&format!("it was {alt_m:.1} m up when the landing began")),
            "{detail}"
        );
    }
}

/// A way home from `from_ned` that doglegs through (`from` north, 10 east) to the launch point
/// (0, 0), at 5 m.
fn dogleg_home(from_ned: [f64; 3]) -> crate::sensing::WayHome {
    let targets = vec![
        wp(from_ned[0], from_ned[1], 0.0),
        wp(from_ned[0], 10.0, 0.0),
        wp(0.0, 10.0, 0.0),
        wp(0.0, 0.0, 0.0),
    ];
    let length_m = targets
        .windows(2)
        .map(|w| w[0].horizontal_distance_m(&w[1]))
        .sum();
    crate::sensing::WayHome {
        targets,
        length_m,
        planner: "test".into(),
    }
}

#[test]
fn failsafe_return_holds_then_flies_the_way_home_it_is_given_and_lands_at_launch() {
    let mut ex = MissionExecutor::new(&route(), with_failsafe(FailsafeAction::Return)).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let mut asked = Vec::new();
    let f = fly_homing(
        &mut ex,
        &mut v,
        300.0,
        |t, _| gap(t),
        |ex, t, from| {
            asked.push(from);
            Some(ex.return_home(t, &dogleg_home(from)).unwrap())
        },
    );
    // Asked once, from where the vehicle was when the link came back (in the air, mid-route).
    assert_eq!(asked.len(), 1, "{asked:?}");
    assert!(asked[0][2] < -4.0, "{asked:?}");
    // No RTL and no landing before the way home: the route's targets went out as GoTo.
    assert!(!f.commands.contains(&Command::ReturnToLaunch));
    assert!(f.commands.iter().any(|c| matches!(
        c.position_target(),
        Some(([n, e, _], _)) if (n - asked[0][0]).abs() < 1e-9 && (e - 10.0).abs() < 1e-9
    )));
    let Some(Outcome::Failed(Failure::Aborted { reason })) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert!(
        reason.contains("--failsafe return") && reason.contains("flew the planned way home"),
        "{reason}"
    );
    let s = v.state();
    assert!(s.on_ground && !s.armed, "{s:?}");
    assert!(
        s.position_ned_m[0].hypot(s.position_ned_m[1]) < 1.5,
        "landed at {:?}, not at the launch point",
        s.position_ned_m
    );
    use FlightState::*;
    assert_eq!(
        &f.states[f.states.len() - 3..],
        &[Landing, Disarming, Manual]
    );
}

/// Stopped at speed, the vehicle brakes past the point where it was stopped and comes back: the
/// way home is asked for only once it is at rest there (seen against ArduCopter SITL: asked at
/// once, the way home's first target was "reached" while the vehicle still flew through it, and
/// it skipped on to the second, 23 m further, by a straight line nobody planned).
#[test]
fn the_way_home_is_asked_for_only_once_the_vehicle_is_at_rest_where_it_was_stopped() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let mut stopped: Option<(f64, [f64; 3])> = None;
    let mut asked: Vec<(f64, [f64; 3], f64, [f64; 3])> = Vec::new();
    let vehicle = std::cell::RefCell::new(Vec::new());
    fly_homing(
        &mut ex,
        &mut v,
        300.0,
        |t, v| {
            let s = v.state();
            vehicle
                .borrow_mut()
                .push((s.position_ned_m, s.velocity_ned_m_s));
            let speed = s.velocity_ned_m_s[0].hypot(s.velocity_ned_m_s[1]);
            (stopped.is_none() && t > 8.0 && speed > 3.0).then(|| {
                stopped = Some((speed, s.position_ned_m));
                Event::Stop {
                    reason: "interrupted by Ctrl-C".into(),
                    action: FailsafeAction::Return,
                }
            })
        },
        |ex, t, from| {
            let (at, vel) = *vehicle.borrow().last().unwrap();
            asked.push((t, from, vel[0].hypot(vel[1]), at));
            Some(ex.return_home(t, &dogleg_home(from)).unwrap())
        },
    );
    let (speed, at_stop) = stopped.expect("stopped at speed");
    assert!(speed > 3.0);
    assert_eq!(asked.len(), 1, "{asked:?}");
    let (_, from, speed_then, at) = asked[0];
    // Asked from where it was stopped, with the vehicle at rest there.
    assert!(
        (from[0] - at_stop[0]).hypot(from[1] - at_stop[1]) < 0.5,
        "{from:?} vs {at_stop:?}"
    );
    assert!(speed_then < 0.5, "asked while moving at {speed_then} m/s");
    assert!(
        (at[0] - from[0]).hypot(at[1] - from[1]) <= 1.0,
        "{at:?} vs {from:?}"
    );
    let s = v.state();
    assert!(
        s.on_ground && s.position_ned_m[0].hypot(s.position_ned_m[1]) < 1.5,
        "{s:?}"
    );
}

#[test]
fn ctrl_c_return_without_a_way_home_lands_where_the_vehicle_is() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let mut stopped_at = None;
    fly_homing(
        &mut ex,
        &mut v,
        300.0,
        |t, v| {
            (t > 12.0 && stopped_at.is_none()).then(|| {
                stopped_at = Some(v.state().position_ned_m);
                Event::Stop {
                    reason: "interrupted by Ctrl-C".into(),
                    action: FailsafeAction::Return,
                }
            })
        },
        |ex, t, _| Some(ex.no_way_home(t, "the start is inside an obstacle".into())),
    );
    let Some(Outcome::Failed(Failure::Aborted { reason })) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert!(
        reason.contains("no way home (the start is inside an obstacle): landed where it was"),
        "{reason}"
    );
    let (s, at) = (v.state(), stopped_at.unwrap());
    assert!(s.on_ground && !s.armed);
    assert!(
        (s.position_ned_m[0] - at[0]).hypot(s.position_ned_m[1] - at[1]) < 3.0,
        "landed at {:?}, stopped at {at:?}",
        s.position_ned_m
    );
}

#[test]
fn a_way_home_that_never_comes_ends_in_a_landing_after_the_hold() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let mut stop_t = None;
    fly(&mut ex, &mut v, 300.0, |t, _| {
        (t > 12.0 && stop_t.is_none()).then(|| {
            stop_t = Some(t);
            Event::Stop {
                reason: "interrupted by Ctrl-C".into(),
                action: FailsafeAction::Return,
            }
        })
    });
    let Some(Outcome::Failed(Failure::Aborted { reason })) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert!(reason.contains("no way home came within"), "{reason}");
    // A second request is refused: the flight is over.
    assert!(ex.way_home_wanted().is_none());
    assert!(
        ex.return_home(400.0, &dogleg_home([0.0, 0.0, -5.0]))
            .is_err()
    );
}

#[test]
fn return_home_is_refused_unless_the_way_home_is_wanted() {
    let (mut ex, _) = at_waypoint_state();
    assert!(ex.way_home_wanted().is_none());
    let err = ex
        .return_home(1.0, &dogleg_home([5.0, 0.0, -5.0]))
        .unwrap_err();
    assert!(err.to_string().contains("no way home is wanted"), "{err}");
}
