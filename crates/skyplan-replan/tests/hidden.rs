//! Hidden buildings: near the route, clear of both ends with the margin, the goal still
//! reachable in the true world (checked with the exact oracle on the true world's grid).

mod common;

use common::{city_hidden_spec, route_ne};
use skyplan_map::colliders::parse_colliders;
use skyplan_plan::{FCND_CITY_CSV, FCND_DEFAULT_GOAL_NE, PlanRequest, Session, World};
use skyplan_replan::hidden::{HiddenError, HiddenSpec, place_hidden, true_world};
use skyplan_search::MoveModel;
use skyplan_search::oracle::dijkstra_exact;

#[test]
fn hidden_buildings_lie_on_the_route_leave_both_ends_clear_and_the_goal_reachable() {
    let map = parse_colliders(FCND_CITY_CSV).expect("the bundled map parses");
    let plan = Session::new(World::fcnd_city())
        .plan(&PlanRequest::default())
        .expect("plan");
    let route_ne = route_ne(&plan.waypoints);
    for seed in 0..3 {
        // Start at home, the default goal, 5 m altitude, 5 m margin, 1 m octile cells.
        let spec = city_hidden_spec(route_ne.clone(), 6, seed);
        let hidden = place_hidden(&map, &spec).expect("room");
        assert_eq!(hidden.len(), 6);
        for b in &hidden {
            let near = route_ne
                .windows(2)
                .map(|w| skyplan_testkit::distance_to_segment([b.north_m, b.east_m], w[0], w[1]))
                .fold(f64::INFINITY, f64::min);
            assert!(
                near <= 6.0 * std::f64::consts::SQRT_2 + 1e-9,
                "{near} m from the route"
            );
            assert!(b.bottom_m() <= 0.0 && b.top_m() > 5.0 + 15.0 - 1e-9);
            for end in [[0.0, 0.0], FCND_DEFAULT_GOAL_NE] {
                let clear = (b.north_m - end[0]).abs() > b.half_north_m + 5.0
                    || (b.east_m - end[1]).abs() > b.half_east_m + 5.0;
                assert!(clear, "seed {seed}: a building covers {end:?}");
            }
        }
        let mut truth = Session::new(true_world(&World::fcnd_city(), &hidden).expect("world"));
        let grid = truth.grid(5.0, 5.0, 1.0).expect("grid");
        let cell = |p: [f64; 2]| grid.cell_at_ne(p[0], p[1]).expect("on the map");
        let exact = dijkstra_exact(
            &grid,
            cell([0.0, 0.0]),
            cell(FCND_DEFAULT_GOAL_NE),
            MoveModel::Octile,
        );
        assert!(exact.is_some(), "seed {seed}: the goal is walled off");
        // The same seed, the same buildings; another seed, others.
        assert_eq!(place_hidden(&map, &spec).expect("room"), hidden);
        let other = place_hidden(
            &map,
            &HiddenSpec {
                seed: seed + 100,
                ..spec.clone()
            },
        )
        .expect("room");
        assert_ne!(other, hidden);
    }
}

#[test]
fn bad_specs_are_refused_with_the_field_named() {
    let map = parse_colliders(FCND_CITY_CSV).expect("the bundled map parses");
    let spec = city_hidden_spec(vec![[0.0, 0.0]], 1, 1);
    let err = place_hidden(&map, &spec).expect_err("one point is no route");
    assert!(matches!(err, HiddenError::BadSpec(_)));
    assert!(err.to_string().contains("at least two points"), "{err}");
    let err = place_hidden(
        &map,
        &HiddenSpec {
            route_ne: vec![[0.0, 0.0], [1.0, 1.0]],
            cell_m: 0.0,
            ..spec
        },
    )
    .expect_err("cell 0");
    assert!(err.to_string().contains("cell_m 0"), "{err}");
}
