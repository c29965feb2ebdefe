//! Hostile messages through the simulator's and the ground station's per-message handling (the
//! harnesses the fuzz targets drive): messages addressed to other systems are not obeyed, and
//! messages from other systems do not move the ground station's idea of its vehicle.

use mavlink::dialects::common::*;
use skyplan_flight::executor::FlightState;
use skyplan_flight::sim::SimMode;
use skyplan_link::ground::fuzzing::GroundHarness;
use skyplan_link::vehicle::fuzzing::SimHarness;

fn command(target_system: u8, command: MavCmd, p: [f32; 7]) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        target_system,
        target_component: 1,
        command,
        confirmation: 0,
        param1: p[0],
        param2: p[1],
        param3: p[2],
        param4: p[3],
        param5: p[4],
        param6: p[5],
        param7: p[6],
    })
}

fn set_mode(target_system: u8, custom_mode: u32) -> MavMessage {
    #[allow(deprecated)]
    MavMessage::SET_MODE(SET_MODE_DATA {
        custom_mode,
        target_system,
        ..Default::default()
    })
}

#[test]
fn the_simulator_obeys_only_messages_addressed_to_it() {
    let mut sim = SimHarness::new();
    // EKF ready after 1 s.
    let _ = sim.handle(MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()), 2.0);
    // Addressed to system 9: ignored (this was obeyed for SET_MODE before).
    let _ = sim.handle(set_mode(9, 4), 0.1);
    assert_eq!(sim.state().mode, SimMode::Stabilize);
    let replies = sim.handle(
        command(
            9,
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ),
        0.1,
    );
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
    let replies = sim.handle(
        command(
            0,
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ),
        0.1,
    );
    assert!(sim.state().armed);
    assert!(replies.iter().any(|m| matches!(
        m,
        MavMessage::COMMAND_ACK(a) if a.result == MavResult::MAV_RESULT_ACCEPTED
    )));
}

fn heartbeat(armed: bool, custom_mode: u32) -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode,
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
        base_mode: if armed {
            MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED | MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        } else {
            MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        },
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

fn position(lat: i32, lon: i32, relative_alt_mm: i32) -> MavMessage {
    MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
        time_boot_ms: 1000,
        lat,
        lon,
        alt: relative_alt_mm,
        relative_alt: relative_alt_mm,
        vx: 0,
        vy: 0,
        vz: 0,
        hdg: 0,
    })
}

#[test]
fn another_system_cannot_drive_the_ground_station() {
    let mut g = GroundHarness::new().unwrap();
    // The vehicle (system 1), on the ground at home, disarmed in GUIDED.
    g.handle(1, 1, heartbeat(false, 4), 0.1);
    g.handle(1, 1, position(377_924_800, -1_223_974_500, 0), 0.1);
    let home = g
        .last_telemetry()
        .expect("the vehicle's own position is telemetry");
    assert!(home.north_m.hypot(home.east_m) < 1.0, "{home:?}");
    // System 42 claims to be armed, 100 m up and 25 km away, and to have reached waypoints.
    for _ in 0..50 {
        g.handle(42, 1, heartbeat(true, 4), 0.1);
        g.handle(42, 1, position(380_000_000, -1_220_000_000, 100_000), 0.1);
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
