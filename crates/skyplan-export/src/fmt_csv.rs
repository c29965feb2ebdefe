//! CSV waypoint table.

use skyplan_mission::{Mission, Waypoint};

use crate::{ExportError, check_finite};

/// The header row written by [`to_csv`].
pub const CSV_HEADER: [&str; 6] = [
    "north_m",
    "east_m",
    "alt_m",
    "heading_rad",
    "lat_deg",
    "lon_deg",
];

/// Encodes a mission as CSV: the header [`CSV_HEADER`], then one row per waypoint.
///
/// Numbers are written with Rust's `Display` for `f64`, the shortest text that parses back to
/// the same value (e.g. `5`, `0.1`, `37.79248`), so a round trip is exact. An empty mission
/// gives the header alone.
pub fn to_csv(mission: &Mission) -> Result<String, ExportError> {
    check_finite(mission)?;
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record(CSV_HEADER)?;
    for w in &mission.waypoints {
        writer.write_record(csv_row(w).iter().map(f64::to_string))?;
    }
    let bytes = writer
        .into_inner()
        .map_err(|e| csv::Error::from(e.into_error()))?;
    // Every field is the ASCII header or a formatted number, so nothing is lossy here.
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// A waypoint's values in [`CSV_HEADER`]'s order.
pub fn csv_row(w: &Waypoint) -> [f64; 6] {
    [
        w.north_m,
        w.east_m,
        w.alt_m,
        w.heading_rad,
        w.lat_deg,
        w.lon_deg,
    ]
}
