//! MAVLink messages built in one place: the ground station's heartbeat and commands, and what a
//! vehicle says (its heartbeat, its position) for tests and fuzz harnesses that play one.

use mavlink::dialects::common::*;
use mavlink::{MavHeader, MavlinkVersion};

/// A COMMAND_LONG to `(system, component)` with its seven parameters.
pub fn command_long(target: (u8, u8), command: MavCmd, p: [f32; 7]) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: p[0],
        param2: p[1],
        param3: p[2],
        param4: p[3],
        param5: p[4],
        param6: p[5],
        param7: p[6],
        command,
        target_system: target.0,
        target_component: target.1,
        confirmation: 0,
    })
}

/// The ground station's heartbeat.
pub fn gcs_heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// An ArduCopter quadrotor's heartbeat in `custom_mode` (4: GUIDED), armed or not.
pub fn vehicle_heartbeat(armed: bool, custom_mode: u32) -> MavMessage {
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

/// SET_MODE to `target_system` in `custom_mode`.
pub fn set_mode(target_system: u8, custom_mode: u32) -> MavMessage {
    #[allow(deprecated)]
    MavMessage::SET_MODE(SET_MODE_DATA {
        custom_mode,
        target_system,
        ..Default::default()
    })
}

/// GLOBAL_POSITION_INT at `time_boot_ms`: lat/lon in 1e-7 degrees, altitude above home in
/// millimetres (also as the altitude above sea level), standing still.
pub fn global_position(time_boot_ms: u32, lat: i32, lon: i32, relative_alt_mm: i32) -> MavMessage {
    MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
        time_boot_ms,
        lat,
        lon,
        alt: relative_alt_mm,
        relative_alt: relative_alt_mm,
        ..Default::default()
    })
}

/// `message` as a MAVLink 2 frame from `(system_id, component 1)`, sequence 0.
pub fn frame_v2(system_id: u8, message: &MavMessage) -> Vec<u8> {
    let mut out = Vec::new();
    let header = MavHeader {
        system_id: u32::from(system_id),
        component_id: 1,
        sequence: 0,
    };
    // Writing to a Vec cannot fail.
    let _ = mavlink::write_versioned_msg(&mut out, MavlinkVersion::V2, header, message);
    out
}
