//! Missions shared by the integration tests.
#![allow(dead_code)]

use skyplan_frames::{Lla, LocalFrame};
use skyplan_mission::{Mission, Waypoint};

/// A home in San Francisco: latitude and longitude differ obviously (37.8 vs −122.4).
pub fn home() -> Lla {
    Lla {
        lat_deg: 37.792480,
        lon_deg: -122.397450,
        alt_m: 12.5,
    }
}

/// Four waypoints; headings 0, 0, 90° and about −155° (a negative heading, to check yaw wrapping).
pub fn sample() -> Mission {
    let frame = LocalFrame::new(home()).expect("valid home");
    let points = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (-5.25, 3.0)];
    let mission = Mission::from_points_ne(&frame, &points, 5.0, 0.0).expect("valid points");
    assert!(mission.waypoints[3].heading_rad < 0.0);
    mission
}

/// A mission with one waypoint.
pub fn single() -> Mission {
    Mission {
        home: home(),
        waypoints: vec![Waypoint {
            north_m: 1.0,
            east_m: 2.0,
            alt_m: 3.0,
            heading_rad: 0.5,
            lat_deg: 37.79249,
            lon_deg: -122.39743,
        }],
    }
}

/// A mission with no waypoints.
pub fn empty() -> Mission {
    Mission {
        home: home(),
        waypoints: Vec::new(),
    }
}

/// Parses encoder output as JSON.
pub fn parse(text: &str) -> serde_json::Value {
    serde_json::from_str(text).expect("output is valid JSON")
}

/// `a` and `b` agree to within a few ULPs (serde_json's default float parsing is not
/// guaranteed to be correctly rounded).
pub fn assert_close(a: f64, b: f64) {
    assert!(
        (a - b).abs() <= 4.0 * f64::EPSILON * a.abs().max(b.abs()),
        "{a} != {b}"
    );
}

/// A JSON number as f64.
pub fn num(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}
