//! The random box worlds of the sampling planners' property tests: boxes in a 100 m square up to
//! 50 m high, points up to 45 m, a flight volume from the ground to 45 m with 15 m around.
#![allow(dead_code)]

use proptest::prelude::*;
use skyplan_map::colliders::ObstacleBox;
use skyplan_sampling::{Request, Solution, Status};
use skyplan_world3::{BoxWorld3, CollisionChecker, Neu, first_blocked_segment, path_length_m};

pub fn arb_box() -> impl Strategy<Value = ObstacleBox> {
    skyplan_testkit::arb_box(0.0..25.0, 1.0..12.0, 1.0..25.0)
}

pub fn arb_point() -> impl Strategy<Value = Neu> {
    skyplan_testkit::arb_point(0.0..45.0)
}

pub fn world(boxes: &[ObstacleBox], safety_m: f64) -> BoxWorld3 {
    skyplan_testkit::box_world(boxes, safety_m, 45.0, 15.0)
}

/// Random boxes (as many as `n`), a start, a goal and a seed.
pub fn arb_case(
    n: std::ops::Range<usize>,
) -> impl Strategy<Value = (Vec<ObstacleBox>, Neu, Neu, u64)> {
    (
        prop::collection::vec(arb_box(), n),
        arb_point(),
        arb_point(),
        0u64..1000,
    )
}

/// The world of `boxes` (no margin) with a closed hollow cube of six 1 m slabs around the goal at
/// (70, 70, 20), and that goal; a start inside the cage (which could of course reach the goal) is
/// rejected.
pub fn caged_goal(boxes: Vec<ObstacleBox>, start: Neu) -> Result<(BoxWorld3, Neu), TestCaseError> {
    let c: Neu = [70.0, 70.0, 20.0];
    prop_assume!((0..3).any(|i| (start[i] - c[i]).abs() > 9.0));
    let w = world(&skyplan_testkit::caged(boxes, c), 0.0);
    prop_assert!(w.is_free(c));
    Ok((w, c))
}

/// The checks every solution must pass, whatever its status.
pub fn check_solution(w: &BoxWorld3, request: &Request, s: &Solution) -> Result<(), TestCaseError> {
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
