//! The FCND city map: fixed, seeded queries that every planner must solve, each path re-checked
//! against every box; the optimising planner must not be worse than the first-solution one.

use skyplan_sampling::{Budget, PlannerKind, Request, Status, plan};
use skyplan_world3::{BoxWorld3, CollisionChecker, Neu, distance_m, first_blocked_segment};

fn city() -> BoxWorld3 {
    skyplan_testkit::city_world(5.0, 100.0)
}

/// Free points ≥ 300 m apart, start at 5 m and goal at 40 m, from a fixed low-discrepancy walk.
fn queries(world: &BoxWorld3, n: usize) -> Vec<(Neu, Neu)> {
    let b = world.bounds();
    let mut x = [0.3f64, 0.6];
    let mut next = |alt: f64| -> Neu {
        x[0] = (x[0] + 0.618_034).fract();
        x[1] = (x[1] + 0.754_877_7).fract();
        [
            b.min[0] + x[0] * (b.max[0] - b.min[0]),
            b.min[1] + x[1] * (b.max[1] - b.min[1]),
            alt,
        ]
    };
    let mut out = Vec::new();
    while out.len() < n {
        let (s, g) = (next(5.0), next(40.0));
        if world.is_free(s) && world.is_free(g) && distance_m(s, g) >= 300.0 {
            out.push((s, g));
        }
    }
    out
}

#[test]
fn every_planner_solves_every_city_query_with_exactly_free_paths() {
    let world = city();
    let bf = world.brute_force();
    for (i, (start, goal)) in queries(&world, 12).into_iter().enumerate() {
        let mut costs = Vec::new();
        for kind in [
            PlannerKind::Prm,
            PlannerKind::RrtConnect,
            PlannerKind::RrtStar,
        ] {
            let request = Request {
                start,
                goal,
                seed: i as u64,
                budget: Budget::iterations(4000),
                ..Request::default()
            };
            let s = plan(&world, kind, &request);
            assert_eq!(s.status, Status::Exact, "query {i} {kind:?}");
            assert_eq!(s.path.first(), Some(&start));
            assert_eq!(s.path.last(), Some(&goal));
            assert_eq!(
                first_blocked_segment(&bf, &s.path),
                None,
                "query {i} {kind:?}"
            );
            costs.push(s.cost_m);
        }
        assert!(
            costs[2] <= costs[1] * 1.25,
            "query {i}: RRT* {} vs RRT-Connect {}",
            costs[2],
            costs[1]
        );
    }
}
