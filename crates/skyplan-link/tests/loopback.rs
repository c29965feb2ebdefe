//! The ground station flies the simulator over a real loopback TCP socket.

use skyplan_flight::executor::{
    ExecutorConfig, FailsafeAction, FlightState, MissionExecutor, Note, Outcome, Target, Telemetry,
};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_link::ground::{GroundConfig, GroundStation, Update};
use skyplan_link::in_process::InProcessSim;
use skyplan_link::vehicle::{SimNote, SimServerConfig};
use std::time::Duration;

const HOME: Lla = Lla {
    lat_deg: 37.792480,
    lon_deg: -122.397450,
    alt_m: 0.0,
};

fn route() -> Vec<Target> {
    let wp = |n: f64, e: f64, h: f64| Target {
        north_m: n,
        east_m: e,
        alt_m: 5.0,
        heading_rad: h.to_radians(),
    };
    vec![wp(0.0, 0.0, 0.0), wp(20.0, 0.0, 0.0), wp(20.0, 15.0, 90.0)]
}

struct Run {
    outcome: Option<Outcome>,
    states: Vec<FlightState>,
    sim_notes: Vec<SimNote>,
    reached: usize,
    last: Option<Telemetry>,
}

fn fly(config: SimServerConfig, ground: GroundConfig) -> Run {
    fly_route(config, ground, &route(), None)
}

/// Flies `targets`; with `interrupt_at`, Ctrl-C (the interrupt flag) once that waypoint is
/// reached.
fn fly_route(
    config: SimServerConfig,
    ground: GroundConfig,
    targets: &[Target],
    interrupt_at: Option<usize>,
) -> Run {
    let sim = InProcessSim::start(config, None).unwrap();
    let mut gcs = GroundStation::connect(&sim.address(), ground).unwrap();
    let interrupt = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    gcs.set_interrupt(interrupt.clone());
    let info = gcs
        .wait_for_vehicle(Duration::from_secs(10), |_, _| {})
        .unwrap();
    assert!((info.position.lat_deg - HOME.lat_deg).abs() < 1e-6);
    let mut ex = MissionExecutor::new(targets, ExecutorConfig::default()).unwrap();
    let frame = LocalFrame::new(HOME).unwrap();
    let mut states = vec![FlightState::Manual];
    gcs.fly(&mut ex, &frame, |u| {
        if let Update::Notes(_, notes) = u {
            for n in notes {
                match n {
                    Note::State { to, .. } => states.push(to),
                    Note::Reached(r) if Some(r.index) == interrupt_at => {
                        interrupt.store(true, std::sync::atomic::Ordering::SeqCst);
                    }
                    _ => {}
                }
            }
        }
    })
    .unwrap();
    let (report, sim_notes) = sim.finish();
    assert!(report.unwrap().sim_time_s > 0.0);
    Run {
        outcome: ex.outcome().cloned(),
        states,
        sim_notes,
        reached: ex.reached().len(),
        last: ex.last_telemetry().cloned(),
    }
}

/// The simulator at 20× real time, at home.
fn sim_at_20x() -> SimServerConfig {
    SimServerConfig {
        speedup: 20.0,
        ..SimServerConfig::at(HOME)
    }
}

/// A ground station for the simulator at 20×, with a minute to fly.
fn ground_at_20x() -> GroundConfig {
    GroundConfig {
        speedup: 20.0,
        timeout_s: Some(60.0),
        ..GroundConfig::default()
    }
}

#[test]
fn flies_a_short_mission_over_tcp() {
    let run = fly(sim_at_20x(), ground_at_20x());
    assert_eq!(run.outcome, Some(Outcome::Completed), "{:?}", run.sim_notes);
    use FlightState::*;
    assert_eq!(
        run.states,
        vec![
            Manual, Arming, Takeoff, Waypoint, Landing, Disarming, Manual
        ]
    );
    assert_eq!(run.reached, 3);
    assert!(run.sim_notes.contains(&SimNote::Landed));
    assert!(run.sim_notes.contains(&SimNote::Armed(false)));
}

/// Ctrl-C with `on_interrupt` RTL 200 m out: the ground station waits for the return and the
/// touchdown at home (the executor's landing budget grows with the way back), not only its fixed
/// grace after the abort (here 0.2 wall seconds, far shorter than the flight back).
#[test]
fn an_interrupted_return_to_launch_is_awaited_until_the_touchdown_at_home() {
    let ground = GroundConfig {
        abort_grace_s: 0.2,
        on_interrupt: FailsafeAction::ReturnToLaunch,
        ..ground_at_20x()
    };
    let wp = |n: f64| Target {
        north_m: n,
        east_m: 0.0,
        alt_m: 5.0,
        heading_rad: 0.0,
    };
    let targets = [wp(0.0), wp(100.0), wp(200.0), wp(300.0)];
    let run = fly_route(sim_at_20x(), ground, &targets, Some(2));
    let Some(Outcome::Failed(f)) = &run.outcome else {
        panic!("{:?}", run.outcome)
    };
    assert!(f.to_string().contains("interrupted"), "{f}");
    assert!(
        run.sim_notes.contains(&SimNote::Landed),
        "{:?}",
        run.sim_notes
    );
    assert!(run.sim_notes.contains(&SimNote::Armed(false)));
    let last = run.last.unwrap();
    assert!(
        last.north_m.hypot(last.east_m) < 2.0,
        "landed at {last:?}, not home"
    );
    assert_eq!(run.states.last(), Some(&FlightState::Manual));
}

#[test]
fn a_silent_vehicle_is_a_lost_link() {
    let config = SimServerConfig {
        drop_link_after_s: Some(8.0),
        ..sim_at_20x()
    };
    let ground = GroundConfig {
        link_timeout_s: 1.0,
        ..ground_at_20x()
    };
    let run = fly(config, ground);
    let Some(Outcome::Failed(f)) = &run.outcome else {
        panic!("{:?}", run.outcome)
    };
    assert!(f.to_string().contains("link lost"), "{f}");
    assert!(run.sim_notes.contains(&SimNote::LinkDropped));
}

#[test]
fn the_simulator_streams_nothing_until_asked_like_arducopter() {
    use skyplan_link::Link;
    use skyplan_link::mavlink::dialects::common::MavCmd;
    use skyplan_link::messages::command_long;
    let config = SimServerConfig {
        ekf_delay_s: 2.0,
        ..sim_at_20x()
    };
    let sim = InProcessSim::start(config, None).unwrap();
    let address = sim.address();
    let mut link = Link::open(&address, 250, 190).unwrap();
    let names = |link: &mut Link, wall_s: f64| {
        let until = std::time::Instant::now() + Duration::from_secs_f64(wall_s);
        let mut names = std::collections::BTreeSet::new();
        while std::time::Instant::now() < until {
            if let Some(r) = link.recv_timeout(Duration::from_millis(20)) {
                names.insert(skyplan_link::message_name(&r.message));
            }
        }
        names
    };
    // 0.5 s wall = 10 s of vehicle time: heartbeats only, and the proximity sensor's
    // OBSTACLE_DISTANCE (a sensor, or a companion computer, sends it unrequested).
    let first = names(&mut link, 0.5);
    assert_eq!(
        first.into_iter().collect::<Vec<_>>(),
        ["HEARTBEAT", "OBSTACLE_DISTANCE"]
    );
    for (id, us) in [(33.0, 1e5), (49.0, 1e6)] {
        let p = [id, us, 0.0, 0.0, 0.0, 0.0, 0.0];
        link.send(&command_long(
            (1, 1),
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
            p,
        ))
        .unwrap();
    }
    let then = names(&mut link, 0.5);
    for name in [
        "HEARTBEAT",
        "COMMAND_ACK",
        "GLOBAL_POSITION_INT",
        "GPS_GLOBAL_ORIGIN",
    ] {
        assert!(then.contains(name), "{then:?}");
    }
    assert!(
        !then.contains("LOCAL_POSITION_NED") && !then.contains("ATTITUDE"),
        "{then:?}"
    );
    assert!(sim.finish().0.is_some());
}
