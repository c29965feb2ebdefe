//! The operational intent and its 4D volumes, in the JSON shape of the InterUSS DSS (ASTM
//! F3548-21's `Volume4D`, `Volume3D`, `Polygon`, `LatLngPoint`, `Altitude`, `Time`).

use crate::Timestamp;
use serde::{Deserialize, Serialize};

/// A polygon vertex, WGS84 degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatLng {
    /// Latitude, degrees north.
    pub lat: f64,
    /// Longitude, degrees east.
    pub lng: f64,
}

/// A polygon: its vertices in order, without repeating the first at the end. Those skyplan
/// writes are convex and counter-clockwise; any other is checked through its convex hull (a
/// superset, so no conflict is missed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Polygon {
    /// The vertices.
    pub vertices: Vec<LatLng>,
}

/// The datum of an altitude: `W84`, height above the WGS84 ellipsoid (the only one the DSS
/// takes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum AltitudeReference {
    /// Height above the WGS84 ellipsoid.
    W84,
}

/// The unit of an altitude: `M`, metres (the only one the DSS takes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum AltitudeUnits {
    /// Metres.
    M,
}

/// An altitude: `{"value": 120.0, "reference": "W84", "units": "M"}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Altitude {
    /// Metres above the reference.
    pub value: f64,
    /// The datum.
    pub reference: AltitudeReference,
    /// The unit.
    pub units: AltitudeUnits,
}

impl Altitude {
    /// `value` metres above the WGS84 ellipsoid.
    pub fn w84_m(value: f64) -> Self {
        Self {
            value,
            reference: AltitudeReference::W84,
            units: AltitudeUnits::M,
        }
    }
}

/// The format of a time: `RFC3339` (the only one the DSS takes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TimeFormat {
    /// RFC 3339 date-time text.
    #[serde(rename = "RFC3339")]
    Rfc3339,
}

/// A time: `{"value": "2026-03-01T12:00:00Z", "format": "RFC3339"}`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Time {
    /// The instant.
    pub value: Timestamp,
    /// The format of `value`.
    pub format: TimeFormat,
}

impl From<Timestamp> for Time {
    fn from(value: Timestamp) -> Self {
        Self {
            value,
            format: TimeFormat::Rfc3339,
        }
    }
}

/// A volume in space: a footprint and an altitude band.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Volume3D {
    /// The footprint.
    pub outline_polygon: Polygon,
    /// The band's floor.
    pub altitude_lower: Altitude,
    /// The band's ceiling.
    pub altitude_upper: Altitude,
}

/// A volume in space and time: the DSS's `Volume4D`. As a set it is closed: two volumes
/// conflict when they share a point (a touching edge, band or instant included).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Volume4D {
    /// Where.
    pub volume: Volume3D,
    /// From when.
    pub time_start: Time,
    /// Until when.
    pub time_end: Time,
}

impl Volume4D {
    /// The same volume `ms` milliseconds later.
    pub fn shifted_ms(&self, ms: i64) -> Self {
        Self {
            volume: self.volume.clone(),
            time_start: self.time_start.value.plus_ms(ms).into(),
            time_end: self.time_end.value.plus_ms(ms).into(),
        }
    }
}

/// Where an intent is in its life.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum IntentState {
    /// Accepted by the airspace: its volumes are reserved.
    Accepted,
    /// Flying.
    Activated,
    /// Over: its volumes no longer block anyone.
    Ended,
}

impl IntentState {
    /// The name in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Accepted => "Accepted",
            Self::Activated => "Activated",
            Self::Ended => "Ended",
        }
    }
}

/// The most important priority; priorities run from 0 (least) to this.
pub const MAX_PRIORITY: u32 = 100;

/// A flight's declared use of the airspace.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OperationalIntent {
    /// Unique id (a UUID when the store made it).
    pub id: String,
    /// Version, from 1; changes when the intent does.
    pub version: u64,
    /// Where it is in its life.
    pub state: IntentState,
    /// 0 to [`MAX_PRIORITY`]; higher is more important. A new intent must not conflict with
    /// stored ones of equal or higher priority.
    pub priority: u32,
    /// Who flies it.
    pub owner: String,
    /// The volumes, in flight order.
    pub volumes: Vec<Volume4D>,
}

/// An intent named in an answer: its id and version.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct IntentRef {
    /// The intent's id.
    pub id: String,
    /// Its version.
    pub version: u64,
}

impl std::fmt::Display for IntentRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} (version {})", self.id, self.version)
    }
}

impl OperationalIntent {
    /// Its id and version.
    pub fn reference(&self) -> IntentRef {
        IntentRef {
            id: self.id.clone(),
            version: self.version,
        }
    }

    /// The earliest start and latest end of its volumes (`None` without volumes).
    pub fn time_bounds(&self) -> Option<(Timestamp, Timestamp)> {
        let start = self.volumes.iter().map(|v| v.time_start.value).min()?;
        let end = self.volumes.iter().map(|v| v.time_end.value).max()?;
        Some((start, end))
    }

    /// Refuses what no conflict test can read, naming the field: no volumes, a polygon of
    /// fewer than 3 vertices or enclosing no area, coordinates out of range or not finite, a
    /// floor above its ceiling, a start after its end, a priority above [`MAX_PRIORITY`].
    pub fn validate(&self) -> Result<(), crate::AirspaceError> {
        let bad = |field: String, why: String| crate::AirspaceError::Invalid { field, why };
        if self.priority > MAX_PRIORITY {
            return Err(bad(
                "priority".into(),
                format!("{} is above {MAX_PRIORITY}", self.priority),
            ));
        }
        if self.volumes.is_empty() {
            return Err(bad("volumes".into(), "no volume".into()));
        }
        for (i, v) in self.volumes.iter().enumerate() {
            validate_volume(v).map_err(|(field, why)| bad(format!("volumes[{i}].{field}"), why))?;
        }
        Ok(())
    }
}

/// The first thing wrong with `v`, as (field, why).
pub(crate) fn validate_volume(v: &Volume4D) -> Result<(), (String, String)> {
    let vertices = &v.volume.outline_polygon.vertices;
    for (k, p) in vertices.iter().enumerate() {
        if !(p.lat.is_finite() && p.lat.abs() <= 90.0 && p.lng.is_finite() && p.lng.abs() <= 180.0)
        {
            return Err((
                format!("volume.outline_polygon.vertices[{k}]"),
                format!("lat {} / lng {} out of ±90 / ±180", p.lat, p.lng),
            ));
        }
    }
    if crate::geometry::Hull::of_polygon(&v.volume.outline_polygon).is_none() {
        return Err((
            "volume.outline_polygon".into(),
            "fewer than 3 vertices, or they enclose no area".into(),
        ));
    }
    let (lo, hi) = (v.volume.altitude_lower.value, v.volume.altitude_upper.value);
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return Err((
            "volume.altitude_lower".into(),
            format!("{lo} m must be a number at most altitude_upper ({hi} m)"),
        ));
    }
    if v.time_start.value > v.time_end.value {
        return Err((
            "time_start".into(),
            format!(
                "{} is after time_end {}",
                v.time_start.value, v.time_end.value
            ),
        ));
    }
    Ok(())
}
