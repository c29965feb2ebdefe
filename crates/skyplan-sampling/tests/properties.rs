//! Property tests on random box worlds: every returned path is exactly free (by the brute-force
//! checker, which tests every box), starts and ends as asked, costs are path lengths, statuses are
//! right for invalid and enclosed goals, runs are reproducible, shortcutting never lengthens.

use proptest::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use skyplan_map::colliders::ObstacleBox;
use skyplan_sampling::{Budget, PlannerKind, Request, Solution, Status, plan, shortcut};
use skyplan_world3::{
    BoxWorld3, CollisionChecker, Neu, WorldSpec, first_blocked_segment, path_length_m,
};

const KINDS: [PlannerKind; 3] = [
    PlannerKind::Prm,
    PlannerKind::RrtConnect,
    PlannerKind::RrtStar,
];

fn arb_box() -> impl Strategy<Value = ObstacleBox> {
    (
        0.0..100.0,
        0.0..100.0,
        0.0..25.0,
        1.0..12.0,
        1.0..12.0,
        1.0..25.0,
    )
        .prop_map(|(n, e, u, hn, he, hu)| ObstacleBox {
            north_m: n,
            east_m: e,
            up_m: u,
            half_north_m: hn,
            half_east_m: he,
            half_up_m: hu,
        })
}

fn arb_point() -> impl Strategy<Value = Neu> {
    (0.0..100.0f64, 0.0..100.0f64, 0.0..45.0f64).prop_map(|(n, e, a)| [n, e, a])
}

fn world(boxes: &[ObstacleBox], safety_m: f64) -> BoxWorld3 {
    let spec = WorldSpec {
        safety_m,
        min_alt_m: 0.0,
        max_alt_m: 45.0,
        margin_bounds_m: 15.0,
    };
    BoxWorld3::new(boxes, &spec).expect("valid spec")
}

/// The checks every solution must pass, whatever its status.
fn check_solution(w: &BoxWorld3, request: &Request, s: &Solution) -> Result<(), TestCaseError> {
    let bf = w.brute_force();
    match s.status {
        Status::InvalidStart => prop_assert!(!bf.is_free(request.start)),
        Status::InvalidGoal => {
            prop_assert!(bf.is_free(request.start));
            prop_assert!(!bf.is_free(request.goal));
        }
        Status::Timeout => prop_assert!(s.path.is_empty()),
        Status::Exact | Status::Approximate => {
            prop_assert_eq!(s.path.first(), Some(&request.start));
            prop_assert_eq!(
                first_blocked_segment(&bf, &s.path),
                None,
                "path {:?}",
                s.path
            );
            prop_assert!((s.cost_m - path_length_m(&s.path)).abs() <= 1e-9 * (1.0 + s.cost_m));
            if s.status == Status::Exact {
                prop_assert_eq!(s.path.last(), Some(&request.goal));
                prop_assert!(
                    s.cost_m + 1e-9 >= skyplan_world3::distance_m(request.start, request.goal)
                );
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn paths_are_exactly_free_and_end_where_asked(
        boxes in prop::collection::vec(arb_box(), 1..14),
        safety_m in 0.0..3.0f64,
        start in arb_point(),
        goal in arb_point(),
        seed in 0u64..1000,
    ) {
        let w = world(&boxes, safety_m);
        for kind in KINDS {
            let request = Request { start, goal, seed, budget: Budget::iterations(1500), ..Request::default() };
            let s = plan(&w, kind, &request);
            check_solution(&w, &request, &s)?;
            // The straight line free ⇒ every planner finds an exact path.
            if w.brute_force().segment_is_free(start, goal) {
                prop_assert_eq!(s.status, Status::Exact, "{:?}", kind);
            }
            // Reproducible with the same seed.
            prop_assert_eq!(&plan(&w, kind, &request).path, &s.path);
        }
    }

    #[test]
    fn enclosed_goal_is_never_reached(
        boxes in prop::collection::vec(arb_box(), 0..6),
        start in arb_point(),
        seed in 0u64..1000,
    ) {
        // A closed hollow cube (six 1 m slabs, no margin) around the goal at (70, 70, 20).
        let c: Neu = [70.0, 70.0, 20.0];
        // A start inside the cage could of course reach the goal.
        prop_assume!((0..3).any(|i| (start[i] - c[i]).abs() > 9.0));
        let slab = |dn: f64, de: f64, du: f64, hn: f64, he: f64, hu: f64| ObstacleBox {
            north_m: c[0] + dn, east_m: c[1] + de, up_m: c[2] + du,
            half_north_m: hn, half_east_m: he, half_up_m: hu,
        };
        let mut all: Vec<ObstacleBox> = boxes
            .into_iter()
            .filter(|b| (b.north_m - c[0]).abs() > b.half_north_m + 12.0 || (b.east_m - c[1]).abs() > b.half_east_m + 12.0)
            .collect();
        all.extend([
            slab(-8.0, 0.0, 0.0, 1.0, 9.0, 9.0), slab(8.0, 0.0, 0.0, 1.0, 9.0, 9.0),
            slab(0.0, -8.0, 0.0, 9.0, 1.0, 9.0), slab(0.0, 8.0, 0.0, 9.0, 1.0, 9.0),
            slab(0.0, 0.0, -8.0, 9.0, 9.0, 1.0), slab(0.0, 0.0, 8.0, 9.0, 9.0, 1.0),
        ]);
        let w = world(&all, 0.0);
        prop_assert!(w.is_free(c));
        for kind in KINDS {
            let request = Request { start, goal: c, seed, budget: Budget::iterations(800), ..Request::default() };
            let s = plan(&w, kind, &request);
            check_solution(&w, &request, &s)?;
            prop_assert_ne!(s.status, Status::Exact, "{:?} reached an enclosed goal", kind);
            if w.is_free(start) {
                prop_assert!(matches!(s.status, Status::Timeout | Status::Approximate));
            }
        }
    }

    #[test]
    fn simplify_never_lengthens_and_stays_free(
        boxes in prop::collection::vec(arb_box(), 1..10),
        start in arb_point(),
        goal in arb_point(),
        seed in 0u64..1000,
    ) {
        let w = world(&boxes, 1.0);
        let request = Request { start, goal, seed, simplify: false, budget: Budget::iterations(1500), ..Request::default() };
        let s = plan(&w, PlannerKind::RrtConnect, &request);
        if s.status == Status::Exact {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let out = shortcut::simplify(&w, &s.path, &mut rng, 100);
            prop_assert_eq!(out.first(), s.path.first());
            prop_assert_eq!(out.last(), s.path.last());
            prop_assert!(path_length_m(&out) <= path_length_m(&s.path));
            prop_assert_eq!(first_blocked_segment(&w.brute_force(), &out), None);
        }
    }
}

#[test]
fn invalid_start_and_goal_are_reported() {
    let tower = ObstacleBox {
        north_m: 50.0,
        east_m: 50.0,
        up_m: 20.0,
        half_north_m: 10.0,
        half_east_m: 10.0,
        half_up_m: 20.0,
    };
    let w = world(&[tower], 2.0);
    for kind in KINDS {
        let inside = [50.0, 50.0, 10.0];
        let free = [30.0, 30.0, 10.0];
        let below = [30.0, 30.0, -1.0];
        let r = |start, goal| Request {
            start,
            goal,
            budget: Budget::iterations(100),
            ..Request::default()
        };
        assert_eq!(
            plan(&w, kind, &r(inside, free)).status,
            Status::InvalidStart
        );
        assert_eq!(plan(&w, kind, &r(free, inside)).status, Status::InvalidGoal);
        assert_eq!(plan(&w, kind, &r(free, below)).status, Status::InvalidGoal);
    }
}
