//! Building footprints from GeoJSON (RFC 7946): a `FeatureCollection` of `Polygon` and
//! `MultiPolygon` features in longitude/latitude, each a prism from `min_height` to its height.
//!
//! Parsing ([`parse_geojson`]) checks the geometry and reads the heights; projecting
//! ([`GeoFootprints::project`]) turns every ring into local metres north/east of a home (the
//! data's bounding-box centre unless one is given) with `skyplan-frames`.
//!
//! Heights, metres above home: the property `height` (a number, or a numeric string with an
//! optional `m` suffix), else `building:levels` × [`METRES_PER_LEVEL`], else the default height
//! (counted in [`GeoFootprints::default_heights`]; above `min_height` when one is given);
//! `min_height` (same forms, default 0) is the prism's floor.
//!
//! ```
//! use skyplan_map::footprints::{parse_geojson, DEFAULT_HEIGHT_M};
//! let text = r#"{"type": "FeatureCollection", "features": [
//!   {"type": "Feature", "properties": {"building:levels": "4"},
//!    "geometry": {"type": "Polygon", "coordinates":
//!      [[[-122.3975, 37.7925], [-122.3974, 37.7925], [-122.3974, 37.7926], [-122.3975, 37.7925]]]}}]}"#;
//! let geo = parse_geojson(text, DEFAULT_HEIGHT_M)?;
//! assert_eq!(geo.buildings[0].height_m, 12.0);
//! let map = geo.project(None).unwrap();
//! assert_eq!(map.footprints[0].rings[0].len(), 3); // the closing position is dropped
//! # Ok::<(), skyplan_map::footprints::FootprintError>(())
//! ```

use crate::colliders::GeodeticHome;
use serde_json::Value;
use skyplan_frames::{Lla, LocalFrame};
use std::fmt;

/// Metres per storey when a height comes from `building:levels`.
pub const METRES_PER_LEVEL: f64 = 3.0;
/// The height of a building that gives neither `height` nor `building:levels`, metres.
pub const DEFAULT_HEIGHT_M: f64 = 10.0;
/// Most positions a file may hold (all rings of all features together).
pub const MAX_VERTICES: usize = 1_000_000;

/// A footprint file that could not be read: which feature, which field, what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct FootprintError {
    /// 0-based index of the feature in `features`, or `None` for the file as a whole.
    pub feature: Option<usize>,
    /// The field, as a path inside the feature (`geometry.coordinates[0][3]`).
    pub field: String,
    /// What was expected and what was found.
    pub message: String,
}

impl fmt::Display for FootprintError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.feature {
            Some(i) => write!(f, "feature {i}, {}: {}", self.field, self.message),
            None => write!(f, "{}: {}", self.field, self.message),
        }
    }
}

pub(crate) fn err(
    feature: Option<usize>,
    field: impl Into<String>,
    message: impl Into<String>,
) -> FootprintError {
    FootprintError {
        feature,
        field: field.into(),
        message: message.into(),
    }
}

/// Where a building's height came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeightSource {
    /// The `height` property.
    Height,
    /// `building:levels` × [`METRES_PER_LEVEL`].
    Levels,
    /// Neither was given: the default height.
    Default,
}

/// One polygon in longitude/latitude: the outer ring, then its holes; each ring closed in the
/// file, stored here without its closing position (≥ 3 distinct positions `[lon, lat]`).
pub type GeoPolygon = Vec<Vec<[f64; 2]>>;

/// One feature of the file: its polygons and its height band.
#[derive(Debug, Clone, PartialEq)]
pub struct GeoBuilding {
    /// 0-based index of the feature in the file.
    pub feature: usize,
    /// The polygons (one for a `Polygon`, any number for a `MultiPolygon`).
    pub polygons: Vec<GeoPolygon>,
    /// Floor of the prism, metres above home.
    pub min_height_m: f64,
    /// Top of the prism, metres above home.
    pub height_m: f64,
    /// Where `height_m` came from.
    pub height_source: HeightSource,
}

/// A parsed footprint file, still in longitude/latitude.
#[derive(Debug, Clone, PartialEq)]
pub struct GeoFootprints {
    /// The buildings, in file order.
    pub buildings: Vec<GeoBuilding>,
    /// How many buildings got the default height.
    pub default_heights: usize,
    /// The default height used, metres.
    pub default_height_m: f64,
    /// All positions read (closing positions included).
    pub vertices: usize,
}

/// One footprint in the local frame: a polygon with holes and its height band.
#[derive(Debug, Clone, PartialEq)]
pub struct Footprint {
    /// The feature it came from (0-based index in the file).
    pub feature: usize,
    /// Rings as `[north_m, east_m]` about the home, outer first, then holes, without closing
    /// positions.
    pub rings: Vec<Vec<[f64; 2]>>,
    /// Floor of the prism, metres above home.
    pub min_height_m: f64,
    /// Top of the prism, metres above home.
    pub height_m: f64,
}

impl Footprint {
    /// Whether the prism grown by `margin_m` vertically meets the horizontal plane at `alt_m`
    /// (open interval, as [`ObstacleBox::meets_altitude`](crate::colliders::ObstacleBox::meets_altitude)).
    pub fn meets_altitude(&self, alt_m: f64, margin_m: f64) -> bool {
        self.height_m + margin_m > alt_m && self.min_height_m - margin_m < alt_m
    }

    /// The horizontal bounding box `([north_min, east_min], [north_max, east_max])`, metres.
    pub fn bbox_ne(&self) -> ([f64; 2], [f64; 2]) {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in self.rings.iter().flatten() {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }
}

/// Footprints in the local frame about a geodetic home (one [`Footprint`] per polygon).
#[derive(Debug, Clone, PartialEq)]
pub struct FootprintMap {
    /// The home: origin of the local frame.
    pub home: GeodeticHome,
    /// The footprints, in file order (a `MultiPolygon` gives several).
    pub footprints: Vec<Footprint>,
    /// How many buildings got the default height.
    pub default_heights: usize,
}

impl FootprintMap {
    /// The horizontal bounding box of every footprint, `([north_min, east_min], [north_max,
    /// east_max])`, metres (infinite for a map without footprints).
    pub fn bbox_ne(&self) -> ([f64; 2], [f64; 2]) {
        self.footprints.iter().map(Footprint::bbox_ne).fold(
            ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
            |(lo, hi), (l, h)| {
                (
                    [lo[0].min(l[0]), lo[1].min(l[1])],
                    [hi[0].max(h[0]), hi[1].max(h[1])],
                )
            },
        )
    }
}

impl GeoFootprints {
    /// The centre of the longitude/latitude bounding box of every position (`None` without
    /// buildings).
    pub fn bbox_centre(&self) -> Option<GeodeticHome> {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in self
            .buildings
            .iter()
            .flat_map(|b| b.polygons.iter().flatten().flatten())
        {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo[0] <= hi[0]).then(|| GeodeticHome {
            lon_deg: 0.5 * (lo[0] + hi[0]),
            lat_deg: 0.5 * (lo[1] + hi[1]),
        })
    }

    /// Every polygon in local metres about `home` (default: [`GeoFootprints::bbox_centre`]).
    /// Fails when the home is not a valid UTM position or a position is too far from it
    /// (another UTM zone or hemisphere), naming the feature.
    pub fn project(&self, home: Option<GeodeticHome>) -> Result<FootprintMap, FootprintError> {
        let home = home.or_else(|| self.bbox_centre()).ok_or_else(|| {
            err(
                None,
                "features",
                "no building to place a home at; give a home",
            )
        })?;
        let frame = LocalFrame::new(Lla {
            lat_deg: home.lat_deg,
            lon_deg: home.lon_deg,
            alt_m: 0.0,
        })
        .map_err(|e| err(None, "home", e.to_string()))?;
        let mut footprints = Vec::new();
        for b in &self.buildings {
            for (pi, polygon) in b.polygons.iter().enumerate() {
                let mut rings = Vec::with_capacity(polygon.len());
                for ring in polygon {
                    let local = ring
                        .iter()
                        .map(|&[lon_deg, lat_deg]| {
                            frame
                                .ned_from_lla(Lla {
                                    lat_deg,
                                    lon_deg,
                                    alt_m: 0.0,
                                })
                                .map(|n| [n.north_m, n.east_m])
                        })
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(|e| {
                            err(Some(b.feature), format!("polygon {pi}"), e.to_string())
                        })?;
                    rings.push(local);
                }
                footprints.push(Footprint {
                    feature: b.feature,
                    rings,
                    min_height_m: b.min_height_m,
                    height_m: b.height_m,
                });
            }
        }
        Ok(FootprintMap {
            home,
            footprints,
            default_heights: self.default_heights,
        })
    }
}

/// Parses a GeoJSON `FeatureCollection` of building footprints; `default_height_m` is the height
/// of buildings that give none.
///
/// Refused, naming the feature and the field: text that is not JSON, a feature without
/// geometry or of another geometry type, a ring with fewer than 4 positions or not closed
/// (first ≠ last), a ring that crosses or touches itself, a longitude outside ±180° or a
/// latitude outside ±90° (with a hint when the two look swapped), a height that is not a
/// non-negative number, `min_height` not below the height, more than [`MAX_VERTICES`]
/// positions.
///
/// ```
/// use skyplan_map::footprints::{parse_geojson, DEFAULT_HEIGHT_M};
/// let swapped = r#"{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {},
///   "geometry": {"type": "Polygon", "coordinates": [[[37.79, -122.39], [37.8, -122.39], [37.8, -122.38], [37.79, -122.39]]]}}]}"#;
/// let e = parse_geojson(swapped, DEFAULT_HEIGHT_M).unwrap_err();
/// assert_eq!(e.feature, Some(0));
/// assert!(e.to_string().contains("swapped"), "{e}");
/// ```
pub fn parse_geojson(text: &str, default_height_m: f64) -> Result<GeoFootprints, FootprintError> {
    parse_geojson_bytes(text.as_bytes(), default_height_m)
}

/// [`parse_geojson`] from bytes (UTF-8).
pub fn parse_geojson_bytes(
    bytes: &[u8],
    default_height_m: f64,
) -> Result<GeoFootprints, FootprintError> {
    if !(default_height_m.is_finite() && default_height_m >= 0.0) {
        return Err(err(
            None,
            "default height",
            format!("{default_height_m} m: expected a finite height ≥ 0"),
        ));
    }
    let root = json_root(bytes)?;
    let features = feature_list(&root)?;
    let mut out = GeoFootprints {
        buildings: Vec::with_capacity(features.len()),
        default_heights: 0,
        default_height_m,
        vertices: 0,
    };
    for (i, f) in features.iter().enumerate() {
        let building = parse_feature(i, f, default_height_m, &mut out.vertices)?;
        if building.height_source == HeightSource::Default {
            out.default_heights += 1;
        }
        out.buildings.push(building);
    }
    if out.buildings.is_empty() {
        return Err(err(
            None,
            "features",
            "the collection has no features; expected at least one building",
        ));
    }
    Ok(out)
}

/// A JSON document (UTF-8 bytes), or an error naming the line and column.
pub(crate) fn json_root(bytes: &[u8]) -> Result<Value, FootprintError> {
    serde_json::from_slice(bytes).map_err(|e| {
        err(
            None,
            "JSON",
            format!(
                "line {}, column {}: {}",
                e.line(),
                e.column(),
                json_reason(&e)
            ),
        )
    })
}

/// The features of a GeoJSON FeatureCollection, or an error naming what the document is instead.
pub(crate) fn feature_list(root: &Value) -> Result<&Vec<Value>, FootprintError> {
    let kind = root.get("type").and_then(Value::as_str);
    if kind != Some("FeatureCollection") {
        return Err(err(
            None,
            "type",
            format!(
                "expected \"FeatureCollection\", found {}",
                kind.map_or_else(|| "none".to_string(), |k| format!("\"{}\"", shorten(k)))
            ),
        ));
    }
    root.get("features")
        .and_then(Value::as_array)
        .ok_or_else(|| err(None, "features", "expected an array of features"))
}

pub(crate) fn json_reason(e: &serde_json::Error) -> String {
    // serde_json's message ends with " at line L column C"; the place is given separately.
    let s = e.to_string();
    match s.find(" at line ") {
        Some(k) => s[..k].to_string(),
        None => s,
    }
}

pub(crate) fn shorten(s: &str) -> String {
    const MAX: usize = 40;
    let mut out: String = s.chars().take(MAX).collect();
    if s.chars().count() > MAX {
        out.push('…');
    }
    out
}

fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

pub(crate) fn parse_feature(
    i: usize,
    f: &Value,
    default_height_m: f64,
    vertices: &mut usize,
) -> Result<GeoBuilding, FootprintError> {
    let at = Some(i);
    if f.get("type").and_then(Value::as_str) != Some("Feature") {
        return Err(err(at, "type", "expected \"Feature\""));
    }
    let geometry = match f.get("geometry") {
        None | Some(Value::Null) => {
            return Err(err(
                at,
                "geometry",
                "the feature has no geometry; expected a Polygon or MultiPolygon",
            ));
        }
        Some(g) => g,
    };
    let gtype = geometry.get("type").and_then(Value::as_str).unwrap_or("");
    let coords = geometry
        .get("coordinates")
        .ok_or_else(|| err(at, "geometry.coordinates", "missing"))?;
    let polygons = match gtype {
        "Polygon" => vec![parse_polygon(i, coords, "geometry.coordinates", vertices)?],
        "MultiPolygon" => {
            let list = coords.as_array().ok_or_else(|| {
                err(
                    at,
                    "geometry.coordinates",
                    format!("expected an array of polygons, found {}", kind_of(coords)),
                )
            })?;
            if list.is_empty() {
                return Err(err(
                    at,
                    "geometry.coordinates",
                    "expected at least one polygon",
                ));
            }
            list.iter()
                .enumerate()
                .map(|(k, p)| parse_polygon(i, p, &format!("geometry.coordinates[{k}]"), vertices))
                .collect::<Result<_, _>>()?
        }
        other => {
            return Err(err(
                at,
                "geometry.type",
                format!(
                    "expected \"Polygon\" or \"MultiPolygon\", found \"{}\"",
                    shorten(other)
                ),
            ));
        }
    };
    let props = f.get("properties").filter(|p| !p.is_null());
    let prop = |name: &str| props.and_then(|p| p.get(name)).filter(|v| !v.is_null());
    let min_height_m = match prop("min_height") {
        Some(v) => metres(i, "properties.min_height", v)?,
        None => 0.0,
    };
    let (height_m, height_source) = if let Some(v) = prop("height") {
        (metres(i, "properties.height", v)?, HeightSource::Height)
    } else if let Some(v) = prop("building:levels") {
        (
            metres(i, "properties.building:levels", v)? * METRES_PER_LEVEL,
            HeightSource::Levels,
        )
    } else {
        // A raised part without a height (OpenStreetMap has them): the default above its floor.
        (min_height_m + default_height_m, HeightSource::Default)
    };
    if min_height_m >= height_m {
        return Err(err(
            at,
            "properties.min_height",
            format!("{min_height_m} m: expected below the building's height ({height_m} m)"),
        ));
    }
    Ok(GeoBuilding {
        feature: i,
        polygons,
        min_height_m,
        height_m,
        height_source,
    })
}

/// A non-negative finite number, or a string holding one (optionally ending in `m`).
pub(crate) fn metres(i: usize, field: &str, v: &Value) -> Result<f64, FootprintError> {
    let x = match v {
        Value::Number(n) => n.as_f64(),
        Value::String(s) => {
            let t = s.trim();
            let t = t.strip_suffix('m').map_or(t, str::trim_end);
            t.parse::<f64>().ok()
        }
        _ => None,
    };
    match x {
        Some(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(err(
            Some(i),
            field,
            format!(
                "expected a number of metres ≥ 0 (or a string holding one), found {}",
                shown(v)
            ),
        )),
    }
}

pub(crate) fn shown(v: &Value) -> String {
    match v {
        Value::String(s) => format!("\"{}\"", shorten(s)),
        Value::Number(n) => n.to_string(),
        other => kind_of(other).to_string(),
    }
}

pub(crate) fn parse_polygon(
    i: usize,
    v: &Value,
    field: &str,
    vertices: &mut usize,
) -> Result<GeoPolygon, FootprintError> {
    let at = Some(i);
    let rings = v.as_array().ok_or_else(|| {
        err(
            at,
            field,
            format!("expected an array of rings, found {}", kind_of(v)),
        )
    })?;
    if rings.is_empty() {
        return Err(err(at, field, "expected at least the outer ring"));
    }
    let mut out = Vec::with_capacity(rings.len());
    for (r, ring) in rings.iter().enumerate() {
        let rfield = format!("{field}[{r}]");
        let positions = ring.as_array().ok_or_else(|| {
            err(
                at,
                &rfield,
                format!("expected an array of positions, found {}", kind_of(ring)),
            )
        })?;
        *vertices = vertices.saturating_add(positions.len());
        if *vertices > MAX_VERTICES {
            return Err(err(
                at,
                &rfield,
                format!(
                    "the file has more than {MAX_VERTICES} positions; split it or simplify the footprints"
                ),
            ));
        }
        if positions.len() < 4 {
            return Err(err(
                at,
                &rfield,
                format!(
                    "a ring needs at least 4 positions (the first repeated at the end), found {}",
                    positions.len()
                ),
            ));
        }
        let mut pts = Vec::with_capacity(positions.len());
        for (k, p) in positions.iter().enumerate() {
            pts.push(position(i, p, &format!("{rfield}[{k}]"))?);
        }
        if pts[0] != pts[pts.len() - 1] {
            return Err(err(
                at,
                &rfield,
                format!(
                    "the ring is not closed: the last position [{}, {}] must repeat the first [{}, {}]",
                    pts[pts.len() - 1][0],
                    pts[pts.len() - 1][1],
                    pts[0][0],
                    pts[0][1]
                ),
            ));
        }
        pts.pop();
        pts.dedup();
        while pts.len() > 1 && pts.first() == pts.last() {
            pts.pop();
        }
        if pts.len() < 3 {
            return Err(err(
                at,
                &rfield,
                "the ring has fewer than 3 distinct positions",
            ));
        }
        if let Some((a, b)) = self_intersection(&pts) {
            return Err(err(
                at,
                &rfield,
                format!(
                    "the ring crosses or touches itself: its edges {a} and {b} meet (edge k joins positions k and k+1)"
                ),
            ));
        }
        out.push(pts);
    }
    Ok(out)
}

pub(crate) fn position(i: usize, p: &Value, field: &str) -> Result<[f64; 2], FootprintError> {
    let at = Some(i);
    let arr = p.as_array().filter(|a| a.len() >= 2).ok_or_else(|| {
        err(
            at,
            field,
            format!(
                "expected a position [longitude, latitude], found {}",
                kind_of(p)
            ),
        )
    })?;
    let num = |k: usize, name: &str| {
        arr[k].as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
            err(
                at,
                field,
                format!("{name}: expected a finite number, found {}", shown(&arr[k])),
            )
        })
    };
    let lon = num(0, "longitude")?;
    let lat = num(1, "latitude")?;
    let lon_ok = (-180.0..=180.0).contains(&lon);
    let lat_ok = (-90.0..=90.0).contains(&lat);
    if !(lon_ok && lat_ok) {
        let swapped = (-180.0..=180.0).contains(&lat) && (-90.0..=90.0).contains(&lon);
        let hint = if swapped {
            "; longitude and latitude look swapped (GeoJSON positions are [longitude, latitude])"
        } else {
            ""
        };
        return Err(err(
            at,
            field,
            format!(
                "[{lon}, {lat}]: expected longitude within ±180° and latitude within ±90°{hint}"
            ),
        ));
    }
    Ok([lon, lat])
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn on_segment(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// Whether closed segments `ab` and `cd` share a point.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0))
        && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0))
    {
        return true;
    }
    (o1 == 0.0 && on_segment(a, b, c))
        || (o2 == 0.0 && on_segment(a, b, d))
        || (o3 == 0.0 && on_segment(c, d, a))
        || (o4 == 0.0 && on_segment(c, d, b))
}

/// Two edges of a ring (no closing position; edge k joins k and k+1 mod n) that meet other
/// than at the vertex two neighbouring edges share, if any.
pub(crate) fn self_intersection(pts: &[[f64; 2]]) -> Option<(usize, usize)> {
    let n = pts.len();
    let seg = |k: usize| (pts[k], pts[(k + 1) % n]);
    // Neighbouring edges share a vertex; they are wrong only when they fold back over each other.
    for k in 0..n {
        let (a, b) = seg(k);
        let c = pts[(k + 2) % n];
        let dot = (a[0] - b[0]) * (c[0] - b[0]) + (a[1] - b[1]) * (c[1] - b[1]);
        if orient(a, b, c) == 0.0 && dot > 0.0 {
            return Some((k, (k + 1) % n));
        }
    }
    let adjacent = |i: usize, j: usize| j == i + 1 || (i == 0 && j == n - 1);
    let check = |i: usize, j: usize| {
        let (i, j) = (i.min(j), i.max(j));
        if i == j || adjacent(i, j) {
            return None;
        }
        let (a, b) = seg(i);
        let (c, d) = seg(j);
        segments_meet(a, b, c, d).then_some((i, j))
    };
    if n <= 64 {
        return (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .find_map(|(i, j)| check(i, j));
    }
    // Larger rings: bucket the edges on a grid of about n cells over the ring's box and compare
    // only edges that share a bucket.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in pts {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let side = ((n as f64).sqrt().ceil() as usize).max(1);
    let cell = |x: f64, k: usize| -> usize {
        let w = hi[k] - lo[k];
        if w <= 0.0 {
            return 0;
        }
        (((x - lo[k]) / w * side as f64) as usize).min(side - 1)
    };
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); side * side];
    for k in 0..n {
        let (a, b) = seg(k);
        let (x0, x1) = (cell(a[0].min(b[0]), 0), cell(a[0].max(b[0]), 0));
        let (y0, y1) = (cell(a[1].min(b[1]), 1), cell(a[1].max(b[1]), 1));
        for y in y0..=y1 {
            for x in x0..=x1 {
                buckets[y * side + x].push(k as u32);
            }
        }
    }
    buckets.iter().find_map(|b| {
        b.iter().enumerate().find_map(|(p, &i)| {
            b[p + 1..]
                .iter()
                .find_map(|&j| check(i as usize, j as usize))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn collection(features: &str) -> String {
        format!(r#"{{"type": "FeatureCollection", "features": [{features}]}}"#)
    }

    fn square(props: &str) -> String {
        format!(
            r#"{{"type": "Feature", "properties": {props}, "geometry": {{"type": "Polygon", "coordinates": [[[-122.3975, 37.7925], [-122.3974, 37.7925], [-122.3974, 37.7926], [-122.3975, 37.7926], [-122.3975, 37.7925]]]}}}}"#
        )
    }

    fn parse(t: &str) -> Result<GeoFootprints, FootprintError> {
        parse_geojson(t, DEFAULT_HEIGHT_M)
    }

    #[test]
    fn heights_from_each_source() {
        let t = collection(
            &[
                square(r#"{"height": 25.5, "min_height": "5"}"#),
                square(r#"{"height": "30 m", "building:levels": 2}"#),
                square(r#"{"building:levels": "7"}"#),
                square("null"),
            ]
            .join(","),
        );
        let g = parse(&t).unwrap();
        let h: Vec<_> = g
            .buildings
            .iter()
            .map(|b| (b.min_height_m, b.height_m, b.height_source))
            .collect();
        assert_eq!(
            h,
            [
                (5.0, 25.5, HeightSource::Height),
                (0.0, 30.0, HeightSource::Height),
                (0.0, 21.0, HeightSource::Levels),
                (0.0, 10.0, HeightSource::Default)
            ]
        );
        assert_eq!(g.default_heights, 1);
        assert_eq!(g.vertices, 20);
    }

    #[test]
    fn projection_puts_the_default_home_at_the_centre() {
        let g = parse(&collection(&square("{}"))).unwrap();
        let home = g.bbox_centre().unwrap();
        assert!(
            (home.lat_deg - 37.79255).abs() < 1e-12 && (home.lon_deg + 122.39745).abs() < 1e-12
        );
        let m = g.project(None).unwrap();
        let (lo, hi) = m.bbox_ne();
        // 0.0001° of latitude is 11.1 m, of longitude 8.8 m here; centred within the UTM skew.
        assert!(((hi[0] - lo[0]) - 11.1).abs() < 0.1, "{lo:?} {hi:?}");
        assert!(((hi[1] - lo[1]) - 8.8).abs() < 0.1, "{lo:?} {hi:?}");
        assert!((lo[0] + hi[0]).abs() < 0.1 && (lo[1] + hi[1]).abs() < 0.1);
        // Another home moves every point by the same offset.
        let other = GeodeticHome {
            lat_deg: 37.7925,
            lon_deg: -122.3975,
        };
        let m2 = g.project(Some(other)).unwrap();
        assert!(
            m2.footprints[0].rings[0][0][0].abs() < 1e-6
                && m2.footprints[0].rings[0][0][1].abs() < 1e-6
        );
    }

    fn one_ring(coords: &str) -> String {
        collection(&format!(
            r#"{{"type": "Feature", "properties": {{}}, "geometry": {{"type": "Polygon", "coordinates": [{coords}]}}}}"#
        ))
    }

    fn error_of(t: &str) -> String {
        parse(t).unwrap_err().to_string()
    }

    #[test]
    fn bad_input_names_feature_field_and_expectation() {
        let cases = [
            (
                one_ring("[[0,0],[1,0],[1,1],[0,1]]"),
                "feature 0, geometry.coordinates[0]: the ring is not closed",
            ),
            (one_ring("[[0,0],[1,0],[0,0]]"), "at least 4 positions"),
            (
                one_ring("[[0,0],[1,1],[1,0],[0,1],[0,0]]"),
                "crosses or touches itself",
            ),
            (
                one_ring("[[0,0],[200,0],[1,1],[0,0]]"),
                "[200, 0]: expected longitude within ±180°",
            ),
            (
                one_ring("[[0,0],[\"a\",0],[1,1],[0,0]]"),
                "coordinates[0][1]: longitude: expected a finite number",
            ),
            (
                one_ring("[[0,0],[1,0],[2,0],[0,0]]"),
                "crosses or touches itself",
            ),
            (
                collection(r#"{"type": "Feature", "properties": {}, "geometry": null}"#),
                "feature 0, geometry: the feature has no geometry",
            ),
            (
                collection(
                    r#"{"type": "Feature", "geometry": {"type": "Point", "coordinates": [0, 0]}}"#,
                ),
                "found \"Point\"",
            ),
            (
                collection(&square(r#"{"height": -3}"#)),
                "properties.height: expected a number of metres ≥ 0",
            ),
            (
                collection(&square(r#"{"height": "tall"}"#)),
                "found \"tall\"",
            ),
            (
                collection(&square(r#"{"height": 5, "min_height": 5}"#)),
                "properties.min_height: 5 m: expected below",
            ),
            (
                "{\"type\": \"Feature\"}".to_string(),
                "type: expected \"FeatureCollection\"",
            ),
            (
                "{\"type\": \"FeatureCollection\", \"features\": [".to_string(),
                "JSON: line 1",
            ),
            (collection(""), "no features"),
        ];
        for (text, want) in cases {
            let got = error_of(&text);
            assert!(
                got.contains(want),
                "got {got:?}, expected it to contain {want:?}"
            );
        }
        // The second feature is the bad one.
        let two = collection(&[square("{}"), square(r#"{"building:levels": []}"#)].join(","));
        assert!(error_of(&two).starts_with("feature 1, properties.building:levels"));
    }

    #[test]
    fn multipolygon_with_hole_and_vertex_bound() {
        let t = collection(
            r#"{"type": "Feature", "properties": {"height": 12}, "geometry": {"type": "MultiPolygon", "coordinates": [
              [[[0,0],[0.001,0],[0.001,0.001],[0,0.001],[0,0]], [[0.0002,0.0002],[0.0002,0.0004],[0.0004,0.0004],[0.0004,0.0002],[0.0002,0.0002]]],
              [[[0.002,0],[0.003,0],[0.003,0.001],[0.002,0]]]]}}"#,
        );
        let g = parse(&t).unwrap();
        assert_eq!(g.buildings[0].polygons.len(), 2);
        assert_eq!(g.buildings[0].polygons[0].len(), 2);
        assert_eq!(g.project(None).unwrap().footprints.len(), 2);
        // Over the bound: refused before more is read.
        let n = MAX_VERTICES / 4 + 1;
        let features: Vec<String> = (0..n)
            .map(|_| r#"{"type": "Feature", "geometry": {"type": "Polygon", "coordinates": [[[0,0],[1,0],[1,1],[0,0]]]}}"#.to_string())
            .collect();
        let e = parse(&collection(&features.join(","))).unwrap_err();
        assert!(e.to_string().contains("more than 1000000 positions"), "{e}");
        assert_eq!(e.feature, Some(n - 1));
    }

    /// The bucketed check agrees with the all-pairs one on rings above the brute-force size.
    #[test]
    fn bucketed_self_intersection_matches_all_pairs() {
        let mut state = 12345u64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for trial in 0..40 {
            let n = 70 + trial;
            // A star-shaped ring (simple), with one vertex sometimes moved to make it cross.
            let mut pts: Vec<[f64; 2]> = (0..n)
                .map(|k| {
                    let a = k as f64 / n as f64 * std::f64::consts::TAU;
                    let r = 1.0 + rnd();
                    [r * a.cos(), r * a.sin()]
                })
                .collect();
            if trial % 2 == 1 {
                let k = (rnd() * n as f64) as usize % n;
                pts[k] = [-pts[k][0] * 0.9, -pts[k][1] * 0.9];
            }
            let brute = (0..n).any(|i| {
                (i + 1..n).any(|j| {
                    let adjacent = j == i + 1 || (i == 0 && j == n - 1);
                    !adjacent && segments_meet(pts[i], pts[(i + 1) % n], pts[j], pts[(j + 1) % n])
                })
            });
            assert_eq!(self_intersection(&pts).is_some(), brute, "trial {trial}");
            if trial % 2 == 0 {
                assert!(!brute, "a star-shaped ring is simple");
            }
        }
    }
}
