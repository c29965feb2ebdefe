//! A planned mission as a vehicle gets it (`skyplan fly --upload`): MISSION_ITEM_INTs for its
//! autopilot, headings turned from the map's grid north to true north.

use skyplan_flight::executor::ConfigError;
use skyplan_flight::upload::{GlobalWaypoint, LegPace, MissionPlan, paced_mission_items};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_link::ground::{Autopilot, VehicleInfo, grid_convergence_rad};
use skyplan_mission::Mission;
use skyplan_plan::trajectory::Trajectory;

/// The items to upload for `mission` to this vehicle: ArduPilot gets its home as item 0 (PX4
/// has none) and a CONDITION_YAW before each waypoint (ArduCopter ignores NAV_WAYPOINT's yaw).
/// The plan's headings are from the map's grid north; the vehicle's are from true north. With
/// `pace` (one per waypoint, [`trajectory_pace`]) each waypoint gets a DO_CHANGE_SPEED before it
/// and its acceptance radius.
pub fn items_for(
    mission: &Mission,
    frame: &LocalFrame,
    vehicle: &VehicleInfo,
    pace: Option<&[LegPace]>,
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
    let condition_yaw = vehicle.autopilot == Autopilot::ArduPilot;
    paced_mission_items(&waypoints, home, condition_yaw, pace)
}

/// The slowest speed a paced leg is given, m/s (a vertical leg has no ground speed to keep).
pub const MIN_LEG_SPEED_M_S: f64 = 0.5;

/// The smallest acceptance radius given, metres.
pub const MIN_ACCEPTANCE_RADIUS_M: f64 = 0.5;

/// What an uploaded mission keeps of a trajectory through the mission's waypoints: each leg's
/// speed is the highest ground speed the trajectory reaches on it (at least
/// [`MIN_LEG_SPEED_M_S`]; the first waypoint, where the flight starts, gets the first leg's), and
/// each waypoint's acceptance radius is how far the trajectory rounds it, at least
/// [`MIN_ACCEPTANCE_RADIUS_M`] and at most half the margin: a vehicle that turns for the next
/// waypoint within `r` of this one stays within `r` of the legs, which are clear by the margin.
pub fn trajectory_pace(trajectory: &Trajectory, mission: &Mission, safety_m: f64) -> Vec<LegPace> {
    let route: Vec<[f64; 3]> = (mission.waypoints.iter())
        .map(|w| [w.north_m, w.east_m, w.alt_m])
        .collect();
    let passes = trajectory.passes(&route);
    let max_radius_m = (safety_m / 2.0).max(MIN_ACCEPTANCE_RADIUS_M);
    let speed = |k: usize| {
        passes.get(k).map_or(MIN_LEG_SPEED_M_S, |p| {
            p.peak_ground_speed_m_s.max(MIN_LEG_SPEED_M_S)
        })
    };
    (passes.iter().enumerate())
        .map(|(k, p)| LegPace {
            // Down to 0.1 (never above the limit the trajectory keeps).
            speed_m_s: (speed(k.max(1)) * 10.0).floor() / 10.0,
            acceptance_radius_m: (p.miss_m.clamp(MIN_ACCEPTANCE_RADIUS_M, max_radius_m) * 10.0)
                .floor()
                / 10.0,
        })
        .collect()
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
