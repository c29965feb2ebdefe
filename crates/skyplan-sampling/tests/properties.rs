//! Property tests on random box worlds: every returned path is exactly free (by the brute-force
//! checker, which tests every box), starts and ends as asked, costs are path lengths, statuses are
//! right for invalid and enclosed goals, runs are reproducible, shortcutting never lengthens.

use proptest::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use skyplan_map::colliders::ObstacleBox;
use skyplan_sampling::{Budget, PlannerKind, Request, Solution, Status, plan, shortcut};
use skyplan_world3::{CollisionChecker, first_blocked_segment, path_length_m};

const KINDS: [PlannerKind; 4] = [
    PlannerKind::Prm,
    PlannerKind::LazyPrm,
    PlannerKind::RrtConnect,
    PlannerKind::RrtStar,
];

mod common;
use common::{arb_box, arb_case, arb_point, caged_goal, check_solution, world};

/// Lazy PRM checks edges only on found paths, so it returns an exact path or none (never an
/// approximate one).
fn lazy_prm_is_exact_or_nothing(kind: PlannerKind, s: &Solution) -> Result<(), TestCaseError> {
    if kind == PlannerKind::LazyPrm {
        prop_assert_ne!(
            s.status,
            Status::Approximate,
            "lazy PRM is exact or nothing"
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn paths_are_exactly_free_and_end_where_asked(
        (boxes, start, goal, seed) in arb_case(1..14),
        safety_m in 0.0..3.0f64,
    ) {
        let w = world(&boxes, safety_m);
        for kind in KINDS {
            let request = Request { start, goal, seed, budget: Budget::iterations(1500), ..Request::default() };
            let s = plan(&w, kind, &request);
            check_solution(&w, &request, &s)?;
            lazy_prm_is_exact_or_nothing(kind, &s)?;
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
        let (w, c) = caged_goal(boxes, start)?;
        for kind in KINDS {
            let request = Request { start, goal: c, seed, budget: Budget::iterations(800), ..Request::default() };
            let s = plan(&w, kind, &request);
            check_solution(&w, &request, &s)?;
            lazy_prm_is_exact_or_nothing(kind, &s)?;
            prop_assert_ne!(s.status, Status::Exact, "{:?} reached an enclosed goal", kind);
            if w.is_free(start) {
                prop_assert!(matches!(s.status, Status::Timeout | Status::Approximate));
            }
        }
    }

    #[test]
    fn simplify_never_lengthens_and_stays_free(
        (boxes, start, goal, seed) in arb_case(1..10),
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
    let tower = ObstacleBox::from_row([50.0, 50.0, 20.0, 10.0, 10.0, 20.0]);
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
