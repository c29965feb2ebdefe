//! The vehicle's fence from no-fly zones, without I/O: what is uploaded, as which MAVLink items,
//! and how the read-back is checked.
//!
//! A fence travels over the mission protocol with `mission_type` FENCE (1): one
//! MISSION_ITEM_INT per polygon vertex (MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION 5001 /
//! _EXCLUSION 5002, `param1` = the polygon's vertex count, every vertex of a polygon in a row)
//! and one per circle (MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION 5003 / _EXCLUSION 5004, `param1` =
//! the radius in metres), latitude and longitude as degrees × 10⁷ in `MAV_FRAME_GLOBAL_INT`.
//!
//! **What a fence cannot carry.** A fence is 2D, for the whole flight, and its polygons have no
//! holes. [`fence_from_zones`] decides, zone by zone, and says what is lost
//! ([`FencePlan::notes`]); it never drops anything silently:
//! - zones are uploaded as the file gives them, not grown by the planning margin (the autopilot
//!   applies its own `FENCE_MARGIN`);
//! - an exclusion zone whose altitude band (grown by the margin) holds the route's altitudes is
//!   uploaded without its band: the fence keeps the vehicle out at every altitude;
//! - an exclusion zone whose band the route flies above or below is left out (uploaded, the
//!   fence would forbid the column the route legally crosses);
//! - an inclusion zone's band is lost (ArduPilot's altitude limits are parameters,
//!   `FENCE_ALT_MIN`/`FENCE_ALT_MAX`, which skyplan does not set);
//! - an inclusion polygon's holes become exclusion polygons (the same region in 2D);
//! - an exclusion polygon's holes cannot be carried: its outer ring is uploaded (the vehicle is
//!   kept out of the holes too) when the route does not enter that ring, and the fence is
//!   refused when it does (the vehicle's own fence would contradict the route);
//! - a time window (`start`/`end`) is lost: a stored fence holds until it is replaced.
//!
//! [`MissionDownload`] is the read-back, ground side: MISSION_REQUEST_LIST → MISSION_COUNT →
//! MISSION_REQUEST_INT per item → MISSION_ITEM_INT → MISSION_ACK, with retries;
//! [`verify_fence`] compares the items read back with the items sent, field by field.
//!
//! ```
//! use skyplan_flight::fence::{fence_items, FenceShape, CIRCLE_EXCLUSION};
//! let items = fence_items(&[FenceShape::Circle {
//!     inclusion: false, centre_lat_lon_deg: [37.7925, -122.3975], radius_m: 40.0 }]).unwrap();
//! assert_eq!((items[0].command, items[0].param1, items[0].lat_e7), (CIRCLE_EXCLUSION, 40.0, 377_925_000));
//! ```

use crate::executor::ConfigError;
use skyplan_map::nofly::{AltReference, NoFlyZones, ZoneShape};

/// MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION.
pub const POLYGON_VERTEX_INCLUSION: u16 = 5001;
/// MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION.
pub const POLYGON_VERTEX_EXCLUSION: u16 = 5002;
/// MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION.
pub const CIRCLE_INCLUSION: u16 = 5003;
/// MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION.
pub const CIRCLE_EXCLUSION: u16 = 5004;

/// The most vertices a fence polygon may have here (ArduPilot stores a fence in its EEPROM's
/// fence area: a few hundred points).
pub const MAX_POLYGON_VERTICES: usize = 1000;

/// One shape of the fence, in degrees.
#[derive(Debug, Clone, PartialEq)]
pub enum FenceShape {
    /// A polygon, vertices `[latitude, longitude]`, not closed.
    Polygon {
        /// Stay inside (`true`) or out.
        inclusion: bool,
        /// The vertices.
        vertices_lat_lon_deg: Vec<[f64; 2]>,
    },
    /// A circle.
    Circle {
        /// Stay inside (`true`) or out.
        inclusion: bool,
        /// The centre, `[latitude, longitude]`.
        centre_lat_lon_deg: [f64; 2],
        /// The radius, metres.
        radius_m: f64,
    },
}

/// One fence item as it goes on the wire (MISSION_ITEM_INT with `mission_type` FENCE).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FenceItem {
    /// Its index in the fence.
    pub seq: u16,
    /// The MAV_CMD: [`POLYGON_VERTEX_INCLUSION`], [`POLYGON_VERTEX_EXCLUSION`],
    /// [`CIRCLE_INCLUSION`] or [`CIRCLE_EXCLUSION`].
    pub command: u16,
    /// A vertex's polygon's vertex count, or a circle's radius in metres.
    pub param1: f32,
    /// Latitude, degrees × 10⁷.
    pub lat_e7: i32,
    /// Longitude, degrees × 10⁷.
    pub lon_e7: i32,
}

/// The name of a fence command, for messages.
pub fn command_name(command: u16) -> String {
    match command {
        POLYGON_VERTEX_INCLUSION => "POLYGON_VERTEX_INCLUSION".into(),
        POLYGON_VERTEX_EXCLUSION => "POLYGON_VERTEX_EXCLUSION".into(),
        CIRCLE_INCLUSION => "CIRCLE_INCLUSION".into(),
        CIRCLE_EXCLUSION => "CIRCLE_EXCLUSION".into(),
        other => format!("command {other}"),
    }
}

fn e7(deg: f64) -> i32 {
    (deg * 1e7).round() as i32
}

/// The items of a fence, shape after shape. Refused: no shape, a polygon with fewer than 3 or
/// more than [`MAX_POLYGON_VERTICES`] vertices, a coordinate out of range or not finite, a
/// radius that is not a positive number of metres, more items than a mission can count.
pub fn fence_items(shapes: &[FenceShape]) -> Result<Vec<FenceItem>, ConfigError> {
    if shapes.is_empty() {
        return Err(ConfigError("the fence has no shape".into()));
    }
    let ok = |[lat, lon]: [f64; 2]| {
        lat.is_finite() && lon.is_finite() && lat.abs() <= 90.0 && lon.abs() <= 180.0
    };
    let mut items = Vec::new();
    for (k, s) in shapes.iter().enumerate() {
        match s {
            FenceShape::Polygon {
                inclusion,
                vertices_lat_lon_deg: v,
            } => {
                if v.len() < 3 || v.len() > MAX_POLYGON_VERTICES {
                    return Err(ConfigError(format!(
                        "fence shape {k}: a polygon of {} vertices; expected 3 to {MAX_POLYGON_VERTICES}",
                        v.len()
                    )));
                }
                if !v.iter().all(|p| ok(*p)) {
                    return Err(ConfigError(format!(
                        "fence shape {k}: a vertex is not a latitude within ±90° and a longitude within ±180°"
                    )));
                }
                let command = if *inclusion {
                    POLYGON_VERTEX_INCLUSION
                } else {
                    POLYGON_VERTEX_EXCLUSION
                };
                for p in v {
                    items.push((command, v.len() as f32, *p));
                }
            }
            FenceShape::Circle {
                inclusion,
                centre_lat_lon_deg,
                radius_m,
            } => {
                if !(radius_m.is_finite() && *radius_m > 0.0 && *radius_m < 1e7) {
                    return Err(ConfigError(format!(
                        "fence shape {k}: radius {radius_m} m; expected a positive number of metres"
                    )));
                }
                if !ok(*centre_lat_lon_deg) {
                    return Err(ConfigError(format!(
                        "fence shape {k}: the centre is not a latitude within ±90° and a longitude within ±180°"
                    )));
                }
                let command = if *inclusion {
                    CIRCLE_INCLUSION
                } else {
                    CIRCLE_EXCLUSION
                };
                items.push((command, *radius_m as f32, *centre_lat_lon_deg));
            }
        }
    }
    if items.len() > usize::from(u16::MAX) {
        return Err(ConfigError(format!(
            "{} fence items do not fit in one MAVLink mission",
            items.len()
        )));
    }
    Ok(items
        .into_iter()
        .enumerate()
        .map(|(seq, (command, param1, [lat, lon]))| FenceItem {
            seq: seq as u16,
            command,
            param1,
            lat_e7: e7(lat),
            lon_e7: e7(lon),
        })
        .collect())
}

/// Compares a fence read back from the vehicle with the one sent: the same number of items,
/// and each with the same command, `param1` (exactly: a vertex count or a radius as the `f32`
/// sent) and latitude and longitude (the 10⁻⁷° integers sent). The first difference, told.
///
/// ```
/// use skyplan_flight::fence::{verify_fence, FenceItem, CIRCLE_EXCLUSION};
/// let a = FenceItem { seq: 0, command: CIRCLE_EXCLUSION, param1: 40.0, lat_e7: 1, lon_e7: 2 };
/// assert!(verify_fence(&[a], &[a]).is_ok());
/// let b = FenceItem { lon_e7: 3, ..a };
/// assert_eq!(verify_fence(&[a], &[b]).unwrap_err(),
///     "item 0 (CIRCLE_EXCLUSION): longitude 3 × 10⁻⁷° read back, 2 sent");
/// ```
pub fn verify_fence(sent: &[FenceItem], read: &[FenceItem]) -> Result<(), String> {
    if sent.len() != read.len() {
        return Err(format!(
            "{} items read back, {} sent",
            read.len(),
            sent.len()
        ));
    }
    for (s, r) in sent.iter().zip(read) {
        let at = format!("item {} ({})", s.seq, command_name(s.command));
        if r.command != s.command {
            return Err(format!("{at}: {} read back", command_name(r.command)));
        }
        if r.param1.to_bits() != s.param1.to_bits() {
            let what = if matches!(s.command, CIRCLE_INCLUSION | CIRCLE_EXCLUSION) {
                "radius"
            } else {
                "vertex count"
            };
            return Err(format!(
                "{at}: {what} {} read back, {} sent",
                r.param1, s.param1
            ));
        }
        if r.lat_e7 != s.lat_e7 {
            return Err(format!(
                "{at}: latitude {} × 10⁻⁷° read back, {} sent",
                r.lat_e7, s.lat_e7
            ));
        }
        if r.lon_e7 != s.lon_e7 {
            return Err(format!(
                "{at}: longitude {} × 10⁻⁷° read back, {} sent",
                r.lon_e7, s.lon_e7
            ));
        }
    }
    Ok(())
}

/// The fence decided from the zones, with what it says and what is lost.
#[derive(Debug, Clone, PartialEq)]
pub struct FencePlan {
    /// The shapes to upload, in order.
    pub shapes: Vec<FenceShape>,
    /// For each shape, the zone (feature index in the file) it comes from.
    pub zone_of: Vec<usize>,
    /// One line per zone: what was uploaded and what is lost, or why it was left out.
    pub notes: Vec<String>,
}

/// How the route flies, for [`fence_from_zones`].
#[derive(Debug, Clone, PartialEq)]
pub struct RouteForFence {
    /// The route's points, `[latitude, longitude]` degrees, in order.
    pub points_lat_lon_deg: Vec<[f64; 2]>,
    /// Its lowest and highest altitude above home, metres.
    pub alt_range_m: [f64; 2],
    /// The planning margin, metres (a zone's band grown by it is what the route kept out of).
    pub margin_m: f64,
}

/// The fence for `zones` and this route: see the [module](self) for what is uploaded and what
/// is lost. An error when nothing is left to upload, or when a zone's holes, which a fence
/// cannot carry, are where the route flies.
pub fn fence_from_zones(
    zones: &NoFlyZones,
    route: &RouteForFence,
) -> Result<FencePlan, ConfigError> {
    let plan = fence_shapes(zones, route)?;
    if plan.shapes.is_empty() {
        return Err(ConfigError(
            "no zone is left to upload as the fence (every zone's band is clear of the route's altitudes)".into(),
        ));
    }
    Ok(plan)
}

/// [`fence_from_zones`] without its last check: an empty fence is an answer here (a file's
/// fence, such as a `.plan`'s `geoFence`, may be empty; a vehicle's upload may not).
pub fn fence_shapes(zones: &NoFlyZones, route: &RouteForFence) -> Result<FencePlan, ConfigError> {
    let mut plan = FencePlan {
        shapes: Vec::new(),
        zone_of: Vec::new(),
        notes: Vec::new(),
    };
    let [lo, hi] = route.alt_range_m;
    let m = route.margin_m;
    let band = |f: f64, c: f64| {
        if c.is_finite() {
            format!("{f:.0}–{c:.0} m")
        } else {
            format!("from {f:.0} m up")
        }
    };
    for z in &zones.zones {
        let i = z.feature;
        let kind = if z.inclusion {
            "inclusion"
        } else {
            "exclusion"
        };
        let amsl = z.reference == AltReference::Amsl;
        let band_text = format!(
            "{}{}",
            band(z.floor_m, z.ceiling_m),
            if amsl { " above mean sea level" } else { "" }
        );
        let mut lost = Vec::new();
        if !z.inclusion {
            // Above home: the band grown by the margin against the route's altitudes. Above
            // mean sea level the home's altitude is not known here: kept (the safe side).
            let meets = amsl || (z.floor_m - m < hi && lo < z.ceiling_m + m);
            if !meets {
                let at = if (hi - lo).abs() < 0.5 {
                    format!("{lo:.0} m")
                } else {
                    format!("{lo:.0}–{hi:.0} m")
                };
                plan.notes.push(format!(
                    "zone {i} ({kind}, band {band_text}): left out: a fence holds at every altitude, and the route flies at {at}, clear of the band by the margin"
                ));
                continue;
            }
            lost.push(format!(
                "its band {band_text} (the fence keeps the vehicle out at every altitude)"
            ));
        } else if z.floor_m > 0.0 || z.ceiling_m.is_finite() {
            lost.push(format!(
                "its band {band_text} (ArduPilot's altitude limits are the FENCE_ALT_MIN/FENCE_ALT_MAX parameters, not set)"
            ));
        }
        if z.start_unix_s.is_some() || z.end_unix_s.is_some() {
            lost.push("its time window (a stored fence holds until replaced)".into());
        }
        let lat_lon = |ring: &[[f64; 2]]| ring.iter().map(|&[lon, lat]| [lat, lon]).collect();
        let what = match &z.shape {
            ZoneShape::Circle { centre, radius_m } => {
                plan.shapes.push(FenceShape::Circle {
                    inclusion: z.inclusion,
                    centre_lat_lon_deg: [centre[1], centre[0]],
                    radius_m: *radius_m,
                });
                plan.zone_of.push(i);
                format!("{kind} circle, radius {radius_m} m")
            }
            ZoneShape::Polygon(rings) => {
                let Some(outer) = rings.first() else {
                    continue;
                };
                let holes = rings.len() - 1;
                plan.shapes.push(FenceShape::Polygon {
                    inclusion: z.inclusion,
                    vertices_lat_lon_deg: lat_lon(outer),
                });
                plan.zone_of.push(i);
                if holes > 0 && z.inclusion {
                    for hole in &rings[1..] {
                        plan.shapes.push(FenceShape::Polygon {
                            inclusion: false,
                            vertices_lat_lon_deg: lat_lon(hole),
                        });
                        plan.zone_of.push(i);
                    }
                    format!(
                        "{kind} polygon of {} vertices, its {holes} hole(s) as exclusion polygons",
                        outer.len()
                    )
                } else if holes > 0 {
                    if let Some(k) = (1..rings.len()).find(|&k| route_enters(route, &rings[k])) {
                        return Err(ConfigError(format!(
                            "zone {i} is an exclusion polygon with holes, which a fence cannot carry, and the route flies through its hole {k}: the vehicle's fence (the outer ring) would forbid the route; plan without that zone's holes or fly without --fence"
                        )));
                    }
                    lost.push(format!(
                        "its {holes} hole(s) (a fence polygon has none: the vehicle is kept out of them too; the route does not enter them)"
                    ));
                    format!("{kind} polygon of {} vertices", outer.len())
                } else {
                    format!("{kind} polygon of {} vertices", outer.len())
                }
            }
        };
        let lost = if lost.is_empty() {
            "nothing lost".to_string()
        } else {
            format!("lost: {}", lost.join("; "))
        };
        plan.notes.push(format!("zone {i}: {what}; {lost}"));
    }
    Ok(plan)
}

/// Whether the route (a polyline in latitude/longitude) enters the ring (`[lon, lat]`
/// vertices): a point inside, or a leg crossing an edge. Straight lines in degrees: the
/// difference from straight lines on the ground is negligible over a zone.
fn route_enters(route: &RouteForFence, ring_lon_lat: &[[f64; 2]]) -> bool {
    let ring: Vec<[f64; 2]> = ring_lon_lat.iter().map(|&[lon, lat]| [lat, lon]).collect();
    let pts = &route.points_lat_lon_deg;
    if pts.iter().any(|p| inside(&ring, *p)) {
        return true;
    }
    pts.windows(2).any(|leg| {
        (0..ring.len()).any(|k| {
            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
            crosses(leg[0], leg[1], a, b)
        })
    })
}

/// Even-odd point in polygon.
fn inside(ring: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut c = false;
    let n = ring.len();
    for k in 0..n {
        let (a, b) = (ring[k], ring[(k + n - 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0]
        {
            c = !c;
        }
    }
    c
}

/// Whether segments p–q and a–b properly cross.
fn crosses(p: [f64; 2], q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    let orient = |o: [f64; 2], u: [f64; 2], v: [f64; 2]| {
        ((u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])).signum()
    };
    let (d1, d2) = (orient(a, b, p), orient(a, b, q));
    let (d3, d4) = (orient(p, q, a), orient(p, q, b));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// Retries of a download (the upload's [`crate::upload::UploadConfig`]).
pub use crate::upload::UploadConfig as DownloadConfig;

/// What the vehicle said during a download.
#[derive(Debug, Clone, PartialEq)]
pub enum DownloadEvent<T> {
    /// MISSION_COUNT.
    Count(u16),
    /// MISSION_ITEM_INT.
    Item {
        /// Its index.
        seq: u16,
        /// The item.
        item: T,
    },
    /// MISSION_ACK with an error: the vehicle refuses, with the result's name.
    Refused(String),
    /// Time passes.
    Tick,
}

/// What to send during a download.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DownloadSend {
    /// MISSION_REQUEST_LIST.
    RequestList,
    /// MISSION_REQUEST_INT of this item.
    Request(u16),
    /// MISSION_ACK (accepted): the download is over.
    Ack,
}

/// Where a download is.
#[derive(Debug, Clone, PartialEq)]
pub enum DownloadStatus<T> {
    /// Under way.
    InProgress,
    /// Every item, in order.
    Done(Vec<T>),
    /// It failed, with the reason.
    Failed(String),
}

/// The read-back protocol, ground side: MISSION_REQUEST_LIST → MISSION_COUNT → a
/// MISSION_REQUEST_INT per item, in order → MISSION_ITEM_INT → a MISSION_ACK to close. The
/// last message is resent after a silence of `retry_s`, up to `max_retries` times in a row.
///
/// ```
/// use skyplan_flight::fence::{DownloadConfig, DownloadEvent, DownloadSend, DownloadStatus, MissionDownload};
/// let mut d = MissionDownload::new(DownloadConfig::default());
/// assert_eq!(d.start(0.0), vec![DownloadSend::RequestList]);
/// assert_eq!(d.handle(0.1, DownloadEvent::Count(1)), vec![DownloadSend::Request(0)]);
/// assert_eq!(d.handle(0.2, DownloadEvent::Item { seq: 0, item: 'a' }), vec![DownloadSend::Ack]);
/// assert_eq!(d.status(), &DownloadStatus::Done(vec!['a']));
/// ```
#[derive(Debug, Clone)]
pub struct MissionDownload<T> {
    config: DownloadConfig,
    count: Option<u16>,
    items: Vec<T>,
    last: Option<(f64, DownloadSend)>,
    retries_in_a_row: u32,
    resends: u32,
    status: DownloadStatus<T>,
}

impl<T: Clone> MissionDownload<T> {
    /// A download not started yet.
    pub fn new(config: DownloadConfig) -> Self {
        Self {
            config,
            count: None,
            items: Vec::new(),
            last: None,
            retries_in_a_row: 0,
            resends: 0,
            status: DownloadStatus::InProgress,
        }
    }

    /// Starts: the MISSION_REQUEST_LIST to send.
    pub fn start(&mut self, now_s: f64) -> Vec<DownloadSend> {
        self.send(now_s, DownloadSend::RequestList)
    }

    /// Where the download is.
    pub fn status(&self) -> &DownloadStatus<T> {
        &self.status
    }

    /// Messages resent after a silence.
    pub fn resends(&self) -> u32 {
        self.resends
    }

    fn send(&mut self, now_s: f64, what: DownloadSend) -> Vec<DownloadSend> {
        self.last = Some((now_s, what));
        vec![what]
    }

    /// Feeds one event at `now_s` (seconds, monotonic) and returns what to send.
    pub fn handle(&mut self, now_s: f64, event: DownloadEvent<T>) -> Vec<DownloadSend> {
        if !matches!(self.status, DownloadStatus::InProgress) {
            return Vec::new();
        }
        match event {
            DownloadEvent::Count(n) => {
                // A repeated count (our request was resent) restarts nothing already received.
                if self.count.is_some_and(|c| c != n) {
                    self.status = DownloadStatus::Failed(format!(
                        "the vehicle counted {n} items after counting {}",
                        self.count.unwrap_or(0)
                    ));
                    return Vec::new();
                }
                self.count = Some(n);
                self.retries_in_a_row = 0;
                self.next(now_s)
            }
            DownloadEvent::Item { seq, item } => {
                let Some(n) = self.count else {
                    return Vec::new();
                };
                if usize::from(seq) != self.items.len() || seq >= n {
                    return Vec::new(); // a duplicate or an item out of order: re-asked on a tick
                }
                self.items.push(item);
                self.retries_in_a_row = 0;
                self.next(now_s)
            }
            DownloadEvent::Refused(why) => {
                self.status = DownloadStatus::Failed(format!("the vehicle refused: {why}"));
                Vec::new()
            }
            DownloadEvent::Tick => {
                let Some((t, what)) = self.last else {
                    return Vec::new();
                };
                if now_s - t < self.config.retry_s && now_s >= t {
                    return Vec::new();
                }
                if self.retries_in_a_row >= self.config.max_retries {
                    let after = match what {
                        DownloadSend::RequestList => "MISSION_REQUEST_LIST".to_string(),
                        DownloadSend::Request(seq) => format!("the request for item {seq}"),
                        DownloadSend::Ack => "the final MISSION_ACK".into(),
                    };
                    self.status = DownloadStatus::Failed(format!(
                        "no answer from the vehicle to {after} after {} tries, {:.1} s apart",
                        self.retries_in_a_row + 1,
                        self.config.retry_s
                    ));
                    return Vec::new();
                }
                self.retries_in_a_row += 1;
                self.resends += 1;
                self.send(now_s, what)
            }
        }
    }

    /// After a count or an item: the next request, or the closing ack (and done).
    fn next(&mut self, now_s: f64) -> Vec<DownloadSend> {
        let n = self.count.unwrap_or(0);
        if self.items.len() >= usize::from(n) {
            self.status = DownloadStatus::Done(std::mem::take(&mut self.items));
            return vec![DownloadSend::Ack];
        }
        self.send(now_s, DownloadSend::Request(self.items.len() as u16))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_map::nofly::parse_no_fly;

    fn route(points: &[[f64; 2]], alt_m: f64) -> RouteForFence {
        RouteForFence {
            points_lat_lon_deg: points.to_vec(),
            alt_range_m: [alt_m, alt_m],
            margin_m: 5.0,
        }
    }

    /// A square ring `[lon, lat]` about (lon, lat) of half-side `h` degrees, as GeoJSON text.
    fn square(lon: f64, lat: f64, h: f64) -> String {
        format!(
            "[[{a},{b}],[{c},{b}],[{c},{d}],[{a},{d}],[{a},{b}]]",
            a = lon - h,
            b = lat - h,
            c = lon + h,
            d = lat + h
        )
    }

    fn collection(features: &[String]) -> NoFlyZones {
        parse_no_fly(&format!(
            r#"{{"type": "FeatureCollection", "features": [{}]}}"#,
            features.join(",")
        ))
        .unwrap()
    }

    fn polygon(rings: &[String], props: &str) -> String {
        format!(
            r#"{{"type": "Feature", "properties": {{{props}}}, "geometry": {{"type": "Polygon", "coordinates": [{}]}}}}"#,
            rings.join(",")
        )
    }

    #[test]
    fn items_follow_the_shapes_with_counts_and_radii() {
        let shapes = [
            FenceShape::Polygon {
                inclusion: true,
                vertices_lat_lon_deg: vec![[37.0, -122.0], [37.001, -122.0], [37.001, -122.001]],
            },
            FenceShape::Circle {
                inclusion: false,
                centre_lat_lon_deg: [37.0005, -122.0005],
                radius_m: 12.5,
            },
            FenceShape::Polygon {
                inclusion: false,
                vertices_lat_lon_deg: vec![
                    [37.0002, -122.0002],
                    [37.0003, -122.0002],
                    [37.0003, -122.0003],
                    [37.0002, -122.0003],
                ],
            },
        ];
        let items = fence_items(&shapes).unwrap();
        let got: Vec<(u16, u16, f32)> =
            items.iter().map(|i| (i.seq, i.command, i.param1)).collect();
        let mut want = vec![
            (0, 5001, 3.0),
            (1, 5001, 3.0),
            (2, 5001, 3.0),
            (3, 5004, 12.5),
        ];
        want.extend((4..8).map(|s| (s, 5002, 4.0)));
        assert_eq!(got, want);
        assert_eq!(
            (items[1].lat_e7, items[1].lon_e7),
            (370_010_000, -1_220_000_000)
        );
        assert_eq!(
            (items[3].lat_e7, items[3].lon_e7),
            (370_005_000, -1_220_005_000)
        );
        // Refusals.
        assert!(fence_items(&[]).is_err());
        let mut two = shapes[0].clone();
        if let FenceShape::Polygon {
            vertices_lat_lon_deg,
            ..
        } = &mut two
        {
            vertices_lat_lon_deg.pop();
        }
        assert!(fence_items(&[two]).unwrap_err().0.contains("2 vertices"));
        let bad_r = FenceShape::Circle {
            inclusion: false,
            centre_lat_lon_deg: [37.0, -122.0],
            radius_m: -1.0,
        };
        assert!(fence_items(&[bad_r]).is_err());
        let swapped = FenceShape::Circle {
            inclusion: false,
            centre_lat_lon_deg: [-122.0, 37.0],
            radius_m: 1.0,
        };
        assert!(fence_items(&[swapped]).is_err());
    }

    #[test]
    fn every_difference_of_the_read_back_is_found() {
        let sent = fence_items(&[FenceShape::Circle {
            inclusion: true,
            centre_lat_lon_deg: [37.0, -122.0],
            radius_m: 100.0,
        }])
        .unwrap();
        assert!(verify_fence(&sent, &sent).is_ok());
        assert!(
            verify_fence(&sent, &[])
                .unwrap_err()
                .contains("0 items read back, 1 sent")
        );
        let s = sent[0];
        for (read, needle) in [
            (
                FenceItem {
                    command: CIRCLE_EXCLUSION,
                    ..s
                },
                "CIRCLE_EXCLUSION read back",
            ),
            (
                FenceItem {
                    param1: 100.01,
                    ..s
                },
                "radius 100.01 read back",
            ),
            (
                FenceItem {
                    lat_e7: s.lat_e7 + 1,
                    ..s
                },
                "latitude 370000001",
            ),
            (
                FenceItem {
                    lon_e7: s.lon_e7 - 1,
                    ..s
                },
                "longitude -1220000001",
            ),
        ] {
            let e = verify_fence(&sent, &[read]).unwrap_err();
            assert!(e.contains(needle), "{e}");
        }
    }

    #[test]
    fn zones_become_shapes_and_every_loss_is_told() {
        let (lon, lat) = (-122.3975, 37.7925);
        let zones = collection(&[
            // 0: an exclusion square at 0–120 m: uploaded, its band lost.
            polygon(
                &[square(lon + 0.001, lat, 0.0002)],
                r#""floor_m": 0, "ceiling_m": 120"#,
            ),
            // 1: an exclusion square at 200–300 m: the route at 30 m is below it: left out.
            polygon(
                &[square(lon, lat + 0.001, 0.0002)],
                r#""floor_m": 200, "ceiling_m": 300"#,
            ),
            // 2: an inclusion boundary with a hole: the hole becomes an exclusion polygon.
            polygon(
                &[
                    square(lon, lat, 0.01),
                    square(lon - 0.003, lat - 0.003, 0.0002),
                ],
                r#""inclusion": true"#,
            ),
            // 3: a timed circle.
            format!(
                r#"{{"type": "Feature", "properties": {{"radius_m": 25, "floor_m": 0, "ceiling_m": 60, "start": "2026-12-03T10:00:00Z"}}, "geometry": {{"type": "Point", "coordinates": [{}, {}]}}}}"#,
                lon - 0.001,
                lat
            ),
        ]);
        let r = route(&[[lat, lon], [lat + 0.0005, lon + 0.0005]], 30.0);
        let plan = fence_from_zones(&zones, &r).unwrap();
        assert_eq!(plan.zone_of, vec![0, 2, 2, 3]);
        assert!(matches!(
            plan.shapes[0],
            FenceShape::Polygon {
                inclusion: false,
                ..
            }
        ));
        assert!(matches!(
            plan.shapes[1],
            FenceShape::Polygon {
                inclusion: true,
                ..
            }
        ));
        assert!(matches!(
            plan.shapes[2],
            FenceShape::Polygon {
                inclusion: false,
                ..
            }
        ));
        assert!(
            matches!(plan.shapes[3], FenceShape::Circle { inclusion: false, radius_m, .. } if radius_m == 25.0)
        );
        // The vertices are the file's, [lat, lon] (not grown by the margin).
        let FenceShape::Polygon {
            vertices_lat_lon_deg: v,
            ..
        } = &plan.shapes[0]
        else {
            unreachable!()
        };
        let corner = [lat - 0.0002, lon + 0.001 - 0.0002];
        assert!(
            v.iter()
                .any(|p| (p[0] - corner[0]).abs() < 1e-12 && (p[1] - corner[1]).abs() < 1e-12),
            "{v:?}"
        );
        assert_eq!(v.len(), 4);
        let notes = plan.notes.join("\n");
        for needle in [
            "zone 0: exclusion polygon of 4 vertices; lost: its band 0–120 m",
            "zone 1 (exclusion, band 200–300 m): left out",
            "zone 2: inclusion polygon of 4 vertices, its 1 hole(s) as exclusion polygons; nothing lost",
            "zone 3: exclusion circle, radius 25 m; lost: its band 0–60 m (the fence keeps the vehicle out at every altitude); its time window",
        ] {
            assert!(notes.contains(needle), "{needle:?} not in\n{notes}");
        }
    }

    #[test]
    fn an_exclusion_polygon_with_holes_is_refused_when_the_route_uses_a_hole() {
        let (lon, lat) = (-122.3975, 37.7925);
        // A ring 0.002° wide with a hole 0.001° wide in its middle.
        let zones = collection(&[polygon(
            &[square(lon, lat, 0.002), square(lon, lat, 0.001)],
            r#""floor_m": 0, "ceiling_m": 100"#,
        )]);
        // The route starts inside the hole: refused.
        let through = route(&[[lat, lon], [lat + 0.0005, lon]], 20.0);
        let e = fence_from_zones(&zones, &through).unwrap_err().0;
        assert!(e.contains("flies through its hole 1"), "{e}");
        // A route crossing the hole without a waypoint in it: refused too.
        let across = route(&[[lat - 0.003, lon], [lat + 0.003, lon]], 20.0);
        assert!(fence_from_zones(&zones, &across).is_err());
        // A route far away: the outer ring is uploaded, the hole told as lost.
        let away = route(&[[lat + 0.01, lon], [lat + 0.011, lon]], 20.0);
        let plan = fence_from_zones(&zones, &away).unwrap();
        assert_eq!(plan.shapes.len(), 1);
        assert!(
            plan.notes[0].contains("its 1 hole(s) (a fence polygon has none"),
            "{:?}",
            plan.notes
        );
        // Every zone left out: an error, not an empty fence.
        let high = collection(&[polygon(
            &[square(lon, lat, 0.001)],
            r#""floor_m": 200, "ceiling_m": 300"#,
        )]);
        assert!(fence_from_zones(&high, &away).is_err());
    }

    /// A vehicle that answers a download, losing every `drop_every`-th message.
    fn download(n: u16, drop_every: u32) -> (MissionDownload<u16>, u32) {
        let mut d = MissionDownload::new(DownloadConfig::default());
        let mut outbox = d.start(0.0);
        let mut counter = 0;
        let lost = |c: &mut u32| {
            *c += 1;
            drop_every > 0 && (*c).is_multiple_of(drop_every)
        };
        let mut t = 0.0;
        let mut acks = 0;
        while *d.status() == DownloadStatus::InProgress && t < 1000.0 {
            t += 0.1;
            let mut events = vec![DownloadEvent::Tick];
            for s in outbox.drain(..) {
                if lost(&mut counter) {
                    continue;
                }
                let answer = match s {
                    DownloadSend::RequestList => DownloadEvent::Count(n),
                    DownloadSend::Request(seq) => DownloadEvent::Item {
                        seq,
                        item: seq * 10,
                    },
                    DownloadSend::Ack => {
                        acks += 1;
                        continue;
                    }
                };
                if !lost(&mut counter) {
                    events.push(answer);
                }
            }
            for e in events {
                outbox.extend(d.handle(t, e));
            }
        }
        (d, acks)
    }

    #[test]
    fn a_download_survives_lost_messages_and_closes_with_an_ack() {
        for drop_every in [0, 3, 4, 7] {
            let (d, _) = download(9, drop_every);
            let want: Vec<u16> = (0..9).map(|s| s * 10).collect();
            assert_eq!(
                d.status(),
                &DownloadStatus::Done(want),
                "drop every {drop_every}"
            );
            assert_eq!(d.resends() > 0, drop_every > 0, "drop every {drop_every}");
        }
        let (d, acks) = download(0, 0);
        assert_eq!((d.status(), acks), (&DownloadStatus::Done(vec![]), 0));
    }

    #[test]
    fn a_silent_or_refusing_vehicle_fails_the_download() {
        let mut d: MissionDownload<u16> = MissionDownload::new(DownloadConfig::default());
        d.start(0.0);
        let mut t = 0.0;
        while *d.status() == DownloadStatus::InProgress {
            t += 0.1;
            d.handle(t, DownloadEvent::Tick);
        }
        let DownloadStatus::Failed(why) = d.status() else {
            unreachable!()
        };
        assert!(why.contains("MISSION_REQUEST_LIST after 6 tries"), "{why}");
        let mut d: MissionDownload<u16> = MissionDownload::new(DownloadConfig::default());
        d.start(0.0);
        d.handle(0.1, DownloadEvent::Refused("UNSUPPORTED".into()));
        assert_eq!(
            d.status(),
            &DownloadStatus::Failed("the vehicle refused: UNSUPPORTED".into())
        );
    }
}
