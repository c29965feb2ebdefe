//! A fleet re-routed in space and time on the FCND city, checked independently: no two
//! accepted intents intersect (every pair, the exact 4D test), every route keeps the margin
//! from every building (the colliders file's own boxes, sampled every 25 cm), and the search
//! did what it is for (flights hovered and went around).

use skyplan_airspace::{PriorityRule, Timestamp};
use skyplan_airspace_store::{IntentStore, SqliteStore};
use skyplan_fleet::{
    Mission, Mode, RandomMissions, RunOptions, Status, Summary, binding_conflicts, fly_fleet,
    random_missions,
};
use skyplan_plan::{FCND_CITY_CSV, PlanRequest, Session, World};

/// The city's boxes `[n, e, alt, half_n, half_e, half_alt]`, read here from the text.
fn boxes() -> Vec<[f64; 6]> {
    FCND_CITY_CSV
        .lines()
        .skip(2)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|x| x.trim().parse().expect("number"))
                .collect();
            [v[0], v[1], v[2], v[3], v[4], v[5]]
        })
        .collect()
}

/// Distance from a point to a box's footprint, for boxes reaching `alt_m` (grown by `margin`).
fn clearance(boxes: &[[f64; 6]], n: f64, e: f64, alt_m: f64, margin: f64) -> f64 {
    boxes
        .iter()
        .filter(|b| b[2] - b[5] - margin <= alt_m && alt_m <= b[2] + b[5] + margin)
        .map(|b| {
            let dn = ((n - b[0]).abs() - b[3]).max(0.0);
            let de = ((e - b[1]).abs() - b[4]).max(0.0);
            (dn * dn + de * de).sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The city's session and `count` random missions (seed, departures spread over `spread_s`,
/// windows of `window_s`) from 2026-03-01T12:00:00Z.
fn crowd(count: usize, seed: u64, spread_s: f64, window_s: f64) -> (Session, Vec<Mission>) {
    let mut session = Session::new(World::fcnd_city());
    let spec = PlanRequest::default().spec().expect("spec");
    let grid = session
        .grid(spec.alt_m, spec.safety_m, spec.cell_m)
        .expect("grid");
    let start: Timestamp = "2026-03-01T12:00:00Z".parse().expect("time");
    let missions = random_missions(
        &grid,
        spec.move_model,
        &RandomMissions {
            count,
            seed,
            min_distance_m: 300.0,
            spread_s,
            window_s,
            start,
        },
    );
    (session, missions)
}

#[test]
fn a_crowded_fleet_is_rerouted_in_space_and_time_without_a_conflict() {
    let base = PlanRequest::default();
    let spec = base.spec().expect("spec");
    let (mut session, missions) = crowd(24, 5, 120.0, 300.0);
    let run = |mode: Mode, session: &mut Session| {
        let store = SqliteStore::open_url("sqlite::memory:").expect("store");
        let options = RunOptions {
            mode,
            ..RunOptions::default()
        };
        let records =
            fly_fleet(session, &store, &base, &missions, &options, |_, _| {}).expect("run");
        let stored = store.list().expect("list");
        (records, stored)
    };
    let (records, stored) = run(Mode::SpaceTime, &mut session);
    let summary = Summary::of(&records);
    assert_eq!(stored.len(), summary.accepted);
    assert!(
        binding_conflicts(&stored, PriorityRule::EqualOrHigher).is_empty(),
        "accepted intents intersect"
    );
    // Every accepted route keeps the margin from every building at its altitude.
    let boxes = boxes();
    let (alt, margin) = (spec.alt_m, spec.safety_m);
    let mut samples = 0;
    for r in records.iter().filter(|r| r.status == Status::Accepted) {
        for w in r.route_ne.windows(2) {
            let ((n0, e0), (n1, e1)) = (w[0], w[1]);
            let steps = ((n1 - n0).hypot(e1 - e0) / 0.25).ceil().max(1.0) as usize;
            for k in 0..=steps {
                let f = k as f64 / steps as f64;
                let (n, e) = (n0 + f * (n1 - n0), e0 + f * (e1 - e0));
                let c = clearance(&boxes, n, e, alt, margin);
                assert!(
                    c >= margin - 1e-6,
                    "{}: {c:.2} m from a building at N {n:.1}, E {e:.1}",
                    r.mission
                );
                samples += 1;
            }
        }
    }
    assert!(samples > 10_000, "{samples}");
    // The crowd made the search hover and go around.
    assert!(
        summary.hovering >= 1 && summary.detoured >= 1,
        "{summary:?}"
    );
    // Against shifting the departure only, on the same missions: at least as many accepted.
    let (shifted, _) = run(Mode::Shift, &mut session);
    let shift = Summary::of(&shifted);
    assert!(
        summary.accepted >= shift.accepted,
        "space-time {} accepted, shift {}",
        summary.accepted,
        shift.accepted
    );
    eprintln!(
        "space-time: {} of {} accepted, arrival +{:.1} s mean, {} hovering, {} detoured; shift: {} accepted, +{:.1} s",
        summary.accepted,
        summary.missions,
        summary.arrival_delay_mean_s,
        summary.hovering,
        summary.detoured,
        shift.accepted,
        shift.arrival_delay_mean_s
    );
}

/// The search's model of the others is conservative enough that the store's exact check never
/// refuses what it found: with one writer, every reservation succeeds on its first try (a
/// refusal there would be searched again, and show as a second try).
#[test]
fn the_exact_check_accepts_every_route_the_search_finds_at_once() {
    use skyplan_airspace::DepartureWindow;
    use skyplan_fleet::{FlightRequest, reserve_space_time, search_grid};
    let base = PlanRequest::default();
    let (mut session, missions) = crowd(30, 11, 60.0, 120.0);
    let store = SqliteStore::open_url("sqlite::memory:").expect("store");
    let (mut accepted, mut waited) = (0, 0);
    for m in &missions {
        let plan = session.plan(&m.request(&base)).expect("a route");
        let search = search_grid(&mut session, &m.request(&base), &plan)
            .expect("grid")
            .expect("a grid plan");
        let request = FlightRequest::new(
            DepartureWindow {
                earliest: m.window.earliest,
                latest: m.window.latest,
            },
            0,
            "test".into(),
        );
        match reserve_space_time(&store, &search, &plan, &request).0 {
            Ok(r) => {
                assert_eq!(
                    r.tries, 1,
                    "{}: the exact check refused the search's route",
                    m.id
                );
                // It kept to the sky read: within the read reach of the planned route.
                let planned = plan.points_nea();
                let within_m = request.volumes.lateral_margin_m + skyplan_fleet::READ_REACH_M;
                for p in &r.path {
                    let d_m = planned
                        .windows(2)
                        .map(|w| {
                            skyplan_testkit::distance_to_segment(
                                [p.nea[0], p.nea[1]],
                                [w[0][0], w[0][1]],
                                [w[1][0], w[1][1]],
                            )
                        })
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        d_m <= within_m,
                        "{}: {d_m:.1} m from the planned route",
                        m.id
                    );
                }
                accepted += 1;
                waited += usize::from(r.arrival_delay_s > 0.0);
            }
            Err(skyplan_airspace_store::ReserveError::Blocked(_)) => {}
            Err(e) => panic!("{}: {e}", m.id),
        }
    }
    assert!(
        accepted >= 20 && waited >= 5,
        "{accepted} accepted, {waited} later than alone"
    );
}

/// The cached search (stored intents kept between flights, decoded once and rasterised on the
/// grid) answers exactly as the uncached one (every intent read, decoded and converted per
/// flight, cells tested against the footprints one by one): the same routes, times, volumes
/// and counts, flight by flight, on a crowded seeded fleet — with a cache large enough, and
/// with one of 8 intents that evicts on nearly every flight — while some accepted intents are
/// deleted again along the way (a deleted intent, still cached, must no longer block).
#[test]
fn the_cached_search_answers_exactly_as_the_uncached_one() {
    use skyplan_airspace::DepartureWindow;
    use skyplan_airspace_store::ReserveError;
    use skyplan_fleet::{
        FlightRequest, SpaceTimeCache, reserve_space_time, reserve_space_time_cached, search_grid,
    };
    let base = PlanRequest::default();
    let (mut session, missions) = crowd(48, 7, 240.0, 300.0);
    let exact = SqliteStore::open_url("sqlite::memory:").expect("store");
    let stores = [
        SqliteStore::open_url("sqlite::memory:").expect("store"),
        SqliteStore::open_url("sqlite::memory:").expect("store"),
    ];
    let mut caches = [SpaceTimeCache::new(), SpaceTimeCache::with_capacity(8)];
    let (mut accepted, mut refused, mut waited, mut deleted) = (0, 0, 0, 0);
    // The ids each store accepted, in order: the exact store's first.
    let mut ids: [Vec<String>; 3] = Default::default();
    for (k, m) in missions.iter().enumerate() {
        let plan = session.plan(&m.request(&base)).expect("a route");
        let search = search_grid(&mut session, &m.request(&base), &plan)
            .expect("grid")
            .expect("a grid plan");
        let request = FlightRequest::new(
            DepartureWindow {
                earliest: m.window.earliest,
                latest: m.window.latest,
            },
            0,
            "test".into(),
        );
        let (want, want_nearby) = reserve_space_time(&exact, &search, &plan, &request);
        for (i, (store, cache)) in stores.iter().zip(caches.iter_mut()).enumerate() {
            let (got, nearby) = reserve_space_time_cached(store, &search, &plan, &request, cache);
            assert_eq!(nearby, want_nearby, "{}: intents read", m.id);
            match (&want, &got) {
                (Ok(w), Ok(g)) => {
                    assert_eq!(
                        (w.delay_ms, w.departure, w.tries, w.expansions),
                        (g.delay_ms, g.departure, g.tries, g.expansions),
                        "{}",
                        m.id
                    );
                    assert_eq!(
                        (w.hover_s, w.detour_m, w.arrival_delay_s),
                        (g.hover_s, g.detour_m, g.arrival_delay_s),
                        "{}",
                        m.id
                    );
                    assert_eq!(w.route_nea, g.route_nea, "{}", m.id);
                    assert_eq!(w.intent.volumes, g.intent.volumes, "{}", m.id);
                    ids[i + 1].push(g.intent.id.clone());
                }
                (Err(ReserveError::Blocked(w)), Err(ReserveError::Blocked(g))) => {
                    assert_eq!(w.blocking.len(), g.blocking.len(), "{}", m.id);
                }
                (w, g) => panic!("{}: uncached {w:?}, cached {g:?}", m.id),
            }
        }
        match want {
            Ok(w) => {
                accepted += 1;
                waited += usize::from(w.arrival_delay_s > 0.0);
                ids[0].push(w.intent.id);
                // Now and then the flight accepted three before is cancelled, in all three
                // stores: read (and cached) by the flights since, it must block no more.
                if k % 5 == 4 && ids[0].len() >= 3 {
                    let at = ids[0].len() - 3;
                    let gone = exact.delete(&ids[0][at]).expect("delete");
                    assert!(gone.is_some());
                    for (store, ids) in stores.iter().zip(&ids[1..]) {
                        assert!(store.delete(&ids[at]).expect("delete").is_some());
                    }
                    deleted += 1;
                }
            }
            Err(ReserveError::Blocked(_)) => refused += 1,
            Err(e) => panic!("{}: {e}", m.id),
        }
    }
    assert_eq!(
        exact.list().expect("list").len(),
        stores[0].list().expect("list").len()
    );
    assert!(caches[0].len() > 20, "{}", caches[0].len());
    assert!(
        accepted >= 30 && waited >= 10 && deleted >= 3,
        "{accepted} accepted, {refused} refused, {waited} later than alone, {deleted} deleted"
    );
}

/// A timed no-fly zone blocks the space-time search only while it is active: the sample's
/// helipad (feature 1) across the default route, closed from the window's start for an hour,
/// is kept out of by the margin (exactly, segment by segment); opening only half an hour after
/// the window's start, after the flight, it is flown straight over. The stadium (no times)
/// is kept out of in both.
#[test]
fn a_timed_zone_blocks_the_space_time_search_only_while_active() {
    use skyplan_airspace::DepartureWindow;
    use skyplan_fleet::{FlightRequest, reserve_space_time, search_grid};
    use skyplan_map::nofly::{Zone, rfc3339_from_unix_s};
    let t0: Timestamp = "2026-03-01T12:00:00Z".parse().expect("time");
    let at = |s: i64| rfc3339_from_unix_s(t0.unix_ms() / 1000 + s);
    let zones_text = |start: String, end: String| {
        let mut v: serde_json::Value =
            serde_json::from_str(include_str!("../../../data/no-fly-sample.geojson"))
                .expect("json");
        v["features"][1]["properties"]["start"] = start.into();
        v["features"][1]["properties"]["end"] = end.into();
        v.to_string()
    };
    // The smallest distance, over the segments flown while the zone is active, to the zone.
    let clearance = |r: &skyplan_fleet::SpaceTimeFlight, z: &Zone| {
        let dep = r.departure.unix_ms() as f64 / 1000.0;
        r.path
            .windows(2)
            .filter(|w| {
                z.start_unix_s.is_none_or(|s| s as f64 <= dep + w[1].t_s)
                    && z.end_unix_s.is_none_or(|e| e as f64 > dep + w[0].t_s)
            })
            .map(|w| z.clearance_m([w[0].nea[0], w[0].nea[1]], [w[1].nea[0], w[1].nea[1]]))
            .fold(f64::INFINITY, f64::min)
    };
    let mut session = Session::new(World::fcnd_city());
    for (window, closed_all_along) in [((at(-3600), at(3600)), true), ((at(1800), at(7200)), false)]
    {
        let request = PlanRequest {
            no_fly: Some(zones_text(window.0, window.1)),
            ..PlanRequest::default()
        };
        let plan = session.plan(&request).expect("a route");
        let space = search_grid(&mut session, &request, &plan)
            .expect("grid")
            .expect("a grid plan");
        let store = SqliteStore::open_url("sqlite::memory:").expect("store");
        let flight = FlightRequest::new(
            DepartureWindow {
                earliest: t0,
                latest: t0.plus_ms(600_000),
            },
            0,
            "zones".into(),
        );
        let r = reserve_space_time(&store, &space, &plan, &flight)
            .0
            .expect("reserved");
        let (stadium, helipad) = (&space.zones[0], &space.zones[1]);
        assert!(
            clearance(&r, stadium) >= 5.0 - 1e-3,
            "{}",
            clearance(&r, stadium)
        );
        // Every point of the flight, whatever the zone's times.
        let whole = Zone {
            start_unix_s: None,
            end_unix_s: None,
            ..helipad.clone()
        };
        if closed_all_along {
            assert!(
                clearance(&r, helipad) >= 5.0 - 1e-3,
                "{}",
                clearance(&r, helipad)
            );
        } else {
            assert!(
                clearance(&r, &whole) < 5.0,
                "the open helipad is gone around"
            );
            assert_eq!(
                clearance(&r, helipad),
                f64::INFINITY,
                "flown while it was closed"
            );
        }
    }
}

/// A search that passes its deadline stops there: the flight is `timed_out`, says so, and
/// nothing is stored for it; with time to spare the same missions are all decided.
#[test]
fn a_flight_whose_search_passes_its_deadline_times_out_and_reserves_nothing() {
    let base = PlanRequest::default();
    let (mut session, missions) = crowd(12, 5, 120.0, 300.0);
    let run = |deadline: Option<std::time::Duration>, session: &mut Session| {
        let store = SqliteStore::open_url("sqlite::memory:").expect("store");
        let options = RunOptions {
            mode: Mode::SpaceTime,
            search_deadline: deadline,
            ..RunOptions::default()
        };
        let records =
            fly_fleet(session, &store, &base, &missions, &options, |_, _| {}).expect("run");
        (records, store.list().expect("list"))
    };
    // A deadline already passed when the search starts: it stops at its first look at the
    // clock, so every flight whose search needs more states than that times out.
    let (records, stored) = run(Some(std::time::Duration::ZERO), &mut session);
    let summary = Summary::of(&records);
    assert!(summary.timed_out >= 1, "{summary:?}");
    assert_eq!(stored.len(), summary.accepted);
    for r in records.iter().filter(|r| r.status == Status::TimedOut) {
        let message = r.message.as_deref().unwrap_or_default();
        assert!(
            message.contains("deadline") && message.contains("nothing was reserved"),
            "{}: {message}",
            r.mission
        );
        assert!(
            r.intent_id.is_none() && r.departure.is_none(),
            "{}",
            r.mission
        );
    }
    assert_eq!(Status::TimedOut.name(), "timed_out");
    // Without a deadline (or a generous one), none times out.
    let (records, _) = run(Some(std::time::Duration::from_secs(600)), &mut session);
    assert_eq!(Summary::of(&records).timed_out, 0);
}
