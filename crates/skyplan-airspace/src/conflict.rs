//! The exact conflict test between volumes, and between a new intent and the stored ones.

use crate::geometry::{Hull, LocalPlane, convex_intersect};
use crate::model::{IntentRef, IntentState, OperationalIntent, Volume4D};
use serde::Serialize;

/// Whether the closed time windows overlap.
pub fn times_overlap(a: &Volume4D, b: &Volume4D) -> bool {
    a.time_start.value <= b.time_end.value && b.time_start.value <= a.time_end.value
}

/// Whether the closed altitude bands overlap (every altitude the DSS takes is W84 metres, so
/// the values compare directly).
pub fn altitudes_overlap(a: &Volume4D, b: &Volume4D) -> bool {
    let (a, b) = (&a.volume, &b.volume);
    a.altitude_lower.value <= b.altitude_upper.value
        && b.altitude_lower.value <= a.altitude_upper.value
}

/// The latitude/longitude box of a volume's footprint: `[lat_min, lng_min, lat_max, lng_max]`.
pub fn bbox_deg(v: &Volume4D) -> [f64; 4] {
    v.volume.outline_polygon.vertices.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, p| {
            [
                b[0].min(p.lat),
                b[1].min(p.lng),
                b[2].max(p.lat),
                b[3].max(p.lng),
            ]
        },
    )
}

/// Whether the footprints share a point: the boxes first, then separating axes between the
/// convex hulls on a plane about `a`'s first vertex ([`crate::geometry`]).
pub fn footprints_intersect(a: &Volume4D, b: &Volume4D) -> bool {
    boxes_overlap(&bbox_deg(a), &bbox_deg(b)) && hulls_intersect(a, b)
}

/// Whether two [`bbox_deg`] boxes share a point.
fn boxes_overlap(a: &[f64; 4], b: &[f64; 4]) -> bool {
    !(a[2] < b[0] || b[2] < a[0] || a[3] < b[1] || b[3] < a[1])
}

/// [`footprints_intersect`] past its boxes: separating axes between the convex hulls.
fn hulls_intersect(a: &Volume4D, b: &Volume4D) -> bool {
    let Some(&origin) = a.volume.outline_polygon.vertices.first() else {
        return false;
    };
    let plane = LocalPlane::about(origin);
    let (ha, hb) = (
        Hull::on(&plane, &a.volume.outline_polygon),
        Hull::on(&plane, &b.volume.outline_polygon),
    );
    if ha.points.len() < 3 || hb.points.len() < 3 {
        // Validation refuses such polygons; an unchecked one is taken as conflicting.
        return true;
    }
    convex_intersect(&ha.points, &hb.points)
}

/// Whether two volumes share a point in space and time: the time windows, the altitude
/// bands and the footprints all overlap (closed sets).
///
/// ```
/// use skyplan_airspace::{Altitude, LatLng, Polygon, Volume3D, Volume4D, Timestamp, volumes_conflict};
/// let square = |lat: f64, lng: f64, d: f64| Polygon { vertices: vec![
///     LatLng { lat, lng }, LatLng { lat, lng: lng + d }, LatLng { lat: lat + d, lng: lng + d }, LatLng { lat: lat + d, lng },
/// ] };
/// let t = |s: &str| s.parse::<Timestamp>().unwrap().into();
/// let v = |poly, lo, hi, from, to| Volume4D {
///     volume: Volume3D { outline_polygon: poly, altitude_lower: Altitude::w84_m(lo), altitude_upper: Altitude::w84_m(hi) },
///     time_start: t(from), time_end: t(to),
/// };
/// let a = v(square(37.79, -122.40, 0.001), 0.0, 50.0, "2026-03-01T12:00:00Z", "2026-03-01T12:05:00Z");
/// let b = v(square(37.7905, -122.3995, 0.001), 40.0, 90.0, "2026-03-01T12:04:00Z", "2026-03-01T12:09:00Z");
/// assert!(volumes_conflict(&a, &b));
/// let later = v(square(37.7905, -122.3995, 0.001), 40.0, 90.0, "2026-03-01T12:05:01Z", "2026-03-01T12:09:00Z");
/// assert!(!volumes_conflict(&a, &later));
/// let above = v(square(37.7905, -122.3995, 0.001), 50.5, 90.0, "2026-03-01T12:04:00Z", "2026-03-01T12:09:00Z");
/// assert!(!volumes_conflict(&a, &above));
/// ```
pub fn volumes_conflict(a: &Volume4D, b: &Volume4D) -> bool {
    times_overlap(a, b) && altitudes_overlap(a, b) && footprints_intersect(a, b)
}

/// Which stored intents a new one must keep clear of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PriorityRule {
    /// Those of equal or higher priority (ASTM F3548's strategic deconfliction): a more
    /// important flight may be accepted over a less important one.
    #[default]
    EqualOrHigher,
    /// Every one, whatever its priority.
    Every,
}

impl PriorityRule {
    /// Whether `stored` binds a new intent of `priority`: not ended, and of a priority the
    /// rule counts.
    pub fn binds(self, priority: u32, stored: &OperationalIntent) -> bool {
        stored.state != IntentState::Ended
            && match self {
                Self::EqualOrHigher => stored.priority >= priority,
                Self::Every => true,
            }
    }
}

/// A stored intent a new one conflicts with, and the first pair of volumes that meet.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Conflict {
    /// The stored intent's id.
    pub id: String,
    /// Its version.
    pub version: u64,
    /// Its priority.
    pub priority: u32,
    /// The index of the new intent's volume.
    pub volume: usize,
    /// The index of the stored intent's volume it meets.
    pub their_volume: usize,
}

impl Conflict {
    /// The stored intent's id and version.
    pub fn reference(&self) -> IntentRef {
        IntentRef {
            id: self.id.clone(),
            version: self.version,
        }
    }
}

/// The first pair `(new volume, stored volume)` that conflicts, if any.
///
/// The same test as [`volumes_conflict`] on every pair, in that order, with each footprint's
/// box computed once, when a pair first overlaps in time and altitude.
pub fn first_conflict(new: &[Volume4D], stored: &[Volume4D]) -> Option<(usize, usize)> {
    let mut boxes: Vec<Option<[f64; 4]>> = vec![None; stored.len()];
    for (i, a) in new.iter().enumerate() {
        let mut own = None;
        for (j, b) in stored.iter().enumerate() {
            if !(times_overlap(a, b) && altitudes_overlap(a, b)) {
                continue;
            }
            let own = own.get_or_insert_with(|| bbox_deg(a));
            let theirs = boxes[j].get_or_insert_with(|| bbox_deg(b));
            if boxes_overlap(own, theirs) && hulls_intersect(a, b) {
                return Some((i, j));
            }
        }
    }
    None
}

/// The stored intents that `new` conflicts with under `rule` (one entry per intent, in the
/// order given; the intent with `new`'s own id is skipped).
pub fn conflicts<'a>(
    new: &OperationalIntent,
    stored: impl IntoIterator<Item = &'a OperationalIntent>,
    rule: PriorityRule,
) -> Vec<Conflict> {
    stored
        .into_iter()
        .filter(|s| s.id != new.id && rule.binds(new.priority, s))
        .filter_map(|s| {
            first_conflict(&new.volumes, &s.volumes).map(|(volume, their_volume)| Conflict {
                id: s.id.clone(),
                version: s.version,
                priority: s.priority,
                volume,
                their_volume,
            })
        })
        .collect()
}
