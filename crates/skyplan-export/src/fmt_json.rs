//! skyplan's JSON waypoint document.

use serde::Serialize;
use skyplan_mission::Mission;

use crate::{ExportError, check_finite};

/// The `"format"` member of a skyplan JSON document.
pub const JSON_FORMAT_ID: &str = "skyplan-waypoints";

/// The `"version"` member of a skyplan JSON document.
pub const JSON_FORMAT_VERSION: u32 = 1;

/// The `"columns"` member of a skyplan JSON document: the meaning of each `"waypoints"` row.
pub const JSON_COLUMNS: [&str; 4] = ["north_m", "east_m", "alt_m", "heading_rad"];

#[derive(Serialize)]
struct Document<'a> {
    format: &'static str,
    version: u32,
    home: Home,
    columns: [&'static str; 4],
    waypoints: Vec<[f64; 4]>,
    waypoints_lla: Vec<WaypointLla>,
    metadata: &'a serde_json::Value,
}

#[derive(Serialize)]
struct Home {
    lat_deg: f64,
    lon_deg: f64,
    alt_m: f64,
}

#[derive(Serialize)]
struct WaypointLla {
    lat_deg: f64,
    lon_deg: f64,
    alt_m: f64,
    heading_deg: f64,
}

/// Encodes a mission as skyplan's pretty-printed JSON document (with a trailing newline):
///
/// ```json
/// {
///   "format": "skyplan-waypoints",
///   "version": 1,
///   "home": { "lat_deg": …, "lon_deg": …, "alt_m": … },
///   "columns": ["north_m", "east_m", "alt_m", "heading_rad"],
///   "waypoints": [[north, east, alt, heading], …],
///   "waypoints_lla": [{ "lat_deg": …, "lon_deg": …, "alt_m": …, "heading_deg": … }, …],
///   "metadata": <metadata>
/// }
/// ```
///
/// `"waypoints"` holds the FCND rows of [`Mission::rows`]. In `"waypoints_lla"`, `alt_m` is
/// above home (as in the rows) and `heading_deg` is `heading_rad` in degrees, clockwise from
/// north. An empty mission gives empty arrays.
pub fn to_json(mission: &Mission, metadata: &serde_json::Value) -> Result<String, ExportError> {
    check_finite(mission)?;
    let home = &mission.home;
    let doc = Document {
        format: JSON_FORMAT_ID,
        version: JSON_FORMAT_VERSION,
        home: Home {
            lat_deg: home.lat_deg,
            lon_deg: home.lon_deg,
            alt_m: home.alt_m,
        },
        columns: JSON_COLUMNS,
        waypoints: mission.rows(),
        waypoints_lla: mission
            .waypoints
            .iter()
            .map(|w| WaypointLla {
                lat_deg: w.lat_deg,
                lon_deg: w.lon_deg,
                alt_m: w.alt_m,
                heading_deg: w.heading_rad.to_degrees(),
            })
            .collect(),
        metadata,
    };
    let mut text = serde_json::to_string_pretty(&doc)?;
    text.push('\n');
    Ok(text)
}
