mod common;

use common::{assert_close, num, parse};
use skyplan_export::to_json;

#[test]
fn json_structure_and_values() {
    let mission = common::sample();
    let meta = serde_json::json!({ "planner": "a*", "safety_m": 5 });
    let text = to_json(&mission, &meta).unwrap();
    assert!(text.ends_with("}\n"));
    assert!(text.contains("\n  \"format\""), "pretty-printed");
    let doc = parse(&text);

    assert_eq!(doc["format"], "skyplan-waypoints");
    assert_eq!(doc["version"], 1);
    assert_eq!(
        doc["columns"],
        serde_json::json!(["north_m", "east_m", "alt_m", "heading_rad"])
    );
    assert_eq!(doc["metadata"], meta);
    let home = common::home();
    assert_close(num(&doc["home"]["lat_deg"]), home.lat_deg);
    assert_close(num(&doc["home"]["lon_deg"]), home.lon_deg);
    assert_close(num(&doc["home"]["alt_m"]), home.alt_m);

    let rows = doc["waypoints"].as_array().unwrap();
    let lla = doc["waypoints_lla"].as_array().unwrap();
    assert_eq!(rows.len(), mission.waypoints.len());
    assert_eq!(lla.len(), mission.waypoints.len());
    for ((row, want), (p, w)) in rows
        .iter()
        .zip(mission.rows())
        .zip(lla.iter().zip(&mission.waypoints))
    {
        let row = row.as_array().unwrap();
        assert_eq!(row.len(), 4);
        for (got, want) in row.iter().zip(want) {
            assert_close(num(got), want);
        }
        assert_close(num(&p["lat_deg"]), w.lat_deg);
        assert_close(num(&p["lon_deg"]), w.lon_deg);
        assert_close(num(&p["alt_m"]), w.alt_m);
        assert_close(num(&p["heading_deg"]), w.heading_rad.to_degrees());
    }
    assert_close(num(&lla[2]["heading_deg"]), 90.0);
}

#[test]
fn json_of_empty_mission_has_empty_arrays() {
    let doc = parse(&to_json(&common::empty(), &serde_json::Value::Null).unwrap());
    assert_eq!(doc["waypoints"], serde_json::json!([]));
    assert_eq!(doc["waypoints_lla"], serde_json::json!([]));
    assert!(doc["metadata"].is_null());
}
