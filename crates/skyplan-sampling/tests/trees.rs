//! `plan_with_tree` returns the same solution as `plan`, plus what the planner grew: every tree
//! edge (RRT-Connect's two trees, RRT*'s one) or roadmap edge is exactly free, and a tree has one
//! edge per vertex but its root.

use skyplan_map::colliders::ObstacleBox;
use skyplan_sampling::{Budget, PlannerKind, Request, Status, plan, plan_with_tree};
use skyplan_world3::{BoxWorld3, CollisionChecker};

fn world() -> BoxWorld3 {
    let wall = ObstacleBox::from_row([50.0, 50.0, 20.0, 5.0, 40.0, 20.0]);
    skyplan_testkit::box_world(&[wall], 2.0, 50.0, 40.0)
}

#[test]
fn trees_are_returned_free_and_the_solution_is_unchanged() {
    let world = world();
    let exact = world.brute_force();
    let request = Request {
        start: [20.0, 50.0, 10.0],
        goal: [80.0, 50.0, 10.0],
        seed: 5,
        budget: Budget::iterations(3000),
        ..Request::default()
    };
    for kind in [
        PlannerKind::RrtConnect,
        PlannerKind::RrtStar,
        PlannerKind::Prm,
    ] {
        let plain = plan(&world, kind, &request);
        let (solution, edges) = plan_with_tree(&world, kind, &request);
        assert_eq!(solution.status, Status::Exact, "{kind:?}");
        assert_eq!(solution.path, plain.path, "{kind:?}: same run");
        assert!(!edges.is_empty(), "{kind:?}");
        for &(a, b) in &edges {
            assert!(exact.segment_is_free(a, b), "{kind:?}: {a:?} – {b:?}");
        }
        match kind {
            // Two roots (start and goal).
            PlannerKind::RrtConnect => assert_eq!(edges.len() + 2, solution.vertices),
            PlannerKind::RrtStar => assert_eq!(edges.len() + 1, solution.vertices),
            _ => {}
        }
    }
}
