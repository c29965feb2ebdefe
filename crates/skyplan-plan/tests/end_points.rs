//! Ends of a route on the city's cell corners, where free cells meet blocked ones: a plan from
//! or to any of them either succeeds (its final re-check passed) or says the end is invalid —
//! never an internal error. (A start on the corner of a blocked cell, N 400 E −169 at 5 m, used
//! to fail the re-check: "internal check failed: segment 0 … meets an obstacle".)

use skyplan_plan::{FailureKind, PlanRequest, PlannerId, Session, World};

#[test]
fn ends_on_cell_corners_are_planned_or_refused_never_internal() {
    let mut session = Session::new(World::fcnd_city());
    let corner = PlanRequest {
        start_ne: Some([400.0, -169.0]),
        goal_ne: Some([420.0, 390.0]),
        ..PlanRequest::default()
    };
    let refused = session
        .plan(&corner)
        .expect_err("on a blocked cell's corner");
    assert_eq!(
        refused.kind,
        FailureKind::InvalidStart,
        "{}",
        refused.message
    );
    assert!(
        refused.message.contains("on the edge of a blocked cell"),
        "{}",
        refused.message
    );
    // Every whole-metre point of a strip across buildings and streets, as a start and as a
    // goal, with grid and any-angle planners.
    let (mut planned, mut invalid) = (0, 0);
    for planner in [PlannerId::Jps, PlannerId::Astar, PlannerId::Theta] {
        for k in 0..60 {
            let p = [
                380.0 + f64::from(k % 12) * 4.0,
                -190.0 + f64::from(k / 12) * 11.0,
            ];
            for (start, goal) in [(p, [420.0, 390.0]), ([0.0, 0.0], p)] {
                let r = PlanRequest {
                    planner: Some(planner),
                    start_ne: Some(start),
                    goal_ne: Some(goal),
                    ..PlanRequest::default()
                };
                match session.plan(&r) {
                    Ok(_) => planned += 1,
                    Err(f) => {
                        assert!(
                            matches!(f.kind, FailureKind::InvalidStart | FailureKind::InvalidGoal),
                            "{planner} {start:?} → {goal:?}: {:?} {}",
                            f.kind,
                            f.message
                        );
                        invalid += 1;
                    }
                }
            }
        }
    }
    assert!(
        planned > 50 && invalid > 20,
        "{planned} planned, {invalid} refused"
    );
}
