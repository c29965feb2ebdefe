//! Operational intents on the bundled city: the volumes cover the flight, the JSON is the
//! DSS's, the earliest departure is the first free one (against a brute-force scan), a
//! blocked window names its blockers, and (with SKYPLAN_PYTHON's shapely) the footprint test
//! agrees with shapely's `intersects`.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};
use skyplan_airspace::geometry::{Hull, LocalPlane, contains, convex_hull, convex_intersect};
use skyplan_airspace::*;
use skyplan_frames::{Lla, LocalFrame, Ned};
use skyplan_plan::{Plan, PlanRequest, Session, World};

fn t0() -> Timestamp {
    "2026-03-01T12:00:00Z".parse().expect("a time")
}

/// Plans on the city: from `start` to `goal` at `alt_m`.
fn plan(
    session: &mut Session,
    start: [f64; 2],
    goal: [f64; 2],
    alt_m: f64,
    trajectory: bool,
) -> Plan {
    session
        .plan(&PlanRequest {
            start_ne: Some(start),
            goal_ne: Some(goal),
            alt_m: Some(alt_m),
            trajectory: trajectory.then_some(true),
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("{start:?} → {goal:?}: {e}"))
}

/// Every sample of the flight lies in a volume whose altitude band and time window hold it.
fn assert_covers(plan: &Plan, flight: &FlightVolumes, departure: Timestamp) {
    let home = plan.home.expect("the city has a home");
    let frame = LocalFrame::new(Lla {
        lat_deg: home.lat_deg,
        lon_deg: home.lon_deg,
        alt_m: 0.0,
    })
    .expect("a frame");
    let volumes = flight.at(departure);
    let hulls: Vec<(LocalPlane, Hull)> = volumes
        .iter()
        .map(|v| {
            let plane = LocalPlane::about(v.volume.outline_polygon.vertices[0]);
            (plane, Hull::on(&plane, &v.volume.outline_polygon))
        })
        .collect();
    // The plan's own samples when it has a trajectory (the route's otherwise).
    let samples: Vec<(f64, [f64; 3])> = match &plan.trajectory {
        Some(t) => t
            .samples
            .iter()
            .map(|r| (r[0], [r[1], r[2], r[3]]))
            .collect(),
        None => flight.path.iter().map(|p| (p.t_s, p.nea)).collect(),
    };
    assert!(samples.len() > 10);
    for (t_s, [n, e, alt]) in samples {
        let lla = frame
            .lla_from_ned(Ned {
                north_m: n,
                east_m: e,
                down_m: 0.0,
            })
            .expect("in the frame");
        let p = LatLng {
            lat: lla.lat_deg,
            lng: lla.lon_deg,
        };
        let t = departure.unix_ms() as f64 + t_s * 1000.0;
        let inside = volumes.iter().zip(&hulls).any(|(v, (plane, hull))| {
            v.time_start.value.unix_ms() as f64 <= t
                && t <= v.time_end.value.unix_ms() as f64
                && v.volume.altitude_lower.value <= alt
                && alt <= v.volume.altitude_upper.value
                && contains(&hull.points, plane.xy(p))
        });
        assert!(
            inside,
            "the sample at {t_s} s ({n:.1}, {e:.1}, {alt:.1}) is in no volume"
        );
    }
    // Every vertex is at least the margin (less a millimetre) from the route: a sanity check
    // of the buffer's size.
    let o = VolumeOptions::default();
    for v in &volumes {
        assert!(
            v.volume.altitude_upper.value - v.volume.altitude_lower.value
                >= 2.0 * o.vertical_buffer_m
        );
        assert!(
            v.time_end.value.ms_since(v.time_start.value)
                >= (2.0 * o.time_buffer_s * 1000.0) as i64
        );
    }
}

#[test]
fn volumes_cover_the_flight_with_and_without_a_trajectory() {
    let mut session = Session::new(World::fcnd_city());
    for trajectory in [false, true] {
        let p = plan(&mut session, [0.0, 0.0], [420.0, 390.0], 10.0, trajectory);
        let flight = volumes_from_plan(&p, &VolumeOptions::default()).expect("volumes");
        let want = if trajectory {
            Timing::Trajectory
        } else {
            Timing::ConstantSpeed
        };
        assert_eq!(flight.timing, want);
        assert!(
            flight.relative.len() >= 4,
            "{} volumes",
            flight.relative.len()
        );
        if let Some(t) = &p.trajectory {
            assert!((flight.duration_s - t.duration_s).abs() < 1e-9);
        } else {
            // At most 10 m/s: no faster than the route's length allows.
            assert!(flight.duration_s >= p.mission_length_m / 10.0);
        }
        assert_covers(&p, &flight, t0());
        // Shorter stretches, wider margins: still covered, more volumes.
        let tight = VolumeOptions {
            stretch_m: 40.0,
            stretch_s: 5.0,
            lateral_margin_m: 2.0,
            ..Default::default()
        };
        let more = volumes_from_plan(&p, &tight).expect("volumes");
        assert!(more.relative.len() > flight.relative.len());
        assert_covers(&p, &more, t0().plus_ms(1234));
        for v in &more.relative {
            let intent = OperationalIntent {
                id: "x".into(),
                version: 1,
                state: IntentState::Accepted,
                priority: 0,
                owner: "o".into(),
                volumes: vec![v.clone()],
            };
            intent.validate().expect("valid");
        }
    }
}

#[test]
fn timed_route_accelerates_from_rest_and_stops_at_the_goal() {
    // An L-shaped route of 30 m + 40 m: 2.5 s up to 10 m/s (12.5 m), 4.5 s at 10 m/s, 2.5 s
    // down.
    let path = timed_route(
        &[[0.0, 0.0, 5.0], [30.0, 0.0, 5.0], [30.0, 40.0, 5.0]],
        10.0,
        4.0,
        10.0,
    )
    .expect("timed");
    assert!((path.last().expect("points").t_s - 9.5).abs() < 1e-12);
    assert!(path.windows(2).all(|w| w[0].t_s <= w[1].t_s));
    // The corner is a point of the path, at its own time: 30 m = 12.5 m of ramp + 1.75 s.
    let corner = path
        .iter()
        .find(|p| p.nea == [30.0, 0.0, 5.0])
        .expect("the corner");
    assert!((corner.t_s - 4.25).abs() < 1e-12);
    // Speed never above 10 m/s between samples.
    for w in path.windows(2) {
        let d = ((w[1].nea[0] - w[0].nea[0]).hypot(w[1].nea[1] - w[0].nea[1])).max(0.0);
        assert!(d <= 10.0 * (w[1].t_s - w[0].t_s) + 1e-9);
    }
    // Too short to reach the cruise speed: a triangle, 2·√(L/a).
    let short = timed_route(&[[0.0, 0.0, 5.0], [4.0, 0.0, 5.0]], 10.0, 4.0, 10.0).expect("timed");
    assert!((short.last().expect("points").t_s - 2.0).abs() < 1e-12);
}

#[test]
fn the_json_is_the_dss_shape_and_reads_back() {
    let mut session = Session::new(World::fcnd_city());
    let p = plan(&mut session, [0.0, 0.0], [420.0, 390.0], 10.0, false);
    let flight = volumes_from_plan(&p, &VolumeOptions::default()).expect("volumes");
    let intent = OperationalIntent {
        id: "9c3e8f0a-0000-4000-8000-000000000001".into(),
        version: 1,
        state: IntentState::Accepted,
        priority: 10,
        owner: "op".into(),
        volumes: flight.at(t0()),
    };
    let json = serde_json::to_value(&intent).expect("serialisable");
    let keys = |v: &Value| {
        v.as_object()
            .expect("an object")
            .keys()
            .cloned()
            .collect::<Vec<_>>()
    };
    assert_eq!(
        keys(&json),
        ["id", "owner", "priority", "state", "version", "volumes"]
    );
    assert_eq!(json["state"], "Accepted");
    let v = &json["volumes"][0];
    assert_eq!(keys(v), ["time_end", "time_start", "volume"]);
    assert_eq!(
        keys(&v["volume"]),
        ["altitude_lower", "altitude_upper", "outline_polygon"]
    );
    assert_eq!(keys(&v["volume"]["outline_polygon"]), ["vertices"]);
    assert_eq!(
        keys(&v["volume"]["outline_polygon"]["vertices"][0]),
        ["lat", "lng"]
    );
    assert_eq!(
        v["volume"]["altitude_lower"],
        json!({ "value": 0.0, "reference": "W84", "units": "M" })
    );
    assert_eq!(
        v["volume"]["altitude_upper"],
        json!({ "value": 20.0, "reference": "W84", "units": "M" })
    );
    assert_eq!(
        v["time_start"],
        json!({ "value": "2026-03-01T11:59:50Z", "format": "RFC3339" })
    );
    let back: OperationalIntent = serde_json::from_value(json.clone()).expect("reads back");
    assert_eq!(back, intent);
    // Unknown fields and values outside the DSS's enums are refused.
    for (path, bad) in [
        ("/volumes/0/volume/altitude_lower/reference", json!("AGL")),
        ("/volumes/0/volume/altitude_lower/units", json!("FT")),
        ("/volumes/0/time_start/format", json!("unix")),
        ("/volumes/0/time_start/value", json!("yesterday")),
        ("/state", json!("Flying")),
    ] {
        let mut broken = json.clone();
        *broken.pointer_mut(path).expect("the path") = bad;
        assert!(
            serde_json::from_value::<OperationalIntent>(broken).is_err(),
            "{path}"
        );
    }
    let mut extra = json.clone();
    extra["volumes"][0]["volume"]["extra"] = json!(1);
    assert!(serde_json::from_value::<OperationalIntent>(extra).is_err());
    // Validation names the field.
    let mut flat = intent.clone();
    flat.volumes[1].volume.outline_polygon.vertices.truncate(2);
    assert_eq!(
        flat.validate().map_err(|e| e.to_string()),
        Err(
            "volumes[1].volume.outline_polygon: fewer than 3 vertices, or they enclose no area"
                .into()
        )
    );
    let mut upside = intent.clone();
    upside.volumes[0].volume.altitude_lower.value = 99.0;
    assert!(upside.validate().is_err_and(|e| {
        e.to_string()
            .starts_with("volumes[0].volume.altitude_lower")
    }));
}

/// Flights crossing the city in both directions and diagonally, at 10 and 30 m.
fn crossing_flights(session: &mut Session) -> Vec<FlightVolumes> {
    let routes = [
        ([0.0, 0.0], [420.0, 390.0], 10.0),
        ([420.0, 390.0], [0.0, 0.0], 10.0),
        ([0.0, 0.0], [420.0, 390.0], 30.0),
        ([300.0, 0.0], [48.5, 399.5], 10.0),
        ([48.5, 399.5], [300.0, 0.0], 30.0),
    ];
    routes
        .iter()
        .map(|&(s, g, alt)| {
            volumes_from_plan(&plan(session, s, g, alt, false), &VolumeOptions::default())
                .expect("volumes")
        })
        .collect()
}

#[test]
fn the_earliest_departure_is_the_first_free_one_on_the_grid() {
    let mut session = Session::new(World::fcnd_city());
    let flights = crossing_flights(&mut session);
    let mut rng = ChaCha8Rng::seed_from_u64(25);
    let (mut free, mut delayed, mut blocked) = (0, 0, 0);
    for round in 0..40 {
        // Some stored intents at random departures and priorities.
        let stored: Vec<OperationalIntent> = (0..rng.random_range(1..6))
            .map(|k| {
                let f = &flights[rng.random_range(0..flights.len())];
                OperationalIntent {
                    id: format!("stored-{round}-{k}"),
                    version: 1 + k as u64,
                    state: if rng.random_range(0..8) == 0 {
                        IntentState::Ended
                    } else {
                        IntentState::Accepted
                    },
                    priority: rng.random_range(0..3),
                    owner: "other".into(),
                    volumes: f.at(t0().plus_ms(rng.random_range(-60_000..240_000))),
                }
            })
            .collect();
        let flight = &flights[rng.random_range(0..flights.len())];
        let priority = rng.random_range(0..3);
        let step_ms = [1000, 250, 7000][round % 3];
        let window = DepartureWindow {
            earliest: t0(),
            latest: t0().plus_ms(rng.random_range(0..600_000)),
        };
        let got = earliest_departure(
            flight,
            window,
            priority,
            &stored,
            PriorityRule::EqualOrHigher,
            step_ms,
        );
        // Brute force: every departure of the grid, the full conflict test.
        let mut want = None;
        let mut d = window.earliest;
        while d <= window.latest {
            let me = OperationalIntent {
                id: "me".into(),
                version: 1,
                state: IntentState::Accepted,
                priority,
                owner: "me".into(),
                volumes: flight.at(d),
            };
            if conflicts(&me, &stored, PriorityRule::EqualOrHigher).is_empty() {
                want = Some(d);
                break;
            }
            d = d.plus_ms(step_ms);
        }
        match (got, want) {
            (Ok(dep), Some(d)) => {
                assert_eq!(dep.departure, d, "round {round}");
                assert_eq!(dep.delay_ms, d.ms_since(t0()));
                assert_eq!(dep.volumes, flight.at(d));
                if dep.delay_ms == 0 {
                    free += 1;
                } else {
                    delayed += 1;
                }
            }
            (Err(DepartureError::Blocked(b)), None) => {
                assert!(!b.blocking.is_empty());
                // Each named intent binds this flight and is not ended.
                for r in &b.blocking {
                    let s = stored
                        .iter()
                        .find(|s| s.reference() == *r)
                        .expect("a stored intent");
                    assert!(PriorityRule::EqualOrHigher.binds(priority, s));
                }
                blocked += 1;
            }
            (got, want) => panic!("round {round}: search {got:?}, brute force {want:?}"),
        }
    }
    eprintln!("{free} free at once, {delayed} delayed, {blocked} blocked");
    assert!(
        free > 0 && delayed > 5 && blocked > 0,
        "{free} free, {delayed} delayed, {blocked} blocked"
    );
}

#[test]
fn a_blocked_window_names_the_blocking_intents() {
    let mut session = Session::new(World::fcnd_city());
    let flights = crossing_flights(&mut session);
    let stored = OperationalIntent {
        id: "blocker".into(),
        version: 3,
        state: IntentState::Activated,
        priority: 2,
        owner: "o".into(),
        volumes: flights[0].at(t0()),
    };
    let window = DepartureWindow {
        earliest: t0(),
        latest: t0().plus_ms(10_000),
    };
    let err = earliest_departure(
        &flights[1],
        window,
        1,
        std::slice::from_ref(&stored),
        PriorityRule::EqualOrHigher,
        1000,
    )
    .expect_err("blocked");
    assert_eq!(
        err.to_string(),
        "no departure from 2026-03-01T12:00:00Z to 2026-03-01T12:00:10Z is free of the intents of equal or higher priority: blocked by blocker (version 3)"
    );
    // A more important flight is not blocked; with every intent binding it is.
    assert!(
        earliest_departure(
            &flights[1],
            window,
            3,
            std::slice::from_ref(&stored),
            PriorityRule::EqualOrHigher,
            1000
        )
        .is_ok()
    );
    assert!(
        earliest_departure(
            &flights[1],
            window,
            3,
            std::slice::from_ref(&stored),
            PriorityRule::Every,
            1000
        )
        .is_err()
    );
    // An ended intent blocks nobody.
    let ended = OperationalIntent {
        state: IntentState::Ended,
        ..stored.clone()
    };
    assert_eq!(
        earliest_departure(&flights[1], window, 0, &[ended], PriorityRule::Every, 1000)
            .map(|d| d.delay_ms),
        Ok(0)
    );
    // A window that ends before it starts is refused.
    let backwards = DepartureWindow {
        earliest: window.latest,
        latest: window.earliest,
    };
    assert!(matches!(
        earliest_departure(&flights[1], backwards, 0, &[], PriorityRule::Every, 1000),
        Err(DepartureError::Invalid(_))
    ));
}

/// A random convex polygon: the hull of a few points, integer (exact, touching cases happen)
/// or not.
fn random_polygon(rng: &mut ChaCha8Rng, integer: bool) -> Vec<[f64; 2]> {
    loop {
        let n = rng.random_range(3..9);
        let (cx, cy) = (rng.random_range(0..16), rng.random_range(0..16));
        let pts: Vec<[f64; 2]> = (0..n)
            .map(|_| {
                if integer {
                    [
                        f64::from(cx + rng.random_range(0..6)),
                        f64::from(cy + rng.random_range(0..6)),
                    ]
                } else {
                    [
                        f64::from(cx) * 3.0 + rng.random_range(-9.0..9.0),
                        f64::from(cy) * 3.0 + rng.random_range(-9.0..9.0),
                    ]
                }
            })
            .collect();
        let h = convex_hull(&pts);
        if h.len() >= 3 {
            return h;
        }
    }
}

/// A volume whose footprint is `poly` read as degrees scaled about a point in San Francisco.
fn volume_of(poly: &[[f64; 2]]) -> Volume4D {
    Volume4D {
        volume: Volume3D {
            outline_polygon: Polygon {
                vertices: poly
                    .iter()
                    .map(|p| LatLng {
                        lat: 37.79 + p[1] * 1e-4,
                        lng: -122.40 + p[0] * 1e-4,
                    })
                    .collect(),
            },
            altitude_lower: Altitude::w84_m(0.0),
            altitude_upper: Altitude::w84_m(10.0),
        },
        time_start: t0().into(),
        time_end: t0().into(),
    }
}

#[test]
#[ignore = "needs SKYPLAN_PYTHON with shapely (.ci/run's virtual environment has it)"]
fn the_footprint_test_agrees_with_shapely() {
    let python = std::env::var("SKYPLAN_PYTHON").unwrap_or_else(|_| "python3".into());
    let mut rng = ChaCha8Rng::seed_from_u64(3548);
    // Planar polygons (the separating-axis test itself) and the same read as lat/lng volumes.
    type Pair = (Vec<[f64; 2]>, Vec<[f64; 2]>);
    let pairs: Vec<Pair> = (0..3000)
        .map(|k| {
            (
                random_polygon(&mut rng, k % 2 == 0),
                random_polygon(&mut rng, k % 2 == 0),
            )
        })
        .collect();
    let volumes: Vec<(Volume4D, Volume4D)> = pairs
        .iter()
        .filter(|_| true)
        .map(|(a, b)| (volume_of(a), volume_of(b)))
        .collect();
    let latlng = |v: &Volume4D| {
        v.volume
            .outline_polygon
            .vertices
            .iter()
            .map(|p| [p.lng, p.lat])
            .collect::<Vec<_>>()
    };
    let input = json!({
        "planar": pairs,
        "geo": volumes.iter().map(|(a, b)| (latlng(a), latlng(b))).collect::<Vec<_>>(),
    });
    let dir = std::env::temp_dir().join(format!("skyplan-shapely-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let file = dir.join("pairs.json");
    std::fs::write(&file, input.to_string()).expect("written");
    let script = "import json, sys\nfrom shapely.geometry import Polygon\n\
        d = json.load(open(sys.argv[1]))\n\
        out = {k: [Polygon(a).intersects(Polygon(b)) for a, b in d[k]] for k in ('planar', 'geo')}\n\
        print(json.dumps(out))\n";
    let out = std::process::Command::new(&python)
        .arg("-c")
        .arg(script)
        .arg(&file)
        .output()
        .expect("python runs");
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let answers: Value = serde_json::from_slice(&out.stdout).expect("JSON from python");
    let (mut touching, mut meeting) = (0, 0);
    for (k, (a, b)) in pairs.iter().enumerate() {
        let want = answers["planar"][k].as_bool().expect("a bool");
        assert_eq!(convex_intersect(a, b), want, "planar pair {k}: {a:?} {b:?}");
        meeting += usize::from(want);
        // Touching at a shared vertex at least (exact on the integer pairs).
        touching += usize::from(want && (0..a.len()).any(|i| b.contains(&a[i])));
    }
    for (k, (a, b)) in volumes.iter().enumerate() {
        let want = answers["geo"][k].as_bool().expect("a bool");
        // Integer pairs that touch exactly may round either way on the sphere's plane: those are
        // checked in the planar list above.
        if k % 2 == 1 {
            assert_eq!(footprints_intersect(a, b), want, "lat/lng pair {k}");
        }
    }
    eprintln!(
        "{} pairs, {meeting} intersecting, {touching} sharing a vertex: all as shapely says",
        pairs.len()
    );
    assert!(meeting > 300 && meeting < 2700 && touching > 10);
}

/// `first_conflict` (boxes computed once per call) names the same first pair as testing every
/// pair in order with `volumes_conflict`, on random intents whose volumes overlap in time, in
/// altitude and in footprint in every combination.
#[test]
fn the_first_conflict_is_the_first_pair_volumes_conflict_finds() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let random_volume = |rng: &mut ChaCha8Rng| {
        let integer = rng.random_bool(0.5);
        let mut v = volume_of(&random_polygon(rng, integer));
        let start = Timestamp::from_unix_ms(t0().unix_ms() + rng.random_range(0..30) * 1000);
        v.time_start = start.into();
        v.time_end =
            Timestamp::from_unix_ms(start.unix_ms() + rng.random_range(0..20) * 1000).into();
        let lower = f64::from(rng.random_range(0..3)) * 10.0;
        v.volume.altitude_lower = Altitude::w84_m(lower);
        v.volume.altitude_upper = Altitude::w84_m(lower + f64::from(rng.random_range(0..3)) * 10.0);
        v
    };
    let (mut found, mut clear) = (0, 0);
    for _ in 0..400 {
        let new: Vec<Volume4D> = (0..rng.random_range(0..6))
            .map(|_| random_volume(&mut rng))
            .collect();
        let stored: Vec<Volume4D> = (0..rng.random_range(0..6))
            .map(|_| random_volume(&mut rng))
            .collect();
        let every_pair = new.iter().enumerate().find_map(|(i, a)| {
            stored
                .iter()
                .position(|b| volumes_conflict(a, b))
                .map(|j| (i, j))
        });
        assert_eq!(first_conflict(&new, &stored), every_pair);
        if every_pair.is_some() {
            found += 1;
        } else {
            clear += 1;
        }
    }
    assert!(found > 50 && clear > 50, "{found} {clear}");
}
