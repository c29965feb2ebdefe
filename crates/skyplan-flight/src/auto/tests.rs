use super::*;
use crate::executor::{FailsafeAction, Note, Outcome};
use crate::sim::{SimConfig, SimEvent, SimMissionItem, SimMode, SimVehicle};
use crate::testkit::{apply, link_gap, mode_of, route, telemetry};

/// ArduPilot's layout: item 0 home, 1 take-off, each waypoint after its CONDITION_YAW, land.
fn layout(n: usize) -> MissionLayout {
    MissionLayout {
        takeoff_seq: 1,
        first_waypoint_seq: 3,
        waypoint_stride: 2,
        land_seq: 2 + 2 * n as u16,
    }
}

fn sim_mission(targets: &[Target]) -> Vec<SimMissionItem> {
    let mut items = vec![
        SimMissionItem::Unsupported,
        SimMissionItem::Takeoff {
            alt_m: targets[0].alt_m,
        },
    ];
    for t in targets {
        items.push(SimMissionItem::Yaw {
            yaw_rad: t.heading_rad,
        });
        items.push(SimMissionItem::Waypoint {
            north_m: t.north_m,
            east_m: t.east_m,
            alt_m: t.alt_m,
        });
    }
    items.push(SimMissionItem::Land);
    items
}

struct Flight {
    states: Vec<FlightState>,
    commands: Vec<Command>,
    end_s: f64,
}

/// Closed loop in simulated time; `lose_reached` drops every MISSION_ITEM_REACHED (progress then
/// comes from MISSION_CURRENT alone); `interfere` may change the vehicle at a time.
fn fly(
    ex: &mut AutoExecutor,
    v: &mut SimVehicle,
    lose_reached: bool,
    mut interfere: impl FnMut(f64, &mut SimVehicle, &mut AutoExecutor) -> Option<Event>,
) -> Flight {
    let mut states = vec![ex.state()];
    let mut commands = Vec::new();
    let mut t = 0.0;
    let mut pending: Vec<Event> = Vec::new();
    let feed = |ex: &mut AutoExecutor,
                t: f64,
                e: Event,
                pending: &mut Vec<Event>,
                v: &mut SimVehicle,
                states: &mut Vec<FlightState>,
                commands: &mut Vec<Command>| {
        let out = ex.handle(t, e);
        for n in &out.notes {
            if let Note::State { to, .. } = n {
                states.push(*to);
            }
        }
        for c in out.commands {
            assert!(
                !matches!(c, Command::GoTo { .. } | Command::Takeoff { .. }),
                "the AUTO executor sent {c:?}"
            );
            commands.push(c);
            pending.extend(apply(v, c));
        }
    };
    while ex.outcome().is_none() && t < 600.0 {
        for _ in 0..5 {
            for e in v.step(0.02) {
                if let SimEvent::MissionItemReached(seq) = e
                    && !lose_reached
                {
                    pending.push(Event::MissionItemReached(seq));
                }
            }
        }
        t += 0.1;
        if let Some(e) = interfere(t, v, ex) {
            pending.push(e);
        }
        let s = v.state();
        pending.push(Event::Mode(mode_of(s.mode)));
        // As ArduPilot (and `skyplan sim`): MISSION_CURRENT in every mode once there is a mission.
        pending.push(Event::MissionCurrent(s.mission_current));
        pending.push(Event::Telemetry(telemetry(v)));
        while !pending.is_empty() {
            let batch: Vec<Event> = std::mem::take(&mut pending);
            for e in batch {
                feed(ex, t, e, &mut pending, v, &mut states, &mut commands);
            }
        }
    }
    Flight {
        states,
        commands,
        end_s: t,
    }
}

fn ready(targets: &[Target]) -> (AutoExecutor, SimVehicle) {
    ready_with(targets, ExecutorConfig::default())
}

fn ready_with(targets: &[Target], config: ExecutorConfig) -> (AutoExecutor, SimVehicle) {
    let ex = AutoExecutor::new(targets, layout(targets.len()), config).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    v.set_mission(sim_mission(targets));
    (ex, v)
}

/// Flies the square route undisturbed, to completion.
fn fly_the_route(lose_reached: bool) -> (AutoExecutor, SimVehicle, Flight) {
    let (mut ex, mut v) = ready(&route());
    let f = fly(&mut ex, &mut v, lose_reached, |_, _, _| None);
    assert_eq!(ex.outcome(), Some(&Outcome::Completed), "{:?}", f.states);
    (ex, v, f)
}

#[test]
fn the_uploaded_mission_is_flown_in_auto_with_every_waypoint_reported() {
    let (ex, v, f) = fly_the_route(false);
    use FlightState::*;
    assert_eq!(
        f.states,
        [
            Manual, Arming, Takeoff, Waypoint, Landing, Disarming, Manual
        ]
    );
    assert_eq!(ex.reached().len(), 4);
    assert!(ex.reached().iter().enumerate().all(|(i, r)| r.index == i));
    // Reported within the simulator's 1 m acceptance radius (3D), facing the planned heading
    // (the CONDITION_YAW before each waypoint; the simulator ignores NAV_WAYPOINT's yaw, as
    // ArduCopter does, and would face the waypoint instead).
    for r in &ex.reached()[1..] {
        assert!(r.horizontal_error_m <= 1.6, "{r:?}");
        assert!(r.heading_error_rad.to_degrees() < 5.0, "{r:?}");
    }
    assert!(ex.reached().windows(2).all(|w| w[0].time_s <= w[1].time_s));
    // GUIDED, arm, start — and nothing after: the vehicle flies, lands and disarms by itself.
    assert_eq!(
        f.commands,
        [Command::TakeControl, Command::Arm, Command::StartMission]
    );
    let s = v.state();
    assert!(!s.armed && s.on_ground);
    assert!((s.position_ned_m[0]).abs() < 1.0 && (s.position_ned_m[1] - 20.0).abs() < 1.0);
    assert!(f.end_s < 120.0, "{}", f.end_s);
    assert_eq!(ex.distance_left_m(), 0.0);
}

#[test]
fn progress_from_mission_current_alone_when_item_reached_is_lost() {
    let (ex, _, _) = fly_the_route(true);
    assert_eq!(ex.reached().len(), 4);
}

#[test]
fn a_pilot_taking_over_mid_mission_fails_with_the_mode() {
    let targets = route();
    let (mut ex, mut v) = ready(&targets);
    fly(&mut ex, &mut v, false, |t, v, _| {
        if t > 12.0 && v.state().mode == SimMode::Auto {
            v.set_mode(SimMode::Loiter);
        }
        None
    });
    let Some(Outcome::Failed(f)) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert_eq!(
        f,
        &Failure::LeftMission {
            state: FlightState::Waypoint,
            mode: VehicleMode::Hold
        }
    );
    assert!(f.to_string().contains("left AUTO for HOLD during WAYPOINT"));
}

#[test]
fn an_abort_lands_and_fails_and_a_lost_link_ends_the_flight() {
    let targets = route();
    let (mut ex, mut v) = ready(&targets);
    let f = fly(&mut ex, &mut v, false, |t, _, _| {
        (t > 15.0 && t < 15.15).then(|| Event::Abort("Ctrl-C".into()))
    });
    assert!(f.commands.contains(&Command::Land));
    assert_eq!(
        ex.outcome(),
        Some(&Outcome::Failed(Failure::Aborted {
            reason: "Ctrl-C".into()
        }))
    );
    assert!(!v.state().armed && v.state().on_ground);

    let (mut ex, mut v) = ready(&targets);
    fly(&mut ex, &mut v, false, |t, _, _| {
        (t > 10.0).then_some(Event::LinkLost { silent_s: 5.0 })
    });
    assert!(matches!(
        ex.outcome(),
        Some(Outcome::Failed(Failure::LinkLost { .. }))
    ));
}

#[test]
fn a_vehicle_that_never_enters_auto_times_out_and_is_told_to_land() {
    let targets = route();
    let (mut ex, mut v) = ready(&targets);
    let mut starts = 0;
    fly(&mut ex, &mut v, false, |_, v, _| {
        // Refuse AUTO: fall back to GUIDED at once.
        if v.state().mode == SimMode::Auto {
            starts += 1;
            v.set_mode(SimMode::Guided);
        }
        None
    });
    let Some(Outcome::Failed(Failure::Timeout { state, detail, .. })) = ex.outcome() else {
        panic!("{:?}", ex.outcome())
    };
    assert_eq!(*state, FlightState::Takeoff);
    assert!(detail.contains("did not enter AUTO"), "{detail}");
    assert!(starts > 10, "StartMission is retried: {starts}");
}

#[test]
fn bad_layouts_are_refused() {
    let targets = route();
    assert!(AutoExecutor::new(&targets, layout(3), ExecutorConfig::default()).is_err());
    assert!(AutoExecutor::new(&[], layout(0), ExecutorConfig::default()).is_err());
    let mut low = route();
    low[0].alt_m = 0.0;
    assert!(AutoExecutor::new(&low, layout(4), ExecutorConfig::default()).is_err());
}

#[test]
fn in_auto_a_returning_link_commands_the_failsafe() {
    let targets = route();
    for (action, command) in [
        (FailsafeAction::Land, Command::Land),
        (FailsafeAction::ReturnToLaunch, Command::ReturnToLaunch),
    ] {
        let config = ExecutorConfig {
            failsafe: Some(action),
            ..ExecutorConfig::default()
        };
        let (mut ex, mut v) = ready_with(&targets, config);
        let f = fly(&mut ex, &mut v, false, |t, _, _| link_gap(t, 12.0, 14.0));
        assert!(f.commands.contains(&command), "{:?}", f.commands);
        let Some(Outcome::Failed(Failure::Aborted { reason })) = ex.outcome() else {
            panic!("{:?}", ex.outcome())
        };
        assert!(reason.contains(&format!("--failsafe {action}")), "{reason}");
        assert!(!v.state().armed && v.state().on_ground);
        assert!(ex.reached().len() < targets.len());
    }
}

#[test]
fn in_auto_ctrl_c_hold_leaves_the_vehicle_loitering() {
    let targets = route();
    let (mut ex, mut v) = ready(&targets);
    let mut sent = false;
    fly(&mut ex, &mut v, false, |t, _, _| {
        (t > 12.0 && !std::mem::replace(&mut sent, true)).then(|| Event::Stop {
            reason: "interrupted by Ctrl-C".into(),
            action: FailsafeAction::Hold,
        })
    });
    assert!(matches!(
        ex.outcome(),
        Some(Outcome::Failed(Failure::Held { .. }))
    ));
    assert_eq!(v.state().mode, SimMode::Loiter);
    assert!(v.state().armed && !v.state().on_ground);
}

#[test]
fn a_hop_at_40_m_lands_in_landing_without_the_land_item_reported() {
    // The land item is reported only at the touchdown (as ArduCopter): LANDING begins at the
    // last waypoint, high up, and its budget covers the whole descent.
    let targets: Vec<Target> = [(0.0, 0.0), (10.0, 0.0)]
        .iter()
        .map(|&(n, e)| Target {
            north_m: n,
            east_m: e,
            alt_m: 40.0,
            heading_rad: 0.0,
        })
        .collect();
    let (mut ex, mut v) = ready(&targets);
    let mut landing_began_at_m = None;
    let f = fly(&mut ex, &mut v, false, |_, v, ex| {
        if landing_began_at_m.is_none() && ex.state() == FlightState::Landing {
            landing_began_at_m = Some(-v.state().position_ned_m[2]);
        }
        None
    });
    assert_eq!(ex.outcome(), Some(&Outcome::Completed), "{:?}", f.states);
    let alt = landing_began_at_m.unwrap();
    assert!(alt > 35.0, "LANDING began at {alt} m");
    assert!(!v.state().armed && v.state().on_ground);
}

#[test]
fn reports_of_no_item_or_of_a_previous_flight_count_for_nothing() {
    // ArduPilot streams MISSION_ITEM_REACHED when asked: 65535 before any item, else the last
    // one reached — perhaps by the previous flight (its land item, 6 here).
    for stale in [u16::MAX, 2 + 2 * 4] {
        let targets = route();
        let (mut ex, mut v) = ready(&targets);
        let f = fly(&mut ex, &mut v, false, |t, v, _| {
            // Repeated until this mission's take-off is reached.
            (v.state().mission_current <= 1 && t < 30.0).then_some(Event::MissionItemReached(stale))
        });
        assert_eq!(
            ex.outcome(),
            Some(&Outcome::Completed),
            "{stale}: {:?}",
            f.states
        );
        for r in &ex.reached()[1..] {
            assert!(r.horizontal_error_m <= 1.6, "{stale}: {r:?}");
        }
    }
}
