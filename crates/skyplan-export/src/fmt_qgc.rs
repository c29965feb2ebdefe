//! QGroundControl `.plan` files.
//!
//! Layout as documented in QGroundControl's developer guide, "Plan File Format"
//! (`docs/en/qgc-dev-guide/file_formats/plan.md` in mavlink/qgroundcontrol).

use serde_json::{Value, json};
use skyplan_mission::{Mission, Waypoint};

use crate::{ExportError, Format, check_finite, check_len};

/// MAVLink numbers used in `.plan` files.
pub mod mavlink {
    /// `MAV_CMD_NAV_WAYPOINT`: fly to a position.
    pub const MAV_CMD_NAV_WAYPOINT: u16 = 16;
    /// `MAV_CMD_NAV_LAND`: land at a position.
    pub const MAV_CMD_NAV_LAND: u16 = 21;
    /// `MAV_CMD_NAV_TAKEOFF`: take off to an altitude.
    pub const MAV_CMD_NAV_TAKEOFF: u16 = 22;
    /// `MAV_FRAME_GLOBAL_RELATIVE_ALT`: lat/lon, altitude above home.
    pub const MAV_FRAME_GLOBAL_RELATIVE_ALT: u8 = 3;
    /// `MAV_FRAME_GLOBAL`: lat/lon, altitude above mean sea level.
    pub const MAV_FRAME_GLOBAL: u8 = 0;
    /// `MAV_AUTOPILOT_ARDUPILOTMEGA`.
    pub const MAV_AUTOPILOT_ARDUPILOTMEGA: u8 = 3;
    /// `MAV_AUTOPILOT_PX4`.
    pub const MAV_AUTOPILOT_PX4: u8 = 12;
    /// `MAV_TYPE_QUADROTOR`.
    pub const MAV_TYPE_QUADROTOR: u8 = 2;
    /// QGroundControl's `AltitudeMode` "Relative" (altitude above home).
    pub const QGC_ALTITUDE_MODE_RELATIVE: u8 = 1;
    /// QGroundControl's `AltitudeMode` "Absolute" (above mean sea level, `MAV_FRAME_GLOBAL`).
    pub const QGC_ALTITUDE_MODE_ABSOLUTE: u8 = 2;
    /// QGroundControl's `AltitudeMode` "Mixed": each item says its own (a plan's global mode).
    pub const QGC_ALTITUDE_MODE_MIXED: u8 = 0;
}

use mavlink::*;

/// A `.plan` file's `geoFence`: polygons and circles, each to stay inside (`inclusion`) or
/// out of. QGroundControl's layout: `{"circles": [{"circle": {"center": [lat, lon], "radius":
/// r}, "inclusion": b, "version": 1}], "polygons": [{"inclusion": b, "polygon": [[lat, lon],
/// …], "version": 1}], "version": 2}` (polygons open: the first vertex is not repeated).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GeoFence {
    /// The polygons.
    pub polygons: Vec<FencePolygon>,
    /// The circles.
    pub circles: Vec<FenceCircle>,
}

/// A fence polygon.
#[derive(Debug, Clone, PartialEq)]
pub struct FencePolygon {
    /// Stay inside (`true`) or out (`false`).
    pub inclusion: bool,
    /// The vertices, `[latitude, longitude]` in degrees, not closed.
    pub vertices_lat_lon_deg: Vec<[f64; 2]>,
}

/// A fence circle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FenceCircle {
    /// Stay inside (`true`) or out (`false`).
    pub inclusion: bool,
    /// The centre, `[latitude, longitude]` in degrees.
    pub centre_lat_lon_deg: [f64; 2],
    /// The radius, metres.
    pub radius_m: f64,
}

impl GeoFence {
    /// The `geoFence` object.
    fn to_json(&self) -> Value {
        let polygons: Vec<Value> = self
            .polygons
            .iter()
            .map(|p| json!({ "inclusion": p.inclusion, "polygon": p.vertices_lat_lon_deg, "version": 1 }))
            .collect();
        let circles: Vec<Value> = self
            .circles
            .iter()
            .map(|c| {
                json!({
                    "circle": { "center": c.centre_lat_lon_deg, "radius": c.radius_m },
                    "inclusion": c.inclusion,
                    "version": 1,
                })
            })
            .collect();
        json!({ "circles": circles, "polygons": polygons, "version": 2 })
    }

    fn validate(&self) -> Result<(), ExportError> {
        let bad = |value: f64, reason: &'static str| ExportError::InvalidOption {
            name: "geo_fence",
            value,
            reason,
        };
        for p in &self.polygons {
            if p.vertices_lat_lon_deg.len() < 3 {
                return Err(bad(
                    p.vertices_lat_lon_deg.len() as f64,
                    "a fence polygon needs at least 3 vertices",
                ));
            }
            for v in p.vertices_lat_lon_deg.iter().flatten() {
                if !v.is_finite() {
                    return Err(bad(*v, "fence coordinates must be finite"));
                }
            }
        }
        for c in &self.circles {
            if !(c.radius_m.is_finite() && c.radius_m > 0.0) {
                return Err(bad(
                    c.radius_m,
                    "a fence radius must be finite and positive",
                ));
            }
            for v in c.centre_lat_lon_deg {
                if !v.is_finite() {
                    return Err(bad(v, "fence coordinates must be finite"));
                }
            }
        }
        Ok(())
    }
}

/// Mission-wide settings of a `.plan` file.
#[derive(Debug, Clone, PartialEq)]
pub struct QgcPlanOptions {
    /// `cruiseSpeed`, m/s: the default speed of fixed-wing and VTOL vehicles. Default 15.
    pub cruise_speed_m_s: f64,
    /// `hoverSpeed`, m/s: the default speed of multirotors. Default 5.
    pub hover_speed_m_s: f64,
    /// `firmwareType`, a `MAV_AUTOPILOT` value. Default [`mavlink::MAV_AUTOPILOT_PX4`].
    pub firmware_type: u8,
    /// `vehicleType`, a `MAV_TYPE` value. Default [`mavlink::MAV_TYPE_QUADROTOR`].
    pub vehicle_type: u8,
    /// The `geoFence` (default: none).
    pub geo_fence: GeoFence,
    /// The home's height above mean sea level, metres, when known (a plan over a DEM): the
    /// takeoff and waypoint items are then in `MAV_FRAME_GLOBAL` (`AltitudeMode` 2), at the
    /// mission's altitudes plus this, so a vehicle launched anywhere flies them at the heights
    /// planned; the landing item stays relative (its altitude is not flown). Default `None`:
    /// every item in `MAV_FRAME_GLOBAL_RELATIVE_ALT`.
    pub home_amsl_m: Option<f64>,
}

impl Default for QgcPlanOptions {
    fn default() -> Self {
        Self {
            cruise_speed_m_s: 15.0,
            hover_speed_m_s: 5.0,
            firmware_type: MAV_AUTOPILOT_PX4,
            vehicle_type: MAV_TYPE_QUADROTOR,
            geo_fence: GeoFence::default(),
            home_amsl_m: None,
        }
    }
}

impl QgcPlanOptions {
    fn validate(&self) -> Result<(), ExportError> {
        for (name, value) in [
            ("cruise_speed_m_s", self.cruise_speed_m_s),
            ("hover_speed_m_s", self.hover_speed_m_s),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ExportError::InvalidOption {
                    name,
                    value,
                    reason: "must be finite and positive",
                });
            }
        }
        if let Some(h) = self.home_amsl_m
            && !h.is_finite()
        {
            return Err(ExportError::InvalidOption {
                name: "home_amsl_m",
                value: h,
                reason: "must be finite",
            });
        }
        self.geo_fence.validate()
    }
}

/// Heading in degrees clockwise from north, in `[0, 360)`.
fn yaw_deg(heading_rad: f64) -> f64 {
    let deg = heading_rad.to_degrees().rem_euclid(360.0);
    // rem_euclid of a tiny negative number rounds up to 360.
    if deg >= 360.0 { 0.0 } else { deg }
}

/// One `SimpleItem`, in `MAV_FRAME_GLOBAL` with `amsl`, else `MAV_FRAME_GLOBAL_RELATIVE_ALT`.
fn simple_item(
    do_jump_id: usize,
    command: u16,
    (altitude_m, amsl): (f64, bool),
    params: Value,
) -> Value {
    let (mode, frame) = if amsl {
        (QGC_ALTITUDE_MODE_ABSOLUTE, MAV_FRAME_GLOBAL)
    } else {
        (QGC_ALTITUDE_MODE_RELATIVE, MAV_FRAME_GLOBAL_RELATIVE_ALT)
    };
    json!({
        "AMSLAltAboveTerrain": null,
        "Altitude": altitude_m,
        "AltitudeMode": mode,
        "autoContinue": true,
        "command": command,
        "doJumpId": do_jump_id,
        "frame": frame,
        "params": params,
        "type": "SimpleItem",
    })
}

/// The mission items: takeoff at the first waypoint, a waypoint for each later one, land at the
/// last. `doJumpId`s count from 1. With `home_amsl_m`, the takeoff and the waypoints are above
/// mean sea level.
fn items(wps: &[Waypoint], home_amsl_m: Option<f64>) -> Vec<Value> {
    let mut items = Vec::with_capacity(wps.len() + 1);
    let (Some(first), Some(last)) = (wps.first(), wps.last()) else {
        return items;
    };
    let amsl = home_amsl_m.is_some();
    let alt = |w: &Waypoint| w.alt_m + home_amsl_m.unwrap_or(0.0);
    items.push(simple_item(
        1,
        MAV_CMD_NAV_TAKEOFF,
        (alt(first), amsl),
        json!([0, 0, 0, null, first.lat_deg, first.lon_deg, alt(first)]),
    ));
    for w in &wps[1..] {
        // hold time s, acceptance radius m, pass radius m, yaw deg, lat, lon, alt.
        let params = json!([
            0,
            0,
            0,
            yaw_deg(w.heading_rad),
            w.lat_deg,
            w.lon_deg,
            alt(w)
        ]);
        items.push(simple_item(
            items.len() + 1,
            MAV_CMD_NAV_WAYPOINT,
            (alt(w), amsl),
            params,
        ));
    }
    let params = json!([0, 0, 0, null, last.lat_deg, last.lon_deg, 0]);
    items.push(simple_item(
        items.len() + 1,
        MAV_CMD_NAV_LAND,
        (0.0, false),
        params,
    ));
    items
}

/// Encodes a mission as a QGroundControl `.plan` file (pretty JSON, trailing newline).
///
/// The mission items, all `SimpleItem`s in `MAV_FRAME_GLOBAL_RELATIVE_ALT` (frame 3,
/// `AltitudeMode` 1, altitudes above home) — or, with `options.home_amsl_m`, the takeoff and
/// waypoints in `MAV_FRAME_GLOBAL` (frame 0, `AltitudeMode` 2, above mean sea level; the plan's
/// `globalPlanAltitudeMode` 0, mixed, and its home at that height) — are:
/// 1. `MAV_CMD_NAV_TAKEOFF` (22) at the first waypoint, to its altitude;
/// 2. `MAV_CMD_NAV_WAYPOINT` (16) for every later waypoint, with its heading as the yaw
///    (param 4, degrees clockwise from north in `[0, 360)`) and zero hold time and radii;
/// 3. `MAV_CMD_NAV_LAND` (21) at the last waypoint.
///
/// So an `n`-waypoint mission gives `n + 1` items. `plannedHomePosition` is the mission home
/// `[lat, lon, alt]`; the geofence is `options.geo_fence` ([`GeoFence`]); rally points are empty. An empty mission is an error
/// ([`ExportError::TooFewWaypoints`]), as are non-positive speeds
/// ([`ExportError::InvalidOption`]).
pub fn to_qgc_plan(mission: &Mission, options: &QgcPlanOptions) -> Result<String, ExportError> {
    check_finite(mission)?;
    check_len(Format::QgcPlan, mission, 1)?;
    options.validate()?;
    let home = &mission.home;
    let (global_mode, home_alt_m) = match options.home_amsl_m {
        Some(h) => (QGC_ALTITUDE_MODE_MIXED, h),
        None => (QGC_ALTITUDE_MODE_RELATIVE, home.alt_m),
    };
    let plan = json!({
        "fileType": "Plan",
        "geoFence": options.geo_fence.to_json(),
        "groundStation": "QGroundControl",
        "mission": {
            "cruiseSpeed": options.cruise_speed_m_s,
            "firmwareType": options.firmware_type,
            "globalPlanAltitudeMode": global_mode,
            "hoverSpeed": options.hover_speed_m_s,
            "items": items(&mission.waypoints, options.home_amsl_m),
            "plannedHomePosition": [home.lat_deg, home.lon_deg, home_alt_m],
            "vehicleType": options.vehicle_type,
            "version": 2,
        },
        "rallyPoints": { "points": [], "version": 2 },
        "version": 1,
    });
    let mut text = serde_json::to_string_pretty(&plan)?;
    text.push('\n');
    Ok(text)
}
