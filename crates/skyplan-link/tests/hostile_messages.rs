//! Hostile messages through the simulator's and the ground station's per-message handling (the
//! harnesses the fuzz targets drive): messages addressed to other systems are not obeyed, and
//! messages from other systems do not move the ground station's idea of its vehicle.

use mavlink::dialects::common::*;
use skyplan_flight::executor::FlightState;
use skyplan_flight::sim::SimMode;
use skyplan_link::ground::fuzzing::GroundHarness;
use skyplan_link::messages::{
    command_long, global_position, set_mode, vehicle_heartbeat as heartbeat,
};
use skyplan_link::vehicle::fuzzing::SimHarness;

/// Arm! to `target_system`.
fn arm(target_system: u8) -> MavMessage {
    let p = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    command_long((target_system, 1), MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, p)
}

#[test]
fn the_simulator_obeys_only_messages_addressed_to_it() {
    let mut sim = SimHarness::new();
    // EKF ready after 1 s.
    let _ = sim.handle(MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()), 2.0);
    // Addressed to system 9: ignored (this was obeyed for SET_MODE before).
    let _ = sim.handle(set_mode(9, 4), 0.1);
    assert_eq!(sim.state().mode, SimMode::Stabilize);
    let replies = sim.handle(arm(9), 0.1);
    assert!(!sim.state().armed);
    assert!(
        !replies
            .iter()
            .any(|m| matches!(m, MavMessage::COMMAND_ACK(_))),
        "acked a command for another system"
    );
    // Addressed to us (1) or to everyone (0): obeyed.
    let _ = sim.handle(set_mode(1, 4), 0.1);
    assert_eq!(sim.state().mode, SimMode::Guided);
    let replies = sim.handle(arm(0), 0.1);
    assert!(sim.state().armed);
    assert!(replies.iter().any(|m| matches!(
        m,
        MavMessage::COMMAND_ACK(a) if a.result == MavResult::MAV_RESULT_ACCEPTED
    )));
}

#[test]
fn another_system_cannot_drive_the_ground_station() {
    let mut g = GroundHarness::new().unwrap();
    // The vehicle (system 1), on the ground at home, disarmed in GUIDED.
    g.handle(1, 1, heartbeat(false, 4), 0.1);
    g.handle(
        1,
        1,
        global_position(1000, 377_924_800, -1_223_974_500, 0),
        0.1,
    );
    let home = g
        .last_telemetry()
        .expect("the vehicle's own position is telemetry");
    assert!(home.north_m.hypot(home.east_m) < 1.0, "{home:?}");
    // System 42 claims to be armed, 100 m up and 25 km away, and to have reached waypoints.
    for _ in 0..50 {
        g.handle(42, 1, heartbeat(true, 4), 0.1);
        g.handle(
            42,
            1,
            global_position(1000, 380_000_000, -1_220_000_000, 100_000),
            0.1,
        );
        g.handle(
            42,
            1,
            MavMessage::MISSION_ITEM_REACHED(MISSION_ITEM_REACHED_DATA { seq: 1 }),
            0.1,
        );
    }
    // None of it is taken for the vehicle: the telemetry is still the vehicle's, and the flight
    // has not got past arming (the vehicle never said it was armed).
    let now = g.last_telemetry().unwrap();
    assert!(
        now.north_m.hypot(now.east_m) < 1.0 && now.alt_m() < 1.0,
        "system 42's position was taken for the vehicle's: {now:?}"
    );
    assert!(!now.armed);
    assert!(
        matches!(g.state(), FlightState::Manual | FlightState::Arming),
        "{:?}",
        g.state()
    );
}
