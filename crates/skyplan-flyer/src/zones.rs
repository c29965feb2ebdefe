//! How close a flight came to its no-fly zones: the flight log's track (the vehicle's own
//! positions, simulated or real) against the zones that apply at its altitude, segment by
//! segment and exactly ([`skyplan_map::nofly::Zone::clearance_m`]).

use skyplan_link::ground::LogRow;
use skyplan_map::nofly::Zone;

/// The closest approach of a track to its zones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZonePass {
    /// The zone's feature index in its file.
    pub feature: usize,
    /// Metres: to an exclusion zone's shape (0 inside it); to an inclusion boundary's edge (0
    /// on or outside it).
    pub clearance_m: f64,
    /// When (the flight log's time), seconds.
    pub time_s: f64,
    /// Whether the zone is an inclusion boundary.
    pub inclusion: bool,
}

/// The closest approach of the airborne part of `log` to `zones`: an exclusion zone counts
/// where its band, grown by `margin_m` as in planning, holds the vehicle's altitude at both
/// ends of a segment; an inclusion boundary everywhere (its edge, and 0 outside it). `None`
/// without zones or an airborne segment.
///
/// ```
/// use skyplan_flyer::zones::closest_zone;
/// use skyplan_map::nofly::{Zone, ZoneShape};
/// let disc = Zone { feature: 3, shape: ZoneShape::Circle { centre: [50.0, 0.0], radius_m: 10.0 },
///                   floor_m: 0.0, ceiling_m: 100.0, inclusion: false, start_unix_s: None, end_unix_s: None };
/// let row = |t: f64, n: f64, e: f64| skyplan_link::ground::LogRow {
///     time_s: t, state: skyplan_flight::executor::FlightState::Waypoint, lat_deg: 0.0, lon_deg: 0.0,
///     north_m: n, east_m: e, alt_m: 20.0, yaw_rad: 0.0, speed_m_s: 5.0, target: None };
/// let pass = closest_zone(&[row(0.0, 0.0, 16.0), row(10.0, 100.0, 16.0)], &[disc], 5.0).unwrap();
/// assert_eq!((pass.feature, pass.clearance_m), (3, 6.0));
/// ```
pub fn closest_zone(log: &[LogRow], zones: &[Zone], margin_m: f64) -> Option<ZonePass> {
    /// Below this altitude the vehicle is on the ground (taking off or landed), metres.
    const AIRBORNE_M: f64 = 0.5;
    let mut best: Option<ZonePass> = None;
    for w in log.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if a.alt_m < AIRBORNE_M && b.alt_m < AIRBORNE_M {
            continue;
        }
        let (p, q) = ([a.north_m, a.east_m], [b.north_m, b.east_m]);
        for z in zones {
            let clearance_m = if z.inclusion {
                let inside = z.clearance_m(p, p) == 0.0 && z.clearance_m(q, q) == 0.0;
                if inside {
                    z.boundary_clearance_m(p, q)
                } else {
                    0.0
                }
            } else if z.meets_altitude(a.alt_m, margin_m) && z.meets_altitude(b.alt_m, margin_m) {
                z.clearance_m(p, q)
            } else {
                continue;
            };
            if best.is_none_or(|c| clearance_m < c.clearance_m) {
                best = Some(ZonePass {
                    feature: z.feature,
                    clearance_m,
                    time_s: a.time_s,
                    inclusion: z.inclusion,
                });
            }
        }
    }
    best
}

/// The flight's `no-fly` line: the closest approach and the margin.
pub fn zone_line(pass: &ZonePass, margin_m: Option<f64>) -> String {
    let margin = margin_m.map_or(String::new(), |m| format!(", safety margin {m} m"));
    let what = if pass.inclusion {
        "from the edge of inclusion boundary"
    } else {
        "from zone"
    };
    if pass.clearance_m == 0.0 {
        let verb = if pass.inclusion { "left" } else { "entered" };
        format!(
            "no-fly     {verb} zone {} at {:.1} s{margin}",
            pass.feature, pass.time_s
        )
    } else {
        format!(
            "no-fly     closest {:.2} m {what} {} at {:.1} s{margin}",
            pass.clearance_m, pass.feature, pass.time_s
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::{Unfinished, verdict};
    use skyplan_flight::executor::{FlightState, Outcome};
    use skyplan_map::nofly::ZoneShape;

    fn row(t: f64, n: f64, e: f64, alt_m: f64) -> LogRow {
        LogRow {
            time_s: t,
            state: FlightState::Waypoint,
            lat_deg: 0.0,
            lon_deg: 0.0,
            north_m: n,
            east_m: e,
            alt_m,
            yaw_rad: 0.0,
            speed_m_s: 5.0,
            target: None,
        }
    }

    fn square(feature: usize, inclusion: bool, half_m: f64, band: (f64, f64)) -> Zone {
        let ring = vec![
            [-half_m, -half_m],
            [-half_m, half_m],
            [half_m, half_m],
            [half_m, -half_m],
        ];
        Zone {
            feature,
            shape: ZoneShape::Polygon(vec![ring]),
            floor_m: band.0,
            ceiling_m: band.1,
            inclusion,
            start_unix_s: None,
            end_unix_s: None,
        }
    }

    /// A track past a 20 m square (3 m from its edge at 10 m up), with a 200 m inclusion square
    /// around everything and a square above the flight.
    #[test]
    fn the_closest_zone_counts_only_zones_in_band_and_the_boundary_from_inside() {
        let zones = [
            square(0, false, 10.0, (0.0, 50.0)),
            square(1, true, 100.0, (0.0, f64::INFINITY)),
            square(2, false, 10.0, (60.0, 80.0)),
        ];
        let log = [
            row(0.0, -50.0, 13.0, 0.0),
            row(1.0, -50.0, 13.0, 10.0),
            row(5.0, 50.0, 13.0, 10.0),
        ];
        let pass = closest_zone(&log, &zones, 5.0).unwrap();
        assert_eq!(pass.feature, 0);
        assert!((pass.clearance_m - 3.0).abs() < 1e-12, "{pass:?}");
        assert_eq!(pass.time_s, 1.0);
        assert_eq!(
            zone_line(&pass, Some(5.0)),
            "no-fly     closest 3.00 m from zone 0 at 1.0 s, safety margin 5 m"
        );
        // 3 m is more than half the 5 m margin: done; not with an 8 m margin.
        let done = Some(Outcome::Completed);
        assert_eq!(
            verdict(done.clone(), None, Some(5.0), None, Some(&pass)),
            Ok(())
        );
        let got = verdict(done, None, Some(8.0), None, Some(&pass)).unwrap_err();
        assert!(
            matches!(got, Unfinished::NearZone { feature: 0, .. }),
            "{got}"
        );
        assert!(
            got.to_string().contains("within 3.00 m of no-fly zone 0"),
            "{got}"
        );
        // Straying out of the inclusion boundary: 0, "left".
        let out = [row(0.0, 95.0, 50.0, 10.0), row(1.0, 105.0, 50.0, 10.0)];
        let pass = closest_zone(&out, &zones[1..2], 5.0).unwrap();
        assert_eq!((pass.feature, pass.clearance_m), (1, 0.0));
        assert_eq!(zone_line(&pass, None), "no-fly     left zone 1 at 0.0 s");
        // On the ground, nothing counts.
        let ground = [row(0.0, 0.0, 0.0, 0.0), row(1.0, 0.0, 1.0, 0.2)];
        assert_eq!(closest_zone(&ground, &zones, 5.0), None);
    }
}
