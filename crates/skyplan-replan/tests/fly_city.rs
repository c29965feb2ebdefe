//! End to end without a network: fly the city's default route with buildings the map does not
//! know, sensing them with a simulated range sensor, and replanning around them.

mod common;

use common::{
    Flight, city_hidden_spec, first_collision, fly, route_ne, segment_meets_box, track_length_m,
};
use skyplan_map::colliders::{ObstacleBox, parse_colliders};
use skyplan_plan::{FCND_CITY_CSV, FCND_DEFAULT_GOAL_NE, PlanRequest, Session, World};
use skyplan_replan::hidden::{place_hidden, true_world};
use skyplan_replan::{ReplanOptions, Replanner, ReplannerKind};

const SAFETY_M: f64 = 5.0;
const ALT_M: f64 = 5.0;

fn replanner(kind: ReplannerKind) -> Replanner {
    replanner_with(ReplanOptions {
        replanner: kind,
        ..Default::default()
    })
}

fn replanner_with(options: ReplanOptions) -> Replanner {
    Replanner::new(
        Session::new(World::fcnd_city()),
        &PlanRequest::default(),
        options,
    )
    .expect("the default request plans")
}

/// Hidden buildings across the default route: one hand-placed across the long northbound leg,
/// plus random ones (seeded) on or near the route.
fn hidden_across_route(r: &Replanner) -> Vec<ObstacleBox> {
    let map = parse_colliders(FCND_CITY_CSV).expect("the bundled map parses");
    // The spec's altitude and margin are this test's ALT_M and SAFETY_M.
    let spec = city_hidden_spec(route_ne(&r.initial_plan().waypoints), 4, 11);
    let mut hidden = place_hidden(&map, &spec).expect("room for the hidden buildings");
    hidden.push(ObstacleBox {
        north_m: 320.0,
        east_m: -48.0,
        up_m: 20.0,
        half_north_m: 4.0,
        half_east_m: 7.0,
        half_up_m: 20.0,
    });
    hidden
}

/// The city's boxes and `extra` ones: the true world of a flight.
fn city_truth(extra: &[ObstacleBox]) -> Vec<ObstacleBox> {
    let map = parse_colliders(FCND_CITY_CSV).expect("the bundled map parses");
    map.boxes.iter().chain(extra).copied().collect()
}

/// Four walls 2 m thick and `half_up_m` × 2 tall in a square 32 m across about the default goal.
fn ring_around_goal(half_up_m: f64) -> [ObstacleBox; 4] {
    let [gn, ge] = FCND_DEFAULT_GOAL_NE;
    let wall = |dn: f64, de: f64, hn: f64, he: f64| ObstacleBox {
        north_m: gn + dn,
        east_m: ge + de,
        up_m: half_up_m,
        half_north_m: hn,
        half_east_m: he,
        half_up_m,
    };
    [
        wall(16.0, 0.0, 1.0, 17.0),
        wall(-16.0, 0.0, 1.0, 17.0),
        wall(0.0, 16.0, 17.0, 1.0),
        wall(0.0, -16.0, 17.0, 1.0),
    ]
}

/// Flies the default route (D* Lite) in the city with [`ring_around_goal`]`(half_up_m)` added;
/// the flight and the true boxes.
fn fly_to_walled_goal(half_up_m: f64) -> (Flight, Vec<ObstacleBox>) {
    let mut r = replanner(ReplannerKind::DStarLite);
    let truth = city_truth(&ring_around_goal(half_up_m));
    let targets = r.initial_targets();
    let flight = fly(&mut r, targets, &truth, [0.0, 0.0, ALT_M], 5.0, 0.1, 1200.0);
    (flight, truth)
}

/// Whether a replan of `flight` climbed to another altitude.
fn tried_climbing(flight: &Flight) -> bool {
    flight
        .replans
        .iter()
        .any(|e| e.reason.contains("climbing to"))
}

/// The highest altitude `flight` reached, metres.
fn highest_m(flight: &Flight) -> f64 {
    flight.track.iter().map(|p| p[2]).fold(f64::MIN, f64::max)
}

/// Flies the default route into [`hidden_across_route`] and checks the flight: at the goal, no
/// collision, every replan explained; returns the flight.
fn flies_around_hidden_buildings(options: ReplanOptions) -> Flight {
    let kind = options.replanner;
    let mut r = replanner_with(options);
    let hidden = hidden_across_route(&r);
    let truth = city_truth(&hidden);
    // The first plan flies through at least one hidden building: the test means something.
    let first: Vec<[f64; 3]> = r
        .initial_plan()
        .waypoints
        .iter()
        .map(|w| [w[0], w[1], w[2]])
        .collect();
    let crosses = first
        .windows(2)
        .any(|w| hidden.iter().any(|b| segment_meets_box(w[0], w[1], b, 0.0)));
    assert!(crosses, "no hidden building lies across the first plan");
    let targets = r.initial_targets();
    let flight = fly(&mut r, targets, &truth, [0.0, 0.0, ALT_M], 5.0, 0.1, 900.0);
    assert!(flight.hold.is_none(), "held: {:?}", flight.hold);
    assert!(
        flight.reached_goal,
        "did not reach the goal; last at {:?}",
        flight.track.last()
    );
    let end = flight.track.last().copied().unwrap_or_default();
    assert!((end[0] - FCND_DEFAULT_GOAL_NE[0]).hypot(end[1] - FCND_DEFAULT_GOAL_NE[1]) < 1e-6);
    assert!(!flight.replans.is_empty(), "never replanned");
    for e in &flight.replans {
        assert!(e.planner.starts_with(kind.name()), "{}", e.planner);
        assert!(
            e.reason.starts_with("learned obstacle at N "),
            "{}",
            e.reason
        );
        assert!(e.route_length_m > 0.0 && e.learned_cells > 0);
    }
    // Never inside a true obstacle grown by half the margin.
    if let Some((a, b, bx)) = first_collision(&flight.track, &truth, SAFETY_M / 2.0) {
        panic!(
            "track {a:?} → {b:?} meets the box at N {} E {} grown by {} m",
            bx.north_m,
            bx.east_m,
            SAFETY_M / 2.0
        );
    }
    assert_eq!(r.stats().replans as usize, flight.replans.len());
    // The flown track is no shorter than the optimum with full knowledge of the true world.
    let flown = track_length_m(&flight.track);
    let mut true_session =
        Session::new(true_world(&World::fcnd_city(), &hidden).expect("true world"));
    let optimum = true_session
        .plan(&PlanRequest::default())
        .expect("the true world has a path");
    assert!(
        flown >= optimum.cost_m * 0.99,
        "flown {flown} m < full-knowledge octile optimum {} m",
        optimum.cost_m
    );
    flight
}

#[test]
fn dstar_lite_flies_around_hidden_buildings_to_the_goal() {
    flies_around_hidden_buildings(ReplanOptions::default());
}

#[test]
fn scratch_flies_around_hidden_buildings_to_the_goal() {
    flies_around_hidden_buildings(ReplanOptions {
        replanner: ReplannerKind::Scratch,
        ..Default::default()
    });
}

#[test]
fn dstar_lite_over_its_budget_falls_back_and_catches_up() {
    // A budget far too small for some repairs: those replans search from scratch, and D* Lite
    // repairs on at the readings that follow, so a later replan is its own again.
    const BUDGET: u64 = 300;
    let map = parse_colliders(FCND_CITY_CSV).expect("the bundled map parses");
    let (mut fell_back, mut caught_up) = (0, 0);
    for seed in 0..4 {
        let mut r = replanner_with(ReplanOptions {
            dstar_budget_expansions: Some(BUDGET),
            ..Default::default()
        });
        let spec = city_hidden_spec(route_ne(&r.initial_plan().waypoints), 5, seed);
        let hidden = place_hidden(&map, &spec).expect("room for the hidden buildings");
        let truth = city_truth(&hidden);
        let targets = r.initial_targets();
        let flight = fly(&mut r, targets, &truth, [0.0, 0.0, ALT_M], 5.0, 0.1, 1800.0);
        assert!(flight.reached_goal && flight.hold.is_none(), "seed {seed}");
        assert_eq!(first_collision(&flight.track, &truth, SAFETY_M / 2.0), None);
        let planners: Vec<&str> = flight.replans.iter().map(|e| e.planner.as_str()).collect();
        if let Some(k) = planners
            .iter()
            .position(|p| *p == "dstar-lite, over budget: scratch")
        {
            fell_back += 1;
            caught_up += usize::from(planners[k + 1..].contains(&"dstar-lite"));
        }
        for e in &flight.replans {
            if e.planner == "dstar-lite" {
                assert!(e.expansions <= BUDGET, "{} expansions", e.expansions);
            }
        }
    }
    assert!(fell_back > 0, "no replan went over the budget");
    assert!(
        caught_up > 0,
        "D* Lite never caught up after going over its budget"
    );
}

#[test]
fn a_hidden_wall_sealing_the_goal_ends_in_hold() {
    let (flight, truth) = fly_to_walled_goal(100.0);
    assert!(!flight.reached_goal);
    let reason = flight.hold.as_deref().expect("a hold");
    assert!(reason.contains("no route to the goal"), "{reason}");
    // It climbed to look over the wall before giving up (the wall is 200 m tall, the limit 30 m).
    assert!(tried_climbing(&flight), "never tried climbing");
    let top = highest_m(&flight);
    assert!(
        top > ALT_M + 1.0 && top <= 30.0 + 1e-9,
        "highest point {top} m"
    );
    assert!(
        reason.contains("30.0"),
        "the hold names the altitudes tried: {reason}"
    );
    assert_eq!(first_collision(&flight.track, &truth, SAFETY_M / 2.0), None);
}

#[test]
fn a_low_hidden_wall_around_the_goal_is_climbed_over() {
    // 12 m tall (half 6 m): walled off at 5 m (and, with the 5 m margin, up to 17 m), open above.
    let (flight, truth) = fly_to_walled_goal(6.0);
    assert!(flight.hold.is_none(), "held: {:?}", flight.hold);
    assert!(flight.reached_goal);
    assert!(tried_climbing(&flight));
    let top = highest_m(&flight);
    assert!(
        top > 12.0 + SAFETY_M / 2.0 && top <= 30.0 + 1e-9,
        "highest point {top} m"
    );
    assert_eq!(first_collision(&flight.track, &truth, SAFETY_M / 2.0), None);
}
