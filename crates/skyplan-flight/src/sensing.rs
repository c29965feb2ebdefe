//! What a range sensor sees, and the hook that replans a flight from it (receding horizon).
//!
//! The link layer decodes MAVLink `OBSTACLE_DISTANCE` into an [`ObstacleReading`] (sectors
//! referenced to north, ranges in metres) and hands each one, with the route still to fly, to a
//! [`RouteWatcher`]. The watcher — skyplan-replan's world model and replanner — answers with a
//! [`RouteDecision`]: keep the route, fly a new one from here without landing, or hold.
//!
//! ```
//! use skyplan_flight::sensing::{ObstacleReading, SectorRange};
//!
//! // 72 sectors of 5°, the first centred on north; a wall 12 m due east.
//! let mut ranges = vec![SectorRange::Clear; 72];
//! ranges[18] = SectorRange::Obstacle(12.0);
//! let reading = ObstacleReading {
//!     time_s: 3.0,
//!     position_ned: [0.0, 0.0, -5.0],
//!     velocity_ned_m_s: [0.0; 3],
//!     first_bearing_rad: 0.0,
//!     increment_rad: 5f64.to_radians(),
//!     min_range_m: 0.2,
//!     max_range_m: 30.0,
//!     ranges,
//! };
//! let hits: Vec<[f64; 2]> = reading.hits_ne().collect();
//! assert_eq!(hits.len(), 1);
//! assert!((hits[0][0] - 0.0).abs() < 1e-9 && (hits[0][1] - 12.0).abs() < 1e-9);
//! ```

use crate::executor::Target;

/// What one sector of a reading saw.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SectorRange {
    /// An obstacle this many metres from the vehicle (horizontally).
    Obstacle(f64),
    /// Nothing within the sensor's maximum range.
    Clear,
    /// The sector is not measured (MAVLink's `UINT16_MAX`).
    Unknown,
}

/// One sweep of a horizontal range sensor around the vehicle, decoded and referenced to north.
#[derive(Debug, Clone, PartialEq)]
pub struct ObstacleReading {
    /// Vehicle time of the reading, seconds.
    pub time_s: f64,
    /// Where the vehicle was (north, east, down about home), metres.
    pub position_ned: [f64; 3],
    /// How it was moving then (north, east, down), m/s; zeros when not known.
    pub velocity_ned_m_s: [f64; 3],
    /// Bearing of the centre of sector 0, radians clockwise from north.
    pub first_bearing_rad: f64,
    /// Angular width of each sector, radians.
    pub increment_rad: f64,
    /// Closest range the sensor measures, metres.
    pub min_range_m: f64,
    /// Farthest range the sensor measures, metres.
    pub max_range_m: f64,
    /// One entry per sector, clockwise from sector 0.
    pub ranges: Vec<SectorRange>,
}

impl ObstacleReading {
    /// Bearing of the centre of sector `i`, radians clockwise from north.
    pub fn bearing_rad(&self, i: usize) -> f64 {
        self.first_bearing_rad + self.increment_rad * i as f64
    }

    /// The north/east points where the sensor saw an obstacle, metres about home.
    pub fn hits_ne(&self) -> impl Iterator<Item = [f64; 2]> + '_ {
        self.ranges.iter().enumerate().filter_map(|(i, r)| match r {
            SectorRange::Obstacle(d) => {
                let b = self.bearing_rad(i);
                Some([
                    self.position_ned[0] + d * b.cos(),
                    self.position_ned[1] + d * b.sin(),
                ])
            }
            _ => None,
        })
    }
}

/// One replan, as the flight log and the live view tell it.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplanEvent {
    /// Vehicle time, seconds.
    pub time_s: f64,
    /// Where the vehicle was (north, east, down), metres.
    pub position_ned: [f64; 3],
    /// Why, in the user's words (which learned cells blocked which segment).
    pub reason: String,
    /// The replanner that found the route (`dstar-lite`, `scratch`, `voxel-window`, …).
    pub planner: String,
    /// Wall-clock time the replan took, milliseconds.
    pub latency_ms: f64,
    /// CPU time the replanning thread spent on it, milliseconds (`None`: no thread clock on
    /// this platform). Unlike the latency, it does not grow when the machine is busy.
    pub cpu_ms: Option<f64>,
    /// Search expansions of the replan.
    pub expansions: u64,
    /// Length of the new route from the vehicle to the goal, metres.
    pub route_length_m: f64,
    /// Cells the world model has learned as occupied so far.
    pub learned_cells: usize,
}

/// What a [`RouteWatcher`] decides after a reading.
#[derive(Debug, Clone, PartialEq)]
pub enum RouteDecision {
    /// The route still to fly is clear: go on.
    Keep,
    /// Fly this route instead, from where the vehicle is now, without landing (the last
    /// target is the goal).
    Replace {
        /// The new targets, first one first.
        targets: Vec<Target>,
        /// What happened, for the log.
        event: ReplanEvent,
    },
    /// Nothing can be flown: hold position, then act on the failsafe rules.
    Hold {
        /// Why, in the user's words.
        reason: String,
    },
}

/// Watches the route during the mission and replans it from sensor readings.
///
/// Called by the ground station for every reading while the vehicle flies its waypoints; never
/// during take-off or landing. Implementations must answer quickly (the loop runs at ≥ 10 Hz).
pub trait RouteWatcher {
    /// A new reading; `route` is what is still to be flown (the current target first).
    fn on_reading(&mut self, reading: &ObstacleReading, route: &[Target]) -> RouteDecision;
}

/// Plans the way home in flight: a route from where the vehicle is to its launch point, around
/// the map's obstacles (the interrupt and failsafe action [`FailsafeAction::Return`]).
///
/// Called by the ground station once, when the executor asks for the way home; the vehicle
/// holds its position meanwhile.
///
/// [`FailsafeAction::Return`]: crate::executor::FailsafeAction::Return
pub trait HomeRouter {
    /// The targets from `from_ned` (north, east, down about home, metres) to the launch point,
    /// the last one above it; or why there is none, in the user's words.
    fn route_home(&mut self, from_ned: [f64; 3]) -> Result<WayHome, String>;
}

/// A route home, as a [`HomeRouter`] found it.
#[derive(Debug, Clone, PartialEq)]
pub struct WayHome {
    /// The targets, first one first; the last is above the launch point.
    pub targets: Vec<Target>,
    /// Length of the route from the vehicle, metres (3D).
    pub length_m: f64,
    /// The planner that found it.
    pub planner: String,
}
