//! The ground station flies the simulator over a real loopback TCP socket.

use skyplan_flight::executor::{
    ExecutorConfig, FlightState, MissionExecutor, Note, Outcome, Target,
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
}

fn fly(config: SimServerConfig, ground: GroundConfig) -> Run {
    let sim = InProcessSim::start(config, None).unwrap();
    let mut gcs = GroundStation::connect(&sim.address(), ground).unwrap();
    let info = gcs
        .wait_for_vehicle(Duration::from_secs(10), |_, _| {})
        .unwrap();
    assert!((info.position.lat_deg - HOME.lat_deg).abs() < 1e-6);
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let frame = LocalFrame::new(HOME).unwrap();
    let mut states = vec![FlightState::Manual];
    gcs.fly(&mut ex, &frame, |u| {
        if let Update::Notes(_, notes) = u {
            for n in notes {
                if let Note::State { to, .. } = n {
                    states.push(to);
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
    }
}

#[test]
fn flies_a_short_mission_over_tcp() {
    let config = SimServerConfig {
        speedup: 20.0,
        ..SimServerConfig::at(HOME)
    };
    let ground = GroundConfig {
        speedup: 20.0,
        timeout_s: Some(60.0),
        ..GroundConfig::default()
    };
    let run = fly(config, ground);
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

#[test]
fn a_silent_vehicle_is_a_lost_link() {
    let config = SimServerConfig {
        speedup: 20.0,
        drop_link_after_s: Some(8.0),
        ..SimServerConfig::at(HOME)
    };
    let ground = GroundConfig {
        speedup: 20.0,
        link_timeout_s: 1.0,
        timeout_s: Some(60.0),
        ..GroundConfig::default()
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
        speedup: 20.0,
        ekf_delay_s: 2.0,
        ..SimServerConfig::at(HOME)
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
