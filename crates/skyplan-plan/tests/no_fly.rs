//! No-fly zones through the planning API: on the bundled city the default route goes around
//! the zones of `data/no-fly-sample.geojson` laid across it, checked by an independent distance
//! computation on every segment; zones out of their band are ignored; bad zone documents and
//! planners that cannot honour zones are refused with messages naming what is wrong.

use skyplan_map::colliders::GeodeticHome;
use skyplan_map::nofly::{Zone, ZoneShape, parse_no_fly};
use skyplan_plan::{FailureKind, PlanRequest, PlannerId, Session, World};
use skyplan_testkit::distance_to_segment;

const ZONES: &str = include_str!("../../../data/no-fly-sample.geojson");
const CITY_HOME: GeodeticHome = GeodeticHome {
    lat_deg: 37.792480,
    lon_deg: -122.397450,
};

fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let o = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    o(a, b, c) * o(a, b, d) <= 0.0 && o(c, d, a) * o(c, d, b) <= 0.0
}

fn inside(p: [f64; 2], ring: &[[f64; 2]]) -> bool {
    let mut odd = false;
    for k in 0..ring.len() {
        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
        if (a[0] > p[0]) != (b[0] > p[0])
            && p[1] < a[1] + (p[0] - a[0]) / (b[0] - a[0]) * (b[1] - a[1])
        {
            odd = !odd;
        }
    }
    odd
}

/// Distance from segment `ab` to the zone's shape (0 when they meet).
fn segment_zone_m(a: [f64; 2], b: [f64; 2], z: &Zone) -> f64 {
    match &z.shape {
        ZoneShape::Circle { centre, radius_m } => {
            (distance_to_segment(*centre, a, b) - radius_m).max(0.0)
        }
        ZoneShape::Polygon(rings) => {
            if inside(a, &rings[0]) && !rings[1..].iter().any(|h| inside(a, h)) {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for ring in rings {
                for k in 0..ring.len() {
                    let (c, d) = (ring[k], ring[(k + 1) % ring.len()]);
                    if segments_cross(a, b, c, d) {
                        return 0.0;
                    }
                    best = best
                        .min(distance_to_segment(a, c, d))
                        .min(distance_to_segment(b, c, d))
                        .min(distance_to_segment(c, a, b))
                        .min(distance_to_segment(d, a, b));
                }
            }
            best
        }
    }
}

/// The smallest distance from the route to each zone.
fn clearances(waypoints: &[[f64; 4]], zones: &[Zone]) -> Vec<f64> {
    zones
        .iter()
        .map(|z| {
            waypoints
                .windows(2)
                .map(|w| segment_zone_m([w[0][0], w[0][1]], [w[1][0], w[1][1]], z))
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

#[test]
fn default_route_goes_around_the_zones_by_the_margin() {
    let zones = parse_no_fly(ZONES)
        .unwrap()
        .project(CITY_HOME, None)
        .unwrap();
    let mut session = Session::new(World::fcnd_city());
    for planner in [PlannerId::Jps, PlannerId::Theta, PlannerId::Astar] {
        let plain = PlanRequest {
            planner: Some(planner),
            ..Default::default()
        };
        let before = session.plan(&plain).unwrap();
        let zoned = PlanRequest {
            no_fly: Some(ZONES.to_string()),
            ..plain
        };
        let after = session.plan(&zoned).unwrap();
        let (b, a) = (
            clearances(&before.waypoints, &zones),
            clearances(&after.waypoints, &zones),
        );
        println!(
            "{planner}: {:.1} m without zones (clearances {b:.1?}), {:.1} m with (clearances {a:.1?})",
            before.cost_m, after.cost_m
        );
        // Without zones the route crosses both zones that hold 5 m; with them it keeps the
        // 5 m margin from each (to within a micrometre: grid lines can touch the grown zone).
        assert_eq!((b[0], b[1]), (0.0, 0.0), "{planner}");
        assert!(a[0] >= 5.0 - 1e-6 && a[1] >= 5.0 - 1e-6, "{planner}: {a:?}");
        assert!(after.cost_m > before.cost_m);
        // The third zone (60–120 m) does not hold 5 m: the route may cross it.
        assert!(!zones[2].meets_altitude(5.0, 5.0));
    }
}

#[test]
fn a_zone_above_the_flight_does_not_count_and_one_in_band_does() {
    let mut session = Session::new(World::fcnd_city());
    // A 60–120 m square around the goal: free at 5 m, the goal blocked at 65 m.
    let square = r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
        "properties": {"floor_m": 60, "ceiling_m": 120},
        "geometry": {"type": "Polygon", "coordinates": [[[-122.3930, 37.7960], [-122.3920, 37.7960],
          [-122.3920, 37.7970], [-122.3930, 37.7960]]]}}]}"#;
    let plain = PlanRequest::default();
    let low = session
        .plan(&PlanRequest {
            no_fly: Some(square.to_string()),
            ..plain.clone()
        })
        .unwrap();
    assert_eq!(low.cost_m, session.plan(&plain).unwrap().cost_m);
    let inclusion = r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
        "geometry": {"type": "Point", "coordinates": [-122.39745, 37.79248]}, "properties": {"inclusion": true, "radius_m": 100, "floor_m": 0, "ceiling_m": 50}}]}"#;
    // The goal is 573 m from home: outside a 100 m inclusion circle.
    let e = session
        .plan(&PlanRequest {
            no_fly: Some(inclusion.to_string()),
            ..plain
        })
        .unwrap_err();
    assert_eq!(e.kind, FailureKind::InvalidGoal, "{}", e.message);
}

#[test]
fn bad_zones_and_planners_that_cannot_honour_them_are_refused() {
    let mut session = Session::new(World::fcnd_city());
    let missing_band = r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
        "properties": {"radius_m": 10},
        "geometry": {"type": "Point", "coordinates": [-122.39745, 37.79248]}}]}"#;
    let e = session
        .plan(&PlanRequest {
            no_fly: Some(missing_band.to_string()),
            ..Default::default()
        })
        .unwrap_err();
    assert_eq!(e.kind, FailureKind::BadRequest);
    assert!(
        e.message
            .starts_with("no_fly: feature 0, properties.floor_m: missing"),
        "{}",
        e.message
    );
    let amsl = ZONES.replacen(
        "\"floor_m\": 0,",
        "\"reference\": \"amsl\", \"floor_m\": 0,",
        1,
    );
    let e = session
        .plan(&PlanRequest {
            no_fly: Some(amsl),
            ..Default::default()
        })
        .unwrap_err();
    assert!(
        e.message
            .contains("feature 0, properties.reference: \"amsl\" needs the home's altitude"),
        "{}",
        e.message
    );
    let e = session
        .plan(&PlanRequest {
            planner: Some(PlannerId::Voronoi),
            no_fly: Some(ZONES.to_string()),
            ..Default::default()
        })
        .unwrap_err();
    assert!(
        e.message
            .starts_with("no_fly: planner voronoi does not honour no-fly zones"),
        "{}",
        e.message
    );
    let grid = skyplan_cspace::Grid2::from_ascii("....\n....").unwrap();
    let mut on_grid = Session::new(World::from_grid("tiny", grid));
    let e = on_grid
        .plan(&PlanRequest {
            start_ne: Some([0.5, 0.5]),
            goal_ne: Some([1.5, 3.5]),
            no_fly: Some(ZONES.to_string()),
            ..Default::default()
        })
        .unwrap_err();
    assert!(
        e.message
            .contains("no-fly zones need a colliders or footprint map"),
        "{}",
        e.message
    );
}

/// Circles on the default route's waypoints and segment midpoints (radius 8 to 26 m): every
/// route keeps the 5 m margin, and some come within 1.5 m of it (the check is tight).
#[test]
fn routes_keep_the_margin_from_circles_on_the_way() {
    use skyplan_frames::{Lla, LocalFrame, Ned};
    let frame = LocalFrame::new(Lla {
        lat_deg: CITY_HOME.lat_deg,
        lon_deg: CITY_HOME.lon_deg,
        alt_m: 0.0,
    })
    .unwrap();
    let mut session = Session::new(World::fcnd_city());
    let route = session.plan(&PlanRequest::default()).unwrap().waypoints;
    let (mut tightest, mut planned) = (f64::INFINITY, 0);
    for (k, w) in route.windows(2).enumerate().skip(1) {
        for (t, radius_m) in [(0.0, 8.0), (0.5, 14.0), (0.5, 26.0)] {
            let n = w[0][0] + t * (w[1][0] - w[0][0]);
            let e = w[0][1] + t * (w[1][1] - w[0][1]);
            let at = frame
                .lla_from_ned(Ned {
                    north_m: n,
                    east_m: e,
                    down_m: 0.0,
                })
                .unwrap();
            let text = format!(
                r#"{{"type": "FeatureCollection", "features": [{{"type": "Feature",
                "properties": {{"radius_m": {radius_m}, "floor_m": 0, "ceiling_m": 100}},
                "geometry": {{"type": "Point", "coordinates": [{:.9}, {:.9}]}}}}]}}"#,
                at.lon_deg, at.lat_deg
            );
            let zones = parse_no_fly(&text)
                .unwrap()
                .project(CITY_HOME, None)
                .unwrap();
            let request = PlanRequest {
                no_fly: Some(text),
                ..Default::default()
            };
            // A circle may close a street: then no route, which is fine.
            let Ok(plan) = session.plan(&request) else {
                continue;
            };
            let c = clearances(&plan.waypoints, &zones)[0];
            assert!(c >= 5.0 - 1e-6, "segment {k}, t {t}, r {radius_m}: {c} m");
            tightest = tightest.min(c);
            planned += 1;
        }
    }
    println!("{planned} routes around circles, the closest {tightest:.3} m from one");
    assert!(planned >= 15 && tightest < 6.5, "{planned} {tightest}");
}

/// The smooth trajectory's corridor is built in the grid with the zones: every sample keeps the
/// margin from them. A ride on the cost map refuses zones rather than ignoring them.
#[test]
fn trajectories_keep_the_margin_and_rides_refuse_zones() {
    let zones = parse_no_fly(ZONES)
        .unwrap()
        .project(CITY_HOME, None)
        .unwrap();
    let mut session = Session::new(World::fcnd_city());
    let plan = session
        .plan(&PlanRequest {
            no_fly: Some(ZONES.to_string()),
            trajectory: Some(true),
            ..Default::default()
        })
        .unwrap();
    let samples = plan.trajectory.unwrap().samples;
    assert!(samples.len() > 100);
    let points: Vec<[f64; 4]> = samples.iter().map(|s| [s[1], s[2], s[3], 0.0]).collect();
    let c = clearances(&points, &zones);
    assert!(c[0] >= 5.0 - 1e-6 && c[1] >= 5.0 - 1e-6, "{c:?}");
    let mut ride = skyplan_plan::RideRequest::new([0.0, 0.0], vec![[420.0, 390.0]]);
    ride.route.no_fly = Some(ZONES.to_string());
    let e = session.ride(&ride).unwrap_err();
    assert!(
        e.message.starts_with("no_fly: rides on the cost map"),
        "{}",
        e.message
    );
}
