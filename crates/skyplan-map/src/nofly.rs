//! No-fly zones from GeoJSON (RFC 7946): a `FeatureCollection` whose features are zones.
//!
//! - A `Polygon` feature (holes allowed) or a `Point` feature with the property `radius_m`
//!   (a circle).
//! - `floor_m` and `ceiling_m`: the zone's altitude band, metres above home, or above mean sea
//!   level with `"reference": "amsl"` (which needs the home's altitude when projected). Both
//!   are required on exclusion zones; an inclusion zone without them spans every altitude.
//! - `start` and `end` (optional): RFC 3339 times between which the zone is active.
//! - `"inclusion": true`: the zone is a boundary to stay inside (default: a zone to stay out of).
//!
//! A QGroundControl `.plan` file (`"fileType": "Plan"`) is read too: its `geoFence` polygons
//! and circles with their `inclusion` flags, at every altitude (a fence has no band).
//!
//! Parsing ([`parse_no_fly`]) checks every field, naming the feature, the field and what was
//! expected; projecting ([`NoFlyZones::project`]) turns the zones into local metres north/east
//! of the map's home with altitudes above home ([`Zone`]).
//!
//! ```
//! use skyplan_map::colliders::GeodeticHome;
//! use skyplan_map::nofly::{parse_no_fly, ZoneShape};
//! let text = r#"{"type": "FeatureCollection", "features": [
//!   {"type": "Feature", "properties": {"radius_m": 40, "floor_m": 0, "ceiling_m": 120},
//!    "geometry": {"type": "Point", "coordinates": [-122.39, 37.79]}}]}"#;
//! let zones = parse_no_fly(text)?;
//! let local = zones.project(GeodeticHome { lat_deg: 37.79, lon_deg: -122.39 }, None)?;
//! assert!(matches!(local[0].shape, ZoneShape::Circle { radius_m: 40.0, .. }));
//! assert!(local[0].meets_altitude(5.0, 5.0) && !local[0].inclusion);
//! # Ok::<(), skyplan_map::footprints::FootprintError>(())
//! ```

use crate::colliders::GeodeticHome;
use crate::footprints::{
    FootprintError, err, feature_list, json_root, metres, parse_polygon, position, shorten, shown,
};
use serde_json::Value;
use skyplan_frames::{Lla, LocalFrame};

/// The shape of a zone. Points are `[longitude, latitude]` in a [`GeoZone`], `[north, east]`
/// metres in a [`Zone`].
#[derive(Debug, Clone, PartialEq)]
pub enum ZoneShape {
    /// The outer ring then the holes, each without the closing position.
    Polygon(Vec<Vec<[f64; 2]>>),
    /// A disc.
    Circle {
        /// The centre.
        centre: [f64; 2],
        /// The radius, metres (> 0).
        radius_m: f64,
    },
}

/// What a zone's `floor_m` and `ceiling_m` are measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AltReference {
    /// Metres above home (the default).
    Home,
    /// Metres above mean sea level (`"reference": "amsl"`).
    Amsl,
}

/// A zone as the file gives it (longitude/latitude).
#[derive(Debug, Clone, PartialEq)]
pub struct GeoZone {
    /// 0-based index of the feature in the file.
    pub feature: usize,
    /// The shape in longitude/latitude.
    pub shape: ZoneShape,
    /// The band's floor, metres above `reference`.
    pub floor_m: f64,
    /// The band's ceiling, metres above `reference` (may be infinite on an inclusion zone).
    pub ceiling_m: f64,
    /// What the band is measured from.
    pub reference: AltReference,
    /// A boundary to stay inside (not a zone to stay out of).
    pub inclusion: bool,
    /// Active from (Unix seconds, UTC), if the file says.
    pub start_unix_s: Option<i64>,
    /// Active until (Unix seconds, UTC), if the file says.
    pub end_unix_s: Option<i64>,
}

/// A zone in the local frame: shape in metres north/east of home, band above home.
#[derive(Debug, Clone, PartialEq)]
pub struct Zone {
    /// 0-based index of the feature in the file.
    pub feature: usize,
    /// The shape, `[north, east]` metres.
    pub shape: ZoneShape,
    /// The band's floor, metres above home.
    pub floor_m: f64,
    /// The band's ceiling, metres above home (infinite: no ceiling).
    pub ceiling_m: f64,
    /// A boundary to stay inside (not a zone to stay out of).
    pub inclusion: bool,
    /// Active from (Unix seconds, UTC), if the file says.
    pub start_unix_s: Option<i64>,
    /// Active until (Unix seconds, UTC), if the file says.
    pub end_unix_s: Option<i64>,
}

impl Zone {
    /// Whether the zone's band grown by `margin_m` holds `alt_m` (`floor − margin < alt <
    /// ceiling + margin`), as a building's band does.
    pub fn meets_altitude(&self, alt_m: f64, margin_m: f64) -> bool {
        self.floor_m - margin_m < alt_m && alt_m < self.ceiling_m + margin_m
    }

    /// Whether an inclusion zone's band shrunk by `margin_m` holds `alt_m` (`floor + margin ≤
    /// alt ≤ ceiling − margin`): the altitude may be flown inside it.
    pub fn holds_altitude(&self, alt_m: f64, margin_m: f64) -> bool {
        self.floor_m + margin_m <= alt_m && alt_m <= self.ceiling_m - margin_m
    }

    /// Whether the zone is active at `unix_s` (always when no time is given: a timed zone is
    /// then taken as active, the safe side).
    pub fn active_at(&self, unix_s: Option<i64>) -> bool {
        let Some(t) = unix_s else { return true };
        self.start_unix_s.is_none_or(|s| s <= t) && self.end_unix_s.is_none_or(|e| t < e)
    }

    /// The distance from the segment `a`–`b` (`[north, east]` metres) to the zone's shape, 0
    /// where they meet (a polygon's holes are outside it; a circle is a disc).
    ///
    /// ```
    /// use skyplan_map::nofly::{Zone, ZoneShape};
    /// let disc = Zone { feature: 0, shape: ZoneShape::Circle { centre: [0.0, 0.0], radius_m: 1.0 },
    ///                   floor_m: 0.0, ceiling_m: 50.0, inclusion: false, start_unix_s: None, end_unix_s: None };
    /// assert_eq!(disc.clearance_m([3.0, -5.0], [3.0, 5.0]), 2.0);
    /// assert_eq!(disc.clearance_m([0.5, -5.0], [0.5, 5.0]), 0.0);
    /// ```
    pub fn clearance_m(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        match &self.shape {
            ZoneShape::Circle { centre, radius_m } => {
                (point_segment_m(*centre, a, b) - radius_m).max(0.0)
            }
            ZoneShape::Polygon(rings) => crate::planar::region_segment_m(rings, a, b),
        }
    }

    /// The distance from the segment `a`–`b` to the shape's boundary (a circle's rim, a
    /// polygon's rings), 0 where it crosses or touches it: how far a route inside an inclusion
    /// boundary keeps from leaving it.
    ///
    /// ```
    /// use skyplan_map::nofly::{Zone, ZoneShape};
    /// let disc = Zone { feature: 0, shape: ZoneShape::Circle { centre: [0.0, 0.0], radius_m: 10.0 },
    ///                   floor_m: 0.0, ceiling_m: 50.0, inclusion: true, start_unix_s: None, end_unix_s: None };
    /// assert_eq!(disc.boundary_clearance_m([0.0, -6.0], [0.0, 6.0]), 4.0);
    /// assert_eq!(disc.boundary_clearance_m([0.0, -6.0], [0.0, 16.0]), 0.0);
    /// ```
    pub fn boundary_clearance_m(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        match &self.shape {
            ZoneShape::Circle { centre, radius_m } => {
                let far = (a[0] - centre[0])
                    .hypot(a[1] - centre[1])
                    .max((b[0] - centre[0]).hypot(b[1] - centre[1]));
                let near = point_segment_m(*centre, a, b);
                if far <= *radius_m {
                    radius_m - far
                } else {
                    (near - radius_m).max(0.0)
                }
            }
            ZoneShape::Polygon(rings) => crate::planar::boundary_segment_m(rings, a, b),
        }
    }

    /// The shape's bounding box `(min, max)`, `[north, east]`, without margin.
    pub fn bbox_ne(&self) -> ([f64; 2], [f64; 2]) {
        match &self.shape {
            ZoneShape::Circle { centre, radius_m } => (
                [centre[0] - radius_m, centre[1] - radius_m],
                [centre[0] + radius_m, centre[1] + radius_m],
            ),
            ZoneShape::Polygon(rings) => rings.iter().flatten().fold(
                ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
                |(lo, hi), p| {
                    (
                        [lo[0].min(p[0]), lo[1].min(p[1])],
                        [hi[0].max(p[0]), hi[1].max(p[1])],
                    )
                },
            ),
        }
    }
}

/// The zones of a file.
#[derive(Debug, Clone, PartialEq)]
pub struct NoFlyZones {
    /// Every zone, in file order.
    pub zones: Vec<GeoZone>,
}

impl NoFlyZones {
    /// Every zone in local metres about `home`; `home_amsl_m` is the home's altitude above
    /// mean sea level, needed by zones with `"reference": "amsl"` (refused without it).
    pub fn project(
        &self,
        home: GeodeticHome,
        home_amsl_m: Option<f64>,
    ) -> Result<Vec<Zone>, FootprintError> {
        let frame = LocalFrame::new(Lla {
            lat_deg: home.lat_deg,
            lon_deg: home.lon_deg,
            alt_m: 0.0,
        })
        .map_err(|e| err(None, "home", e.to_string()))?;
        let local = |i: usize, [lon_deg, lat_deg]: [f64; 2]| {
            frame
                .ned_from_lla(Lla {
                    lat_deg,
                    lon_deg,
                    alt_m: 0.0,
                })
                .map(|n| [n.north_m, n.east_m])
                .map_err(|e| err(Some(i), "geometry", e.to_string()))
        };
        let mut out = Vec::with_capacity(self.zones.len());
        for z in &self.zones {
            let i = z.feature;
            let shape = match &z.shape {
                ZoneShape::Circle { centre, radius_m } => ZoneShape::Circle {
                    centre: local(i, *centre)?,
                    radius_m: *radius_m,
                },
                ZoneShape::Polygon(rings) => ZoneShape::Polygon(
                    rings
                        .iter()
                        .map(|r| r.iter().map(|&p| local(i, p)).collect())
                        .collect::<Result<_, _>>()?,
                ),
            };
            let below = match z.reference {
                AltReference::Home => 0.0,
                AltReference::Amsl => home_amsl_m.ok_or_else(|| {
                    err(
                        Some(i),
                        "properties.reference",
                        "\"amsl\" needs the home's altitude above mean sea level, which this map does not give (a terrain does: --terrain FILE); give floor_m and ceiling_m above home instead",
                    )
                })?,
            };
            out.push(Zone {
                feature: i,
                shape,
                floor_m: z.floor_m - below,
                ceiling_m: z.ceiling_m - below,
                inclusion: z.inclusion,
                start_unix_s: z.start_unix_s,
                end_unix_s: z.end_unix_s,
            });
        }
        Ok(out)
    }
}

/// Parses a GeoJSON `FeatureCollection` of no-fly zones (see the [module](self) for the
/// fields). Refused, naming the feature and the field: text that is not JSON, a feature
/// without geometry or of another type, a bad ring (as for footprints), a circle without a
/// positive `radius_m`, a missing or negative band, a ceiling not above the floor, a
/// `reference` other than `"home"`/`"amsl"`, an `inclusion` that is not a boolean, a time that
/// is not RFC 3339 or an `end` not after its `start`.
///
/// ```
/// use skyplan_map::nofly::parse_no_fly;
/// let text = r#"{"type": "FeatureCollection", "features": [
///   {"type": "Feature", "properties": {"floor_m": 0},
///    "geometry": {"type": "Point", "coordinates": [-122.39, 37.79]}}]}"#;
/// let e = parse_no_fly(text).unwrap_err();
/// assert_eq!(e.to_string(), "feature 0, properties.radius_m: a Point zone is a circle: expected its radius in metres > 0");
/// ```
pub fn parse_no_fly(text: &str) -> Result<NoFlyZones, FootprintError> {
    parse_no_fly_value(&json_root(text.as_bytes())?)
}

/// [`parse_no_fly`] of an already parsed JSON document.
pub fn parse_no_fly_value(root: &Value) -> Result<NoFlyZones, FootprintError> {
    if root.get("fileType").and_then(Value::as_str) == Some("Plan") {
        return parse_qgc_geofence(root);
    }
    let features = feature_list(root)?;
    let mut vertices = 0;
    let zones = features
        .iter()
        .enumerate()
        .map(|(i, f)| parse_zone(i, f, &mut vertices))
        .collect::<Result<Vec<_>, _>>()?;
    if zones.is_empty() {
        return Err(err(
            None,
            "features",
            "the collection has no features; expected at least one zone",
        ));
    }
    Ok(NoFlyZones { zones })
}

/// The `geoFence` of a QGroundControl `.plan` file (`"fileType": "Plan"`): its polygons
/// (`[lat, lon]` vertices, not closed) then its circles, numbered in that order, each with its
/// `inclusion` flag. A fence has no altitude band: every zone spans every altitude.
fn parse_qgc_geofence(root: &Value) -> Result<NoFlyZones, FootprintError> {
    let fence = root
        .get("geoFence")
        .filter(|f| f.is_object())
        .ok_or_else(|| {
            err(
                None,
                "geoFence",
                "a .plan file without a geoFence object has no zones",
            )
        })?;
    let list = |key: &str| -> Result<Vec<Value>, FootprintError> {
        match fence.get(key) {
            None | Some(Value::Null) => Ok(Vec::new()),
            Some(Value::Array(a)) => Ok(a.clone()),
            Some(v) => Err(err(
                None,
                format!("geoFence.{key}"),
                format!("expected an array, found {}", shown(v)),
            )),
        }
    };
    let (polygons, circles) = (list("polygons")?, list("circles")?);
    let inclusion_of = |item: &Value, field: &str| match item.get("inclusion") {
        Some(Value::Bool(b)) => Ok(*b),
        None => Ok(true), // QGroundControl's default
        Some(v) => Err(err(
            None,
            format!("{field}.inclusion"),
            format!("expected true or false, found {}", shown(v)),
        )),
    };
    let lat_lon = |v: &Value, field: &str| -> Result<[f64; 2], FootprintError> {
        let a = v.as_array().filter(|a| a.len() >= 2);
        let pair = a.and_then(|a| Some([a[0].as_f64()?, a[1].as_f64()?]));
        match pair {
            Some([lat, lon])
                if (-90.0..=90.0).contains(&lat) && (-180.0..=180.0).contains(&lon) =>
            {
                Ok([lon, lat])
            }
            _ => Err(err(
                None,
                field,
                format!(
                    "expected [latitude, longitude] within ±90° and ±180°, found {}",
                    shown(v)
                ),
            )),
        }
    };
    let mut zones = Vec::new();
    for (i, p) in polygons.iter().enumerate() {
        let field = format!("geoFence.polygons[{i}]");
        let inclusion = inclusion_of(p, &field)?;
        let vertices = p.get("polygon").and_then(Value::as_array).ok_or_else(|| {
            err(
                None,
                format!("{field}.polygon"),
                "expected an array of [latitude, longitude] vertices",
            )
        })?;
        if vertices.len() > crate::footprints::MAX_VERTICES {
            return Err(err(
                None,
                format!("{field}.polygon"),
                format!("more than {} vertices", crate::footprints::MAX_VERTICES),
            ));
        }
        let mut ring = vertices
            .iter()
            .enumerate()
            .map(|(k, v)| lat_lon(v, &format!("{field}.polygon[{k}]")))
            .collect::<Result<Vec<_>, _>>()?;
        ring.dedup();
        while ring.len() > 1 && ring.first() == ring.last() {
            ring.pop();
        }
        if ring.len() < 3 {
            return Err(err(
                None,
                format!("{field}.polygon"),
                "expected at least 3 distinct vertices",
            ));
        }
        if let Some((a, b)) = crate::footprints::self_intersection(&ring) {
            return Err(err(
                None,
                format!("{field}.polygon"),
                format!("the polygon crosses or touches itself: its edges {a} and {b} meet"),
            ));
        }
        zones.push(GeoZone {
            feature: i,
            shape: ZoneShape::Polygon(vec![ring]),
            floor_m: 0.0,
            ceiling_m: f64::INFINITY,
            reference: AltReference::Home,
            inclusion,
            start_unix_s: None,
            end_unix_s: None,
        });
    }
    for (i, c) in circles.iter().enumerate() {
        let field = format!("geoFence.circles[{i}]");
        let inclusion = inclusion_of(c, &field)?;
        let circle = c.get("circle");
        let centre = lat_lon(
            circle.and_then(|c| c.get("center")).unwrap_or(&Value::Null),
            &format!("{field}.circle.center"),
        )?;
        let radius_m = circle
            .and_then(|c| c.get("radius"))
            .and_then(Value::as_f64)
            .filter(|r| r.is_finite() && *r > 0.0)
            .ok_or_else(|| {
                err(
                    None,
                    format!("{field}.circle.radius"),
                    "expected a radius in metres > 0",
                )
            })?;
        zones.push(GeoZone {
            feature: polygons.len() + i,
            shape: ZoneShape::Circle { centre, radius_m },
            floor_m: 0.0,
            ceiling_m: f64::INFINITY,
            reference: AltReference::Home,
            inclusion,
            start_unix_s: None,
            end_unix_s: None,
        });
    }
    if zones.is_empty() {
        return Err(err(
            None,
            "geoFence",
            "the fence has no polygons and no circles; expected at least one zone",
        ));
    }
    Ok(NoFlyZones { zones })
}

fn parse_zone(i: usize, f: &Value, vertices: &mut usize) -> Result<GeoZone, FootprintError> {
    let at = Some(i);
    if f.get("type").and_then(Value::as_str) != Some("Feature") {
        return Err(err(at, "type", "expected \"Feature\""));
    }
    let props = f.get("properties").filter(|p| !p.is_null());
    let prop = |name: &str| props.and_then(|p| p.get(name)).filter(|v| !v.is_null());
    let inclusion = match prop("inclusion") {
        None => false,
        Some(Value::Bool(b)) => *b,
        Some(v) => {
            return Err(err(
                at,
                "properties.inclusion",
                format!("expected true or false, found {}", shown(v)),
            ));
        }
    };
    let geometry = match f.get("geometry") {
        None | Some(Value::Null) => {
            return Err(err(
                at,
                "geometry",
                "the feature has no geometry; expected a Polygon or a Point with radius_m",
            ));
        }
        Some(g) => g,
    };
    let gtype = geometry.get("type").and_then(Value::as_str).unwrap_or("");
    let coords = geometry
        .get("coordinates")
        .ok_or_else(|| err(at, "geometry.coordinates", "missing"))?;
    let shape = match gtype {
        "Polygon" => {
            ZoneShape::Polygon(parse_polygon(i, coords, "geometry.coordinates", vertices)?)
        }
        "Point" => {
            let centre = position(i, coords, "geometry.coordinates")?;
            let radius_m = match prop("radius_m") {
                Some(v) => metres(i, "properties.radius_m", v)?,
                None => 0.0,
            };
            if radius_m <= 0.0 {
                return Err(err(
                    at,
                    "properties.radius_m",
                    "a Point zone is a circle: expected its radius in metres > 0",
                ));
            }
            ZoneShape::Circle { centre, radius_m }
        }
        other => {
            return Err(err(
                at,
                "geometry.type",
                format!(
                    "expected \"Polygon\" or \"Point\" (with radius_m), found \"{}\"",
                    shorten(other)
                ),
            ));
        }
    };
    let band = |name: &str, unbounded: f64| -> Result<f64, FootprintError> {
        let field = format!("properties.{name}");
        match prop(name) {
            Some(v) => metres(i, &field, v),
            None if inclusion => Ok(unbounded),
            None => Err(err(
                at,
                field,
                "missing: expected the zone's altitude band in metres (floor_m and ceiling_m)",
            )),
        }
    };
    let floor_m = band("floor_m", 0.0)?;
    let ceiling_m = band("ceiling_m", f64::INFINITY)?;
    if ceiling_m <= floor_m {
        return Err(err(
            at,
            "properties.ceiling_m",
            format!("{ceiling_m} m: expected above floor_m ({floor_m} m)"),
        ));
    }
    let reference = match prop("reference") {
        None => AltReference::Home,
        Some(Value::String(s)) if s.eq_ignore_ascii_case("home") => AltReference::Home,
        Some(Value::String(s)) if s.eq_ignore_ascii_case("amsl") => AltReference::Amsl,
        Some(v) => {
            return Err(err(
                at,
                "properties.reference",
                format!("expected \"home\" or \"amsl\", found {}", shown(v)),
            ));
        }
    };
    let time = |name: &str| -> Result<Option<i64>, FootprintError> {
        let Some(v) = prop(name) else {
            return Ok(None);
        };
        v.as_str().and_then(parse_rfc3339).map(Some).ok_or_else(|| {
            err(
                at,
                format!("properties.{name}"),
                format!(
                    "expected an RFC 3339 time such as \"2026-12-03T17:00:00Z\", found {}",
                    shown(v)
                ),
            )
        })
    };
    let start_unix_s = time("start")?;
    let end_unix_s = time("end")?;
    if let (Some(s), Some(e)) = (start_unix_s, end_unix_s)
        && e <= s
    {
        return Err(err(at, "properties.end", "expected after start"));
    }
    Ok(GeoZone {
        feature: i,
        shape,
        floor_m,
        ceiling_m,
        reference,
        inclusion,
        start_unix_s,
        end_unix_s,
    })
}

pub use crate::planar::point_segment_m;

/// Seconds since 1970-01-01T00:00:00Z of an RFC 3339 date-time (`2026-12-03T17:00:00Z`,
/// `…T17:00:00.5+01:00`; fractions of a second are dropped), or `None`.
///
/// ```
/// use skyplan_map::nofly::parse_rfc3339;
/// assert_eq!(parse_rfc3339("1970-01-02T00:00:00Z"), Some(86_400));
/// assert_eq!(parse_rfc3339("2000-03-01T01:00:00+01:00"), Some(951_868_800));
/// assert_eq!(parse_rfc3339("2026-02-30T00:00:00Z"), None);
/// ```
pub fn parse_rfc3339(s: &str) -> Option<i64> {
    let b = s.as_bytes();
    let num = |r: std::ops::Range<usize>| -> Option<i64> {
        let t = b.get(r)?;
        if t.iter().all(u8::is_ascii_digit) {
            std::str::from_utf8(t).ok()?.parse().ok()
        } else {
            None
        }
    };
    if b.len() < 20 || b[4] != b'-' || b[7] != b'-' || !matches!(b[10], b'T' | b't' | b' ') {
        return None;
    }
    if b[13] != b':' || b[16] != b':' {
        return None;
    }
    let (y, mo, d) = (num(0..4)?, num(5..7)?, num(8..10)?);
    let (h, mi, sec) = (num(11..13)?, num(14..16)?, num(17..19)?);
    let mut k = 19;
    if b[k] == b'.' {
        k += 1;
        let from = k;
        while k < b.len() && b[k].is_ascii_digit() {
            k += 1;
        }
        if k == from {
            return None;
        }
    }
    let offset_s = match b.get(k..)? {
        [b'Z' | b'z'] => 0,
        [sign @ (b'+' | b'-'), _, _, b':', _, _] => {
            let (oh, om) = (num(k + 1..k + 3)?, num(k + 4..k + 6)?);
            if oh > 23 || om > 59 {
                return None;
            }
            let o = oh * 3600 + om * 60;
            if *sign == b'-' { -o } else { o }
        }
        _ => return None,
    };
    let leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    let days_in = [
        31,
        if leap { 29 } else { 28 },
        31,
        30,
        31,
        30,
        31,
        31,
        30,
        31,
        30,
        31,
    ];
    if !(1..=12).contains(&mo) || d < 1 || d > days_in[(mo - 1) as usize] {
        return None;
    }
    if h > 23 || mi > 59 || sec > 60 {
        return None;
    }
    let days = crate::civil::days_from_civil(y, mo, d);
    Some(days * 86_400 + h * 3600 + mi * 60 + sec - offset_s)
}

/// The RFC 3339 text of a time in Unix seconds, UTC (`2026-12-03T17:00:00Z`): what
/// [`parse_rfc3339`] reads back.
///
/// ```
/// use skyplan_map::nofly::{parse_rfc3339, rfc3339_from_unix_s};
/// assert_eq!(rfc3339_from_unix_s(951_868_800), "2000-03-01T00:00:00Z");
/// assert_eq!(parse_rfc3339(&rfc3339_from_unix_s(1_796_317_200)), Some(1_796_317_200));
/// ```
pub fn rfc3339_from_unix_s(unix_s: i64) -> String {
    let (days, s) = (unix_s.div_euclid(86_400), unix_s.rem_euclid(86_400));
    let (y, m, d) = crate::civil::civil_from_days(days);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn collection(features: &str) -> String {
        format!(r#"{{"type": "FeatureCollection", "features": [{features}]}}"#)
    }

    fn error_of(features: &str) -> String {
        parse_no_fly(&collection(features))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    }

    const SQUARE: &str = r#"{"type": "Polygon", "coordinates": [[[-122.39, 37.79], [-122.389, 37.79], [-122.389, 37.791], [-122.39, 37.79]]]}"#;

    #[test]
    fn bad_zones_name_feature_field_and_expectation() {
        let point = r#"{"type": "Point", "coordinates": [-122.39, 37.79]}"#;
        let cases = [
            (
                format!(r#"{{"type": "Feature", "properties": {{"floor_m": 0}}, "geometry": {SQUARE}}}"#),
                "feature 0, properties.ceiling_m: missing: expected the zone's altitude band",
            ),
            (
                format!(r#"{{"type": "Feature", "properties": {{"floor_m": 50, "ceiling_m": 20}}, "geometry": {SQUARE}}}"#),
                "feature 0, properties.ceiling_m: 20 m: expected above floor_m (50 m)",
            ),
            (
                format!(r#"{{"type": "Feature", "properties": {{"floor_m": 0, "ceiling_m": 20, "radius_m": -3}}, "geometry": {point}}}"#),
                "feature 0, properties.radius_m: expected a number of metres ≥ 0",
            ),
            (
                format!(r#"{{"type": "Feature", "properties": {{"floor_m": 0, "ceiling_m": 20, "reference": "agl"}}, "geometry": {SQUARE}}}"#),
                "feature 0, properties.reference: expected \"home\" or \"amsl\", found \"agl\"",
            ),
            (
                format!(r#"{{"type": "Feature", "properties": {{"floor_m": 0, "ceiling_m": 20, "start": "tomorrow"}}, "geometry": {SQUARE}}}"#),
                "feature 0, properties.start: expected an RFC 3339 time",
            ),
            (
                format!(r#"{{"type": "Feature", "properties": {{"floor_m": 0, "ceiling_m": 20, "start": "2026-12-03T18:00:00Z", "end": "2026-12-03T17:00:00Z"}}, "geometry": {SQUARE}}}"#),
                "feature 0, properties.end: expected after start",
            ),
            (
                format!(r#"{{"type": "Feature", "properties": {{"inclusion": "yes"}}, "geometry": {SQUARE}}}"#),
                "feature 0, properties.inclusion: expected true or false, found \"yes\"",
            ),
            (
                r#"{"type": "Feature", "properties": {"floor_m": 0, "ceiling_m": 20}, "geometry": {"type": "LineString", "coordinates": []}}"#.to_string(),
                "feature 0, geometry.type: expected \"Polygon\" or \"Point\" (with radius_m), found \"LineString\"",
            ),
            (
                r#"{"type": "Feature", "properties": {"floor_m": 0, "ceiling_m": 20}, "geometry": null}"#.to_string(),
                "feature 0, geometry: the feature has no geometry",
            ),
            (
                r#"{"type": "Feature", "properties": {"floor_m": 0, "ceiling_m": 20, "radius_m": 5}, "geometry": {"type": "Point", "coordinates": [37.79, -122.39]}}"#.to_string(),
                "feature 0, geometry.coordinates: [37.79, -122.39]: expected longitude within ±180° and latitude within ±90°; longitude and latitude look swapped",
            ),
        ];
        for (feature, want) in cases {
            // As the second feature too: the index is the feature's.
            let ok = format!(
                r#"{{"type": "Feature", "properties": {{"inclusion": true}}, "geometry": {SQUARE}}}"#
            );
            let got = error_of(&feature);
            assert!(got.starts_with(want), "{got}\nwanted {want}");
            let got = error_of(&format!("{ok}, {feature}"));
            assert!(
                got.starts_with(&want.replacen("feature 0", "feature 1", 1)),
                "{got}"
            );
        }
        assert!(error_of("").contains("no features"));
        assert!(parse_no_fly("{").is_err_and(|e| e.field == "JSON"));
    }

    #[test]
    fn amsl_needs_the_home_altitude_and_subtracts_it() {
        let text = collection(&format!(
            r#"{{"type": "Feature", "properties": {{"floor_m": 100, "ceiling_m": 150, "reference": "amsl", "start": "2026-12-03T17:00:00Z"}}, "geometry": {SQUARE}}}"#
        ));
        let zones = parse_no_fly(&text).unwrap();
        let home = GeodeticHome {
            lat_deg: 37.79,
            lon_deg: -122.39,
        };
        let e = zones.project(home, None).unwrap_err();
        assert_eq!(e.feature, Some(0));
        assert_eq!(e.field, "properties.reference");
        let z = &zones.project(home, Some(30.0)).unwrap()[0];
        assert_eq!((z.floor_m, z.ceiling_m), (70.0, 120.0));
        let t = parse_rfc3339("2026-12-03T17:00:00Z");
        assert!(z.active_at(t) && z.active_at(None));
        assert!(!z.active_at(t.map(|t| t - 1)));
        // 0.001° of longitude at 37.79° N is about 87.9 m east.
        let ZoneShape::Polygon(rings) = &z.shape else {
            panic!("a polygon")
        };
        assert!((rings[0][1][1] - 87.9).abs() < 0.2, "{:?}", rings[0][1]);
    }

    #[test]
    fn qgc_plan_geofence_is_read_with_its_inclusion_flags() {
        let plan = r#"{"fileType": "Plan", "geoFence": {"version": 2,
            "polygons": [{"inclusion": true, "polygon": [[37.79, -122.40], [37.80, -122.40], [37.80, -122.39]], "version": 1}],
            "circles": [{"circle": {"center": [37.795, -122.395], "radius": 30.5}, "inclusion": false, "version": 1}]},
            "mission": {}, "version": 1}"#;
        let z = parse_no_fly(plan).unwrap().zones;
        assert_eq!(z.len(), 2);
        assert_eq!(
            z[0].shape,
            ZoneShape::Polygon(vec![vec![
                [-122.40, 37.79],
                [-122.40, 37.80],
                [-122.39, 37.80]
            ]])
        );
        assert!(z[0].inclusion && !z[1].inclusion);
        assert_eq!(
            z[1].shape,
            ZoneShape::Circle {
                centre: [-122.395, 37.795],
                radius_m: 30.5
            }
        );
        assert_eq!(
            (z[1].feature, z[1].floor_m, z[1].ceiling_m),
            (1, 0.0, f64::INFINITY)
        );
        for (bad, want) in [
            (
                r#"{"fileType": "Plan", "mission": {}}"#,
                "geoFence: a .plan file without a geoFence",
            ),
            (
                r#"{"fileType": "Plan", "geoFence": {"circles": [], "polygons": []}}"#,
                "geoFence: the fence has no polygons and no circles",
            ),
            (
                r#"{"fileType": "Plan", "geoFence": {"circles": [{"circle": {"center": [37.7, -122.4], "radius": 0}}]}}"#,
                "geoFence.circles[0].circle.radius: expected a radius in metres > 0",
            ),
            (
                r#"{"fileType": "Plan", "geoFence": {"polygons": [{"polygon": [[37.7, -122.4], [37.8, -122.4], [-122.3, 37.8]]}]}}"#,
                "geoFence.polygons[0].polygon[2]: expected [latitude, longitude]",
            ),
            (
                r#"{"fileType": "Plan", "geoFence": {"polygons": [{"polygon": [[0, 0], [1, 1], [0, 1], [1, 0]]}]}}"#,
                "geoFence.polygons[0].polygon: the polygon crosses or touches itself",
            ),
        ] {
            let e = parse_no_fly(bad).unwrap_err().to_string();
            assert!(e.starts_with(want), "{e}\nwanted {want}");
        }
    }

    #[test]
    fn segment_clearance_agrees_with_dense_sampling() {
        // SplitMix64: uniform numbers in [-10, 40).
        let mut state = 7u64;
        let mut uniform = || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            -10.0 + 50.0 * ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        // An L-shaped polygon with a square hole, and a disc.
        let l_shape = vec![
            vec![
                [0.0, 0.0],
                [0.0, 30.0],
                [10.0, 30.0],
                [10.0, 10.0],
                [30.0, 10.0],
                [30.0, 0.0],
            ],
            vec![[2.0, 2.0], [2.0, 6.0], [6.0, 6.0], [6.0, 2.0]],
        ];
        let zone = |shape| Zone {
            feature: 0,
            shape,
            floor_m: 0.0,
            ceiling_m: 10.0,
            inclusion: false,
            start_unix_s: None,
            end_unix_s: None,
        };
        let zones = [
            zone(ZoneShape::Polygon(l_shape.clone())),
            zone(ZoneShape::Circle {
                centre: [15.0, 15.0],
                radius_m: 4.0,
            }),
        ];
        // A point's distance to the zone: 0 inside (even-odd), else to the nearest edge.
        let point_m = |z: &Zone, p: [f64; 2]| match &z.shape {
            ZoneShape::Circle { centre, radius_m } => {
                ((p[0] - centre[0]).hypot(p[1] - centre[1]) - radius_m).max(0.0)
            }
            ZoneShape::Polygon(rings) => {
                let mut odd = false;
                let mut d = f64::INFINITY;
                for ring in rings {
                    for k in 0..ring.len() {
                        let (c, e) = (ring[k], ring[(k + 1) % ring.len()]);
                        d = d.min(point_segment_m(p, c, e));
                        if (c[0] > p[0]) != (e[0] > p[0])
                            && p[1] < c[1] + (p[0] - c[0]) / (e[0] - c[0]) * (e[1] - c[1])
                        {
                            odd = !odd;
                        }
                    }
                }
                if odd { 0.0 } else { d }
            }
        };
        for _ in 0..400 {
            let (a, b) = ([uniform(), uniform()], [uniform(), uniform()]);
            for z in &zones {
                let n = 20_000;
                let sampled = (0..=n)
                    .map(|k| {
                        let t = f64::from(k) / f64::from(n);
                        point_m(z, [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
                    })
                    .fold(f64::INFINITY, f64::min);
                let exact = z.clearance_m(a, b);
                // Sampling finds no less than the truth, and at most a step's length more.
                let step = (b[0] - a[0]).hypot(b[1] - a[1]) / f64::from(n);
                assert!(
                    exact <= sampled + 1e-9 && sampled <= exact + step,
                    "{a:?} {b:?}: {exact} vs {sampled}"
                );
            }
        }
    }

    #[test]
    fn rfc3339_text_round_trips() {
        for t in (-3_000_000_000i64..5_000_000_000).step_by(7_777_777) {
            assert_eq!(parse_rfc3339(&rfc3339_from_unix_s(t)), Some(t), "{t}");
        }
    }

    #[test]
    fn rfc3339_against_known_instants() {
        // Values from `date -u -d … +%s`.
        for (s, want) in [
            ("2026-12-03T17:00:00Z", 1_796_317_200),
            ("2024-02-29T23:59:59.999Z", 1_709_251_199),
            ("1969-12-31T23:59:59Z", -1),
            ("2026-12-03T12:00:00-05:00", 1_796_317_200),
        ] {
            assert_eq!(parse_rfc3339(s), Some(want), "{s}");
        }
        for s in [
            "2026-12-03",
            "2026-13-01T00:00:00Z",
            "2023-02-29T00:00:00Z",
            "2026-12-03T17:00:00",
            "2026-12-03T17:00:00+0100",
            "2026-12-03T24:00:00Z",
        ] {
            assert_eq!(parse_rfc3339(s), None, "{s}");
        }
    }
}
