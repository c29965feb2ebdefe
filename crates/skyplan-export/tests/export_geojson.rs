mod common;

use common::{assert_close, num, parse};
use skyplan_export::to_geojson;

/// Asserts `p` is the `[lon, lat]` position of a waypoint.
fn assert_position(p: &serde_json::Value, w: &skyplan_mission::Waypoint) {
    let p = p.as_array().unwrap();
    assert_eq!(p.len(), 2, "2D positions only");
    assert_close(num(&p[0]), w.lon_deg);
    assert_close(num(&p[1]), w.lat_deg);
}

#[test]
fn geojson_route_is_lon_lat_linestring() {
    let mission = common::sample();
    let doc = parse(&to_geojson(&mission).unwrap());
    assert_eq!(doc["type"], "FeatureCollection");
    let features = doc["features"].as_array().unwrap();
    assert_eq!(features.len(), 3);
    for f in features {
        assert_eq!(f["type"], "Feature");
    }

    let route = &features[0];
    assert_eq!(route["properties"]["name"], "route");
    assert_eq!(route["geometry"]["type"], "LineString");
    let coords = route["geometry"]["coordinates"].as_array().unwrap();
    assert_eq!(coords.len(), mission.waypoints.len());
    for (p, w) in coords.iter().zip(&mission.waypoints) {
        assert_position(p, w);
    }
    // Longitude first: San Francisco is near (−122.4, 37.8).
    assert!(num(&coords[0][0]) < -122.0 && num(&coords[0][1]) > 37.0);
    let alts: Vec<f64> = route["properties"]["alt_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(num)
        .collect();
    assert_eq!(alts, vec![5.0; 4]);
    assert_eq!(route["properties"]["waypoint_count"], 4);
    assert_close(num(&route["properties"]["heading_deg"][2]), 90.0);
    assert_close(
        num(&route["properties"]["home"]["lat_deg"]),
        common::home().lat_deg,
    );

    let (start, goal) = (&features[1], &features[2]);
    assert_eq!(start["properties"]["name"], "start");
    assert_eq!(start["properties"]["index"], 0);
    assert_eq!(start["geometry"]["type"], "Point");
    assert_position(&start["geometry"]["coordinates"], &mission.waypoints[0]);
    assert_eq!(goal["properties"]["name"], "goal");
    assert_eq!(goal["properties"]["index"], 3);
    assert_eq!(num(&goal["properties"]["alt_m"]), 5.0);
    assert_position(&goal["geometry"]["coordinates"], &mission.waypoints[3]);
}

#[test]
fn geojson_single_waypoint_is_a_point() {
    let mission = common::single();
    let doc = parse(&to_geojson(&mission).unwrap());
    let features = doc["features"].as_array().unwrap();
    assert_eq!(features.len(), 1);
    assert_eq!(features[0]["properties"]["name"], "route");
    assert_eq!(features[0]["geometry"]["type"], "Point");
    assert_position(
        &features[0]["geometry"]["coordinates"],
        &mission.waypoints[0],
    );
    assert_eq!(features[0]["properties"]["alt_m"], serde_json::json!([3.0]));
}

#[test]
fn geojson_parses_with_the_geojson_crate() {
    let text = to_geojson(&common::sample()).unwrap();
    let parsed: geojson::GeoJson = text.parse().unwrap();
    let geojson::GeoJson::FeatureCollection(fc) = parsed else {
        panic!("not a FeatureCollection")
    };
    assert_eq!(fc.features.len(), 3);
}
