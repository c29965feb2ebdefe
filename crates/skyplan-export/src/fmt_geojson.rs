//! GeoJSON (RFC 7946) route.

use geojson::{Feature, FeatureCollection, Geometry, JsonObject, JsonValue};
use skyplan_mission::{Mission, Waypoint};

use crate::{ExportError, Format, check_finite, check_len};

/// A GeoJSON position, `[longitude, latitude]` (RFC 7946 § 3.1.1 order).
fn position(w: &Waypoint) -> [f64; 2] {
    [w.lon_deg, w.lat_deg]
}

fn feature(geometry: Geometry, properties: JsonObject) -> Feature {
    Feature {
        bbox: None,
        geometry: Some(geometry),
        id: None,
        properties: Some(properties),
        foreign_members: None,
    }
}

/// Properties of a start or goal point.
fn point_properties(name: &str, index: usize, w: &Waypoint) -> JsonObject {
    let mut p = JsonObject::new();
    p.insert("name".into(), JsonValue::from(name));
    p.insert("index".into(), JsonValue::from(index));
    p.insert("alt_m".into(), JsonValue::from(w.alt_m));
    p.insert(
        "heading_deg".into(),
        JsonValue::from(w.heading_rad.to_degrees()),
    );
    p
}

/// Encodes a mission as a pretty-printed GeoJSON FeatureCollection (with a trailing newline).
///
/// Positions are `[longitude, latitude]` (RFC 7946 order) without a third coordinate, because
/// RFC 7946 altitudes are above the WGS84 ellipsoid while mission altitudes are above home;
/// altitudes go in the properties instead.
///
/// With two or more waypoints the features are, in order:
/// 1. `"name": "route"`: a LineString through every waypoint, with properties `alt_m` and
///    `heading_deg` (arrays, one entry per vertex), `waypoint_count`, and `home`
///    (`{lat_deg, lon_deg, alt_m}`);
/// 2. `"name": "start"`: a Point at the first waypoint, properties `index`, `alt_m`,
///    `heading_deg`;
/// 3. `"name": "goal"`: the same for the last waypoint.
///
/// A LineString needs two positions, so a one-waypoint mission gives a single `"route"` feature
/// whose geometry is a Point (its `alt_m` and `heading_deg` are still one-entry arrays). An empty
/// mission is an error ([`ExportError::TooFewWaypoints`]).
pub fn to_geojson(mission: &Mission) -> Result<String, ExportError> {
    check_finite(mission)?;
    check_len(Format::GeoJson, mission, 1)?;
    let wps = &mission.waypoints;

    let mut route = JsonObject::new();
    route.insert("name".into(), JsonValue::from("route"));
    route.insert("waypoint_count".into(), JsonValue::from(wps.len()));
    route.insert("alt_m".into(), wps.iter().map(|w| w.alt_m).collect());
    route.insert(
        "heading_deg".into(),
        wps.iter().map(|w| w.heading_rad.to_degrees()).collect(),
    );
    let home = &mission.home;
    route.insert(
        "home".into(),
        serde_json::json!({ "lat_deg": home.lat_deg, "lon_deg": home.lon_deg, "alt_m": home.alt_m }),
    );

    let features = match wps.as_slice() {
        [] => Vec::new(), // excluded by check_len
        [only] => vec![feature(Geometry::new_point(position(only)), route)],
        [first, .., last] => vec![
            feature(Geometry::new_line_string(wps.iter().map(position)), route),
            feature(
                Geometry::new_point(position(first)),
                point_properties("start", 0, first),
            ),
            feature(
                Geometry::new_point(position(last)),
                point_properties("goal", wps.len() - 1, last),
            ),
        ],
    };
    let mut text = serde_json::to_string_pretty(&FeatureCollection::new(features))?;
    text.push('\n');
    Ok(text)
}
