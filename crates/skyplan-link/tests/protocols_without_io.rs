//! The ground station's protocol flies the simulator's protocol with no socket, thread or clock:
//! messages are handed from one state machine to the other and time is a number. The same
//! flight as over TCP (loopback.rs), deterministic.

use skyplan_flight::collision::BoxWorld;
use skyplan_flight::executor::{ExecutorConfig, MissionExecutor, Outcome, Target};
use skyplan_flight::flat_earth::FlatEarth;
use skyplan_flight::sim::SimMode;
use skyplan_frames::{Lla, LocalFrame};
use skyplan_link::Received;
use skyplan_link::ground::{FlightLoop, GroundConfig, GroundProtocol, VehicleWait};
use skyplan_link::mavlink::MavHeader;
use skyplan_link::mavlink::dialects::common::MavMessage;
use skyplan_link::vehicle::{SimProtocol, SimServerConfig};
use skyplan_map::colliders::ObstacleBox;

const HOME: Lla = Lla {
    lat_deg: 37.792480,
    lon_deg: -122.397450,
    alt_m: 0.0,
};

/// Wall seconds per turn of the loops.
const DT_S: f64 = 0.01;

/// Messages from the vehicle (system 1, component 1) as the ground station receives them.
fn from_vehicle(messages: Vec<MavMessage>) -> Vec<Received> {
    messages
        .into_iter()
        .map(|message| Received {
            header: MavHeader {
                system_id: 1,
                component_id: 1,
                sequence: 0,
            },
            message,
        })
        .collect()
}

/// The simulator's turn at `t`: its replies to `to_vehicle`, its physics and what it sends
/// unasked.
fn vehicle_turn(sim: &mut SimProtocol, t: f64, to_vehicle: Vec<MavMessage>) -> Vec<Received> {
    let mut out = Vec::new();
    for m in to_vehicle {
        out.extend(sim.handle(t, m));
    }
    out.extend(sim.advance(t));
    out.extend(sim.outbound(t));
    from_vehicle(out)
}

#[test]
fn the_ground_protocol_flies_the_simulator_protocol_without_a_socket() {
    let frame = LocalFrame::new(HOME).unwrap();
    // A tower 2 m east of the last waypoint: approached, never touched.
    let tower = ObstacleBox {
        north_m: 20.0,
        east_m: 8.0,
        up_m: 15.0,
        half_north_m: 2.0,
        half_east_m: 2.0,
        half_up_m: 15.0,
    };
    let world = BoxWorld::new(&[tower]);
    let config = SimServerConfig {
        ekf_delay_s: 1.0,
        gcs_failsafe_s: None,
        ..SimServerConfig::at(HOME)
    };
    let earth = FlatEarth::new(HOME.lat_deg, HOME.lon_deg);
    let mut sim = SimProtocol::new(config, earth, frame, Some(&world));
    let mut ground = GroundProtocol::new();

    // Waiting for the vehicle: heartbeat, then the streams asked for, then a position.
    let mut wait = VehicleWait::new(0.0, 30.0, 0.2);
    let (mut t, mut to_vehicle, mut inbox) = (0.0, Vec::new(), Vec::new());
    let info = loop {
        t += DT_S;
        inbox.extend(vehicle_turn(&mut sim, t, std::mem::take(&mut to_vehicle)));
        let received = (!inbox.is_empty()).then(|| inbox.remove(0));
        let step = wait.step(&mut ground, t, received.as_ref(), None);
        to_vehicle.extend(step.send);
        if let Some(done) = step.done {
            break done.unwrap();
        }
    };
    assert_eq!(info.system_id, 1);
    assert!(
        (info.position.lat_deg - HOME.lat_deg).abs() < 1e-6,
        "{info:?}"
    );
    // The EKF origin comes at half the EKF delay, the position at the delay.
    assert!((1.0..3.0).contains(&t), "{t}");

    // The flight: N 20, then E 4, toward the tower's west face (E 6).
    let wp = |n: f64, e: f64| Target {
        north_m: n,
        east_m: e,
        alt_m: 5.0,
        heading_rad: 0.0,
    };
    let targets = [wp(0.0, 0.0), wp(20.0, 0.0), wp(20.0, 4.0)];
    let mut ex = MissionExecutor::new(&targets, ExecutorConfig::default()).unwrap();
    let mut flight =
        FlightLoop::start(&mut ground, &ex, &frame, GroundConfig::default(), None, t).unwrap();
    while !flight.finished(&ex) && t < 300.0 {
        t += DT_S;
        inbox.extend(vehicle_turn(&mut sim, t, std::mem::take(&mut to_vehicle)));
        let received = (!inbox.is_empty()).then(|| inbox.remove(0));
        to_vehicle.extend(flight.step(&mut ground, &mut ex, t, received.as_ref(), (None, false)));
        let _ = flight.take_updates();
    }
    assert_eq!(
        ex.outcome(),
        Some(&Outcome::Completed),
        "at {t} s: {:?}",
        ex.state()
    );
    assert_eq!(ex.reached().len(), targets.len());
    let end = sim.state();
    assert!(
        !end.armed && end.on_ground && end.mode == SimMode::Land,
        "{end:?}"
    );
    let summary = flight.summary(&ground, t);
    assert!(summary.position_targets_sent >= targets.len());
    assert!(
        summary.heartbeats_received as f64 >= 0.9 * t - 2.0,
        "{}",
        summary.heartbeats_received
    );
    // The simulator's track check: the closest approach is the last waypoint's 2 m (within the
    // vehicle's tracking), no collision.
    let report = sim.report(t);
    assert!(report.track.collision().is_none());
    let closest = report.track.closest().unwrap();
    assert_eq!(closest.box_index, 0);
    assert!((closest.clearance_m - 2.0).abs() < 0.8, "{closest:?}");
}
