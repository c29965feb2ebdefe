//! Missions for skyplan: waypoints `[north, east, altitude, heading]` in the local frame, each
//! also carrying its latitude and longitude.
//!
//! Headings follow FCND: waypoint *k* faces `atan2(Δeast, Δnorth)` from waypoint *k − 1*; the
//! first waypoint keeps the start heading.
//!
//! ```
//! use skyplan_frames::{LocalFrame, Lla};
//! use skyplan_mission::Mission;
//! let frame = LocalFrame::new(Lla { lat_deg: 37.792480, lon_deg: -122.397450, alt_m: 0.0 })?;
//! let mission = Mission::from_points_ne(&frame, &[(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)], 5.0, 0.0)?;
//! let rows = mission.rows();
//! assert_eq!(rows[1], [10.0, 0.0, 5.0, 0.0]);
//! assert!((rows[2][3] - std::f64::consts::FRAC_PI_2).abs() < 1e-12); // facing east
//! assert!((mission.waypoints[1].lat_deg - 37.79257).abs() < 1e-5);
//! # Ok::<(), skyplan_frames::FrameError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use serde::Serialize;
use skyplan_frames::{FrameError, Lla, LocalFrame, Ned};

/// One waypoint of a mission.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Waypoint {
    /// Metres north of home.
    pub north_m: f64,
    /// Metres east of home.
    pub east_m: f64,
    /// Altitude above home, metres (positive up).
    pub alt_m: f64,
    /// Heading, radians clockwise from north (`atan2(Δeast, Δnorth)`), in (−π, π].
    pub heading_rad: f64,
    /// Latitude, degrees (WGS84).
    pub lat_deg: f64,
    /// Longitude, degrees (WGS84).
    pub lon_deg: f64,
}

/// A list of waypoints about a geodetic home.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mission {
    /// The home the local coordinates are about.
    pub home: Lla,
    /// The waypoints, in flight order.
    pub waypoints: Vec<Waypoint>,
}

/// FCND heading from one point to the next, radians clockwise from north.
///
/// ```
/// let h = skyplan_mission::heading_rad((0.0, 0.0), (-1.0, -1.0));
/// assert!((h + 3.0 * std::f64::consts::FRAC_PI_4).abs() < 1e-12);
/// ```
pub fn heading_rad(from_ne: (f64, f64), to_ne: (f64, f64)) -> f64 {
    (to_ne.1 - from_ne.1).atan2(to_ne.0 - from_ne.0)
}

impl Mission {
    /// Builds a mission at a constant altitude from local (north, east) points.
    ///
    /// A waypoint repeating its predecessor's position keeps the predecessor's heading.
    pub fn from_points_ne(
        frame: &LocalFrame,
        points_ne: &[(f64, f64)],
        alt_m: f64,
        start_heading_rad: f64,
    ) -> Result<Self, FrameError> {
        let points: Vec<[f64; 3]> = points_ne
            .iter()
            .map(|&(north_m, east_m)| [north_m, east_m, alt_m])
            .collect();
        Self::from_points_nea(frame, &points, start_heading_rad)
    }

    /// Builds a mission from local `[north_m, east_m, alt_m]` points, each with its own
    /// altitude (3D routes).
    ///
    /// Headings follow the horizontal motion; a waypoint straight above or below its
    /// predecessor keeps the predecessor's heading.
    ///
    /// ```
    /// use skyplan_frames::{LocalFrame, Lla};
    /// use skyplan_mission::Mission;
    /// let frame = LocalFrame::new(Lla { lat_deg: 37.792480, lon_deg: -122.397450, alt_m: 0.0 })?;
    /// let m = Mission::from_points_nea(&frame, &[[0.0, 0.0, 5.0], [0.0, 10.0, 5.0], [0.0, 10.0, 40.0]], 0.0)?;
    /// assert_eq!(m.rows()[2], [0.0, 10.0, 40.0, std::f64::consts::FRAC_PI_2]); // climbing keeps east
    /// assert!((m.length_3d_m() - 45.0).abs() < 1e-12);
    /// # Ok::<(), skyplan_frames::FrameError>(())
    /// ```
    pub fn from_points_nea(
        frame: &LocalFrame,
        points_nea: &[[f64; 3]],
        start_heading_rad: f64,
    ) -> Result<Self, FrameError> {
        let mut waypoints = Vec::with_capacity(points_nea.len());
        let mut heading = start_heading_rad;
        for (k, &[north_m, east_m, alt_m]) in points_nea.iter().enumerate() {
            if k > 0 {
                let [pn, pe, _] = points_nea[k - 1];
                if (pn, pe) != (north_m, east_m) {
                    heading = heading_rad((pn, pe), (north_m, east_m));
                }
            }
            let lla = frame.lla_from_ned(Ned {
                north_m,
                east_m,
                down_m: -alt_m,
            })?;
            waypoints.push(Waypoint {
                north_m,
                east_m,
                alt_m,
                heading_rad: heading,
                lat_deg: lla.lat_deg,
                lon_deg: lla.lon_deg,
            });
        }
        Ok(Self {
            home: frame.home(),
            waypoints,
        })
    }

    /// Length of the route in 3D (climbs included), metres.
    pub fn length_3d_m(&self) -> f64 {
        self.waypoints
            .windows(2)
            .map(|w| {
                let (dn, de, da) = (
                    w[1].north_m - w[0].north_m,
                    w[1].east_m - w[0].east_m,
                    w[1].alt_m - w[0].alt_m,
                );
                (dn * dn + de * de + da * da).sqrt()
            })
            .sum()
    }

    /// The FCND rows `[north, east, altitude, heading]`.
    pub fn rows(&self) -> Vec<[f64; 4]> {
        self.waypoints
            .iter()
            .map(|w| [w.north_m, w.east_m, w.alt_m, w.heading_rad])
            .collect()
    }

    /// Horizontal length of the route, metres.
    pub fn length_m(&self) -> f64 {
        self.waypoints
            .windows(2)
            .map(|w| (w[1].north_m - w[0].north_m).hypot(w[1].east_m - w[0].east_m))
            .sum()
    }
}
