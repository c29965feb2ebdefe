mod common;

use common::{assert_close, num, parse};
use serde_json::json;
use skyplan_export::{FenceCircle, FencePolygon, GeoFence, QgcPlanOptions, mavlink, to_qgc_plan};

fn plan(mission: &skyplan_mission::Mission) -> serde_json::Value {
    parse(&to_qgc_plan(mission, &QgcPlanOptions::default()).unwrap())
}

#[test]
fn plan_top_level_fields() {
    let doc = plan(&common::sample());
    assert_eq!(doc["fileType"], "Plan");
    assert_eq!(doc["version"], 1);
    assert_eq!(doc["groundStation"], "QGroundControl");
    assert_eq!(
        doc["geoFence"],
        json!({ "circles": [], "polygons": [], "version": 2 })
    );
    assert_eq!(doc["rallyPoints"], json!({ "points": [], "version": 2 }));

    let m = &doc["mission"];
    assert_eq!(m["version"], 2);
    assert_eq!(m["firmwareType"], 12);
    assert_eq!(m["vehicleType"], 2);
    assert_eq!(m["globalPlanAltitudeMode"], 1);
    assert_eq!(num(&m["cruiseSpeed"]), 15.0);
    assert_eq!(num(&m["hoverSpeed"]), 5.0);
    let home = common::home();
    let planned = m["plannedHomePosition"].as_array().unwrap();
    assert_eq!(planned.len(), 3);
    assert_close(num(&planned[0]), home.lat_deg);
    assert_close(num(&planned[1]), home.lon_deg);
    assert_close(num(&planned[2]), home.alt_m);
}

#[test]
fn plan_items_takeoff_waypoints_land() {
    let mission = common::sample();
    let wps = &mission.waypoints;
    let doc = plan(&mission);
    let items = doc["mission"]["items"].as_array().unwrap();
    assert_eq!(items.len(), wps.len() + 1);

    let commands: Vec<u64> = items
        .iter()
        .map(|i| i["command"].as_u64().unwrap())
        .collect();
    assert_eq!(commands, [22, 16, 16, 16, 21]);

    for (k, item) in items.iter().enumerate() {
        assert_eq!(item["type"], "SimpleItem");
        assert_eq!(item["doJumpId"], k + 1);
        assert_eq!(item["frame"], 3);
        assert_eq!(item["autoContinue"], true);
        assert_eq!(item["AltitudeMode"], 1);
        assert!(item["AMSLAltAboveTerrain"].is_null());
        assert!(
            item.as_object()
                .unwrap()
                .contains_key("AMSLAltAboveTerrain")
        );
        assert_eq!(item["params"].as_array().unwrap().len(), 7);
    }

    // Takeoff at the first waypoint, to its altitude; yaw param null.
    let takeoff = items[0]["params"].as_array().unwrap();
    assert_eq!(
        takeoff[0..4],
        [json!(0), json!(0), json!(0), json!(null)][..]
    );
    assert_close(num(&takeoff[4]), wps[0].lat_deg);
    assert_close(num(&takeoff[5]), wps[0].lon_deg);
    assert_eq!(num(&takeoff[6]), 5.0);
    assert_eq!(num(&items[0]["Altitude"]), 5.0);

    // Waypoints 1.. with yaw in degrees in [0, 360).
    let want_yaw = [0.0, 90.0, wps[3].heading_rad.to_degrees() + 360.0];
    for (k, yaw) in (1..wps.len()).zip(want_yaw) {
        let p = items[k]["params"].as_array().unwrap();
        assert_eq!(p[0..3], [json!(0), json!(0), json!(0)]);
        assert_close(num(&p[3]), yaw);
        assert!((0.0..360.0).contains(&num(&p[3])));
        assert_close(num(&p[4]), wps[k].lat_deg);
        assert_close(num(&p[5]), wps[k].lon_deg);
        assert_eq!(num(&p[6]), wps[k].alt_m);
        assert_eq!(num(&items[k]["Altitude"]), wps[k].alt_m);
    }
    // The last heading is about −155°, so about 205° once wrapped.
    assert!(
        (num(&items[3]["params"][3]) - 204.65).abs() < 0.01,
        "{}",
        items[3]["params"][3]
    );

    // Land at the last waypoint.
    let land = items[4]["params"].as_array().unwrap();
    assert_eq!(land[0..4], [json!(0), json!(0), json!(0), json!(null)][..]);
    assert_close(num(&land[4]), wps[3].lat_deg);
    assert_close(num(&land[5]), wps[3].lon_deg);
    assert_eq!(num(&land[6]), 0.0);
}

#[test]
fn plan_lat_lon_order() {
    // Latitude (param 5) and longitude (param 6) differ obviously: 37.8 vs −122.4.
    let doc = plan(&common::sample());
    let p = &doc["mission"]["items"][1]["params"];
    assert!(num(&p[4]) > 37.0 && num(&p[5]) < -122.0);
}

#[test]
fn plan_single_waypoint_is_takeoff_then_land() {
    let doc = plan(&common::single());
    let items = doc["mission"]["items"].as_array().unwrap();
    let commands: Vec<u64> = items
        .iter()
        .map(|i| i["command"].as_u64().unwrap())
        .collect();
    assert_eq!(
        commands,
        [
            u64::from(mavlink::MAV_CMD_NAV_TAKEOFF),
            u64::from(mavlink::MAV_CMD_NAV_LAND)
        ]
    );
}

#[test]
fn plan_options_are_written() {
    let options = QgcPlanOptions {
        cruise_speed_m_s: 8.5,
        hover_speed_m_s: 3.0,
        firmware_type: mavlink::MAV_AUTOPILOT_ARDUPILOTMEGA,
        vehicle_type: mavlink::MAV_TYPE_QUADROTOR,
        geo_fence: GeoFence::default(),
        home_amsl_m: None,
    };
    let doc = parse(&to_qgc_plan(&common::sample(), &options).unwrap());
    assert_eq!(num(&doc["mission"]["cruiseSpeed"]), 8.5);
    assert_eq!(num(&doc["mission"]["hoverSpeed"]), 3.0);
    assert_eq!(doc["mission"]["firmwareType"], 3);
    assert_eq!(
        doc["geoFence"],
        serde_json::json!({"circles": [], "polygons": [], "version": 2})
    );
}

/// The geoFence as QGroundControl writes it (`QGCFencePolygon` / `QGCFenceCircle::saveToJson`:
/// `polygon` of `[lat, lon]`, `circle.center` `[lat, lon]`, `circle.radius`, `inclusion`,
/// item version 1, fence version 2); a bad radius or a two-vertex polygon is refused.
#[test]
fn geofence_is_written_in_qgroundcontrols_layout() {
    let fence = GeoFence {
        polygons: vec![FencePolygon {
            inclusion: true,
            vertices_lat_lon_deg: vec![[37.79, -122.40], [37.80, -122.40], [37.80, -122.39]],
        }],
        circles: vec![FenceCircle {
            inclusion: false,
            centre_lat_lon_deg: [37.795, -122.395],
            radius_m: 30.5,
        }],
    };
    let options = QgcPlanOptions {
        geo_fence: fence.clone(),
        ..QgcPlanOptions::default()
    };
    let doc = parse(&to_qgc_plan(&common::sample(), &options).unwrap());
    assert_eq!(
        doc["geoFence"],
        serde_json::json!({
            "circles": [{"circle": {"center": [37.795, -122.395], "radius": 30.5}, "inclusion": false, "version": 1}],
            "polygons": [{"inclusion": true, "polygon": [[37.79, -122.40], [37.80, -122.40], [37.80, -122.39]], "version": 1}],
            "version": 2
        })
    );
    let mut bad = options.clone();
    bad.geo_fence.circles[0].radius_m = 0.0;
    assert!(to_qgc_plan(&common::sample(), &bad).is_err());
    let mut bad = options;
    bad.geo_fence.polygons[0].vertices_lat_lon_deg.pop();
    assert!(to_qgc_plan(&common::sample(), &bad).is_err());
}

/// With the home's height above mean sea level (a plan over a DEM), the takeoff and the
/// waypoints go in MAV_FRAME_GLOBAL at the mission's altitudes plus that height (QGroundControl's
/// AltitudeMode 2), the landing stays relative, the plan's mode is mixed and its home at that
/// height; a height that is not finite is refused.
#[test]
fn altitudes_above_mean_sea_level_go_in_the_global_frame() {
    let mission = common::sample();
    let options = QgcPlanOptions {
        home_amsl_m: Some(312.5),
        ..QgcPlanOptions::default()
    };
    let doc = parse(&to_qgc_plan(&mission, &options).unwrap());
    assert_eq!(doc["mission"]["globalPlanAltitudeMode"], 0);
    assert_eq!(num(&doc["mission"]["plannedHomePosition"][2]), 312.5);
    let items = doc["mission"]["items"].as_array().unwrap();
    assert_eq!(items.len(), mission.waypoints.len() + 1);
    for (item, w) in items.iter().zip(&mission.waypoints) {
        assert_eq!(item["frame"], u64::from(mavlink::MAV_FRAME_GLOBAL));
        assert_eq!(item["AltitudeMode"], 2);
        assert_eq!(num(&item["Altitude"]), w.alt_m + 312.5);
        assert_eq!(num(&item["params"][6]), w.alt_m + 312.5);
    }
    let land = items.last().unwrap();
    assert_eq!(land["command"], u64::from(mavlink::MAV_CMD_NAV_LAND));
    assert_eq!(
        land["frame"],
        u64::from(mavlink::MAV_FRAME_GLOBAL_RELATIVE_ALT)
    );
    for bad in [f64::NAN, f64::INFINITY] {
        let options = QgcPlanOptions {
            home_amsl_m: Some(bad),
            ..QgcPlanOptions::default()
        };
        assert!(to_qgc_plan(&mission, &options).is_err());
    }
}
