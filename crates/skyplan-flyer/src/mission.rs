//! A planned mission as a vehicle gets it (`skyplan fly --upload`): MISSION_ITEM_INTs for its
//! autopilot, headings turned from the map's grid north to true north.

use skyplan_flight::executor::ConfigError;
use skyplan_flight::upload::{GlobalWaypoint, MissionPlan, mission_items};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_link::ground::{Autopilot, VehicleInfo, grid_convergence_rad};
use skyplan_mission::Mission;

/// The items to upload for `mission` to this vehicle: ArduPilot gets its home as item 0 (PX4
/// has none) and a CONDITION_YAW before each waypoint (ArduCopter ignores NAV_WAYPOINT's yaw).
/// The plan's headings are from the map's grid north; the vehicle's are from true north.
pub fn items_for(
    mission: &Mission,
    frame: &LocalFrame,
    vehicle: &VehicleInfo,
) -> Result<MissionPlan, ConfigError> {
    let waypoints: Vec<GlobalWaypoint> = mission
        .waypoints
        .iter()
        .map(|w| {
            let at = Lla {
                lat_deg: w.lat_deg,
                lon_deg: w.lon_deg,
                alt_m: 0.0,
            };
            let convergence_rad = grid_convergence_rad(frame, at).unwrap_or(0.0);
            GlobalWaypoint {
                heading_rad: w.heading_rad + convergence_rad,
                ..GlobalWaypoint::from(w)
            }
        })
        .collect();
    let home = match vehicle.autopilot {
        Autopilot::Px4 => None,
        _ => Some((vehicle.position.lat_deg, vehicle.position.lon_deg)),
    };
    mission_items(&waypoints, home, vehicle.autopilot == Autopilot::ArduPilot)
}

/// One line about the vehicle: system id, autopilot, position, EKF origin.
pub fn vehicle_line(info: &VehicleInfo) -> String {
    format!(
        "system {} ({}) at lat {:.7}, lon {:.7}, {:.2} m above home; {}",
        info.system_id,
        match info.autopilot {
            Autopilot::ArduPilot => "ArduPilot",
            Autopilot::Px4 => "PX4",
            Autopilot::Other => "another autopilot",
        },
        info.position.lat_deg,
        info.position.lon_deg,
        info.position.alt_m,
        match info.ekf_origin {
            Some(o) => format!("EKF origin lat {:.7}, lon {:.7}", o.lat_deg, o.lon_deg),
            None => "no EKF origin reported".to_string(),
        }
    )
}
