//! Which no-fly zones a flight must keep out of, by their altitude bands and time windows.
//!
//! A zone with a time window applies when that window meets the flight's: from the request's
//! departure to its latest arrival, [`latest_arrival_s`] after it. The flight's duration is
//! not known before its route is, so the session plans twice at most
//! ([`crate::Session::plan`]):
//! 1. among every zone that has not ended by the departure (the safe side), which gives a
//!    route and its latest arrival;
//! 2. if some zones open only after that arrival, again without them; that route is kept if
//!    every zone open during its own (possibly longer) flight was among those it kept out of,
//!    else the first route is.
//!
//! Either way the route returned keeps out of every zone whose window meets its flight's.

use serde_json::{Value, json};
use skyplan_map::nofly::{Zone, rfc3339_from_unix_s};

/// The latest arrival is this many times the time to fly the route stopping at each waypoint
/// (at the request's trajectory limits) …
pub const ARRIVAL_FACTOR: f64 = 1.5;
/// … plus this, seconds: take-off, landing and a slower vehicle than the limits say.
pub const ARRIVAL_SLACK_S: f64 = 60.0;

/// Seconds from the departure to the latest arrival of a flight that takes `stop_s` seconds
/// stopping at each waypoint: `ARRIVAL_FACTOR · stop_s + ARRIVAL_SLACK_S`. Stopping at each
/// waypoint is slower than a trajectory through the same waypoints at the same limits, so this
/// bounds a flight of the route with room to spare.
///
/// ```
/// assert_eq!(skyplan_plan::latest_arrival_s(100.0), 210.0);
/// ```
pub fn latest_arrival_s(stop_s: f64) -> f64 {
    ARRIVAL_FACTOR * stop_s + ARRIVAL_SLACK_S
}

/// Whether zone `z` is active at some time in `[from, until)` (Unix seconds).
pub(crate) fn meets_window(z: &Zone, from: i64, until: i64) -> bool {
    z.start_unix_s.is_none_or(|s| s < until) && z.end_unix_s.is_none_or(|e| e > from)
}

/// What a plan says about its zones (the `no_fly` entry of its details).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ZoneReport {
    /// Every zone of the request, by feature index.
    pub zones: Vec<usize>,
    /// Exclusion zones whose band, grown by the margin, holds none of the flight's altitudes.
    pub out_of_band: Vec<usize>,
    /// Timed zones: `(departure, latest arrival)` when a departure was given.
    pub window: Option<(i64, i64)>,
    /// Timed zones outside the flight's window (with a departure) …
    pub outside_window: Vec<usize>,
    /// … or counted as active at every time (without one).
    pub timed_always: Vec<usize>,
}

impl ZoneReport {
    /// The report on `zones` of which `applied` were planned among, for a flight between the
    /// altitudes `[low, high]` (one altitude for a 2D route).
    pub(crate) fn new(
        zones: &[Zone],
        applied: &[Zone],
        [low, high]: [f64; 2],
        margin_m: f64,
    ) -> Self {
        let kept = |z: &Zone| applied.iter().any(|a| a.feature == z.feature);
        ZoneReport {
            zones: zones.iter().map(|z| z.feature).collect(),
            out_of_band: zones
                .iter()
                .filter(|z| {
                    let band = (z.floor_m - margin_m, z.ceiling_m + margin_m);
                    // As `Zone::meets_altitude` (open band) over the range of altitudes.
                    let meets = band.0 < high && band.1 > low;
                    !z.inclusion && !meets
                })
                .map(|z| z.feature)
                .collect(),
            window: None,
            outside_window: zones
                .iter()
                .filter(|z| !kept(z))
                .map(|z| z.feature)
                .collect(),
            timed_always: Vec::new(),
        }
    }

    pub(crate) fn json(&self) -> Value {
        json!({
            "zones": self.zones,
            "out_of_band": self.out_of_band,
            "departure": self.window.map(|w| rfc3339_from_unix_s(w.0)),
            "latest_arrival": self.window.map(|w| rfc3339_from_unix_s(w.1)),
            "outside_window": self.outside_window,
            "timed_always": self.timed_always,
        })
    }
}

/// The summary line of a plan's `no_fly` details.
pub(crate) fn summary_line(v: &Value) -> Option<String> {
    let list = |k: &str| -> Vec<u64> {
        v[k].as_array()
            .map(|a| a.iter().filter_map(Value::as_u64).collect())
            .unwrap_or_default()
    };
    let features = |ids: &[u64]| {
        let shown: Vec<String> = ids.iter().map(u64::to_string).collect();
        format!(
            "feature{} {}",
            if ids.len() == 1 { "" } else { "s" },
            shown.join(", ")
        )
    };
    let zones = list("zones");
    let (band, outside, always) = (
        list("out_of_band"),
        list("outside_window"),
        list("timed_always"),
    );
    let applied = zones
        .iter()
        .filter(|z| !band.contains(z) && !outside.contains(z))
        .count();
    let mut line = format!(
        "no-fly     {} zone{}: {applied} appl{}",
        zones.len(),
        if zones.len() == 1 { "" } else { "s" },
        if applied == 1 { "ies" } else { "y" }
    );
    if !band.is_empty() {
        line += &format!("; not at this altitude: {}", features(&band));
    }
    if let (Some(dep), Some(arr)) = (v["departure"].as_str(), v["latest_arrival"].as_str()) {
        line += &format!("; flight from {dep} to {arr} at the latest");
        if !outside.is_empty() {
            line += &format!(", inactive then: {}", features(&outside));
        }
    }
    if !always.is_empty() {
        line += &format!(
            "; timed, counted as active at every time without a departure: {}",
            features(&always)
        );
    }
    Some(line)
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_map::nofly::ZoneShape;

    fn zone(feature: usize, window: (Option<i64>, Option<i64>)) -> Zone {
        Zone {
            feature,
            shape: ZoneShape::Circle {
                centre: [0.0, 0.0],
                radius_m: 1.0,
            },
            floor_m: 0.0,
            ceiling_m: 50.0,
            inclusion: false,
            start_unix_s: window.0,
            end_unix_s: window.1,
        }
    }

    #[test]
    fn a_window_meets_a_flight_when_they_share_a_moment() {
        let (from, until) = (1000, 2000);
        for (w, meets) in [
            ((None, None), true),
            ((Some(2000), None), false),
            ((Some(1999), None), true),
            ((None, Some(1000)), false),
            ((None, Some(1001)), true),
            ((Some(500), Some(900)), false),
            ((Some(1500), Some(1600)), true),
            ((Some(500), Some(3000)), true),
        ] {
            assert_eq!(meets_window(&zone(0, w), from, until), meets, "{w:?}");
        }
    }

    #[test]
    fn the_summary_names_what_does_not_apply_and_why() {
        let zones = [zone(0, (None, None)), zone(1, (Some(5000), None)), {
            let mut z = zone(2, (None, None));
            z.floor_m = 100.0;
            z
        }];
        let applied = [zones[0].clone(), zones[2].clone()];
        let mut report = ZoneReport::new(&zones, &applied, [10.0, 10.0], 5.0);
        report.window = Some((0, 300));
        let line = summary_line(&report.json()).unwrap_or_default();
        assert_eq!(
            line,
            "no-fly     3 zones: 1 applies; not at this altitude: feature 2; flight from \
             1970-01-01T00:00:00Z to 1970-01-01T00:05:00Z at the latest, inactive then: \
             feature 1"
        );
    }
}
