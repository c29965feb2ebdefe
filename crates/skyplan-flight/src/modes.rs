//! The one table of autopilot mode numbers (HEARTBEAT's `custom_mode`): ArduCopter's (which the
//! simulator uses too) and PX4's main and sub modes. MAVLink's `common` dialect has no constants
//! for them (ArduPilot's are in its `ardupilotmega` dialect, not compiled here).
//!
//! ```
//! use skyplan_flight::executor::VehicleMode;
//! use skyplan_flight::modes::{arducopter, px4};
//! assert_eq!(arducopter::vehicle_mode(arducopter::GUIDED), VehicleMode::Guided);
//! assert_eq!(px4::vehicle_mode(px4::custom_mode(px4::MAIN_AUTO, px4::SUB_AUTO_RTL)), VehicleMode::ReturnToLaunch);
//! ```

/// ArduCopter's flight modes (`Copter::Mode::Number`).
pub mod arducopter {
    use crate::executor::VehicleMode;

    /// STABILIZE.
    pub const STABILIZE: u32 = 0;
    /// AUTO: flies the uploaded mission.
    pub const AUTO: u32 = 3;
    /// GUIDED: obeys position targets.
    pub const GUIDED: u32 = 4;
    /// LOITER: holds position.
    pub const LOITER: u32 = 5;
    /// RTL: returns to launch.
    pub const RTL: u32 = 6;
    /// LAND.
    pub const LAND: u32 = 9;
    /// BRAKE: stops and holds.
    pub const BRAKE: u32 = 17;
    /// SMART_RTL: returns along the flown path.
    pub const SMART_RTL: u32 = 21;

    /// What an ArduCopter `custom_mode` means to the flight executor.
    pub fn vehicle_mode(custom_mode: u32) -> VehicleMode {
        match custom_mode {
            GUIDED => VehicleMode::Guided,
            AUTO => VehicleMode::Auto,
            LAND => VehicleMode::Land,
            LOITER | BRAKE => VehicleMode::Hold,
            RTL | SMART_RTL => VehicleMode::ReturnToLaunch,
            m => VehicleMode::Other(m),
        }
    }
}

/// PX4's modes: a main mode in `custom_mode` bits 16–23 and a sub mode in bits 24–31.
pub mod px4 {
    use crate::executor::VehicleMode;

    /// AUTO (with a sub mode).
    pub const MAIN_AUTO: u32 = 4;
    /// OFFBOARD: obeys position targets.
    pub const MAIN_OFFBOARD: u32 = 6;
    /// AUTO.LOITER.
    pub const SUB_AUTO_LOITER: u32 = 3;
    /// AUTO.MISSION.
    pub const SUB_AUTO_MISSION: u32 = 4;
    /// AUTO.RTL.
    pub const SUB_AUTO_RTL: u32 = 5;
    /// AUTO.LAND.
    pub const SUB_AUTO_LAND: u32 = 6;

    /// The `custom_mode` of a main and a sub mode.
    pub fn custom_mode(main: u32, sub: u32) -> u32 {
        (main & 0xff) << 16 | (sub & 0xff) << 24
    }

    /// The main mode of a `custom_mode`.
    pub fn main_mode(custom_mode: u32) -> u32 {
        (custom_mode >> 16) & 0xff
    }

    /// What a PX4 `custom_mode` means to the flight executor.
    pub fn vehicle_mode(custom_mode: u32) -> VehicleMode {
        let sub = (custom_mode >> 24) & 0xff;
        match (main_mode(custom_mode), sub) {
            (MAIN_OFFBOARD, _) => VehicleMode::Guided,
            (MAIN_AUTO, SUB_AUTO_MISSION) => VehicleMode::Auto,
            (MAIN_AUTO, SUB_AUTO_LOITER) => VehicleMode::Hold,
            (MAIN_AUTO, SUB_AUTO_RTL) => VehicleMode::ReturnToLaunch,
            (MAIN_AUTO, SUB_AUTO_LAND) => VehicleMode::Land,
            _ => VehicleMode::Other(custom_mode),
        }
    }
}
