//! Every exact grid planner of the registry against the exact Dijkstra oracle on random grids,
//! start and goal drawn among free cells (no case is skipped).

use proptest::prelude::*;
use skyplan_cspace::{Cell, Grid2};
use skyplan_plan::{FailureKind, MapKinds, Optimality, PlanRequest, PlannerId, Session, World};
use skyplan_search::{MoveModel, oracle::dijkstra_exact};

/// The registry's exact planners (`Optimality::Exact`: shortest among grid paths under the move
/// model) that run on grids: a new one is checked here without an edit.
fn exact_grid_planners() -> Vec<PlannerId> {
    (PlannerId::ALL.iter().copied())
        .filter(|p| p.info().optimality == Optimality::Exact)
        .filter(|p| p.is_cell_planner() || p.info().maps != MapKinds::Obstacles)
        .collect()
}

#[test]
fn every_exact_planner_is_a_grid_planner_taking_the_move_model() {
    // The oracle's truth is the shortest grid path under the move model: an exact planner that
    // did not take the move model, or no grid, would have nothing here to be checked against.
    let exact = exact_grid_planners();
    assert!(!exact.is_empty());
    for p in exact {
        assert!(p.is_cell_planner(), "{p} is exact but takes no move model");
    }
}

fn grid_and_ends() -> impl Strategy<Value = (Grid2, Cell, Cell)> {
    skyplan_testkit::arb_grid_and_ends(14)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(if std::env::var_os("CI").is_some() { 600 } else { 200 }))]
    #[test]
    fn exact_planners_equal_the_oracle((grid, start, goal) in grid_and_ends(), model_ix in 0usize..3) {
        let (model, connectivity, corner_cutting) = [
            (MoveModel::Octile, 8, false),
            (MoveModel::OctileCornerCutting, 8, true),
            (MoveModel::FourConnected, 4, false),
        ][model_ix];
        let truth = dijkstra_exact(&grid, start, goal, model);
        let mut session = Session::new(World::from_grid("random", grid.clone()));
        let (sn, se) = grid.center_ne(start);
        let (gn, ge) = grid.center_ne(goal);
        for planner in exact_grid_planners() {
            let r = session.plan(&PlanRequest {
                planner: Some(planner),
                start_ne: Some([sn, se]),
                goal_ne: Some([gn, ge]),
                connectivity: Some(connectivity),
                corner_cutting: Some(corner_cutting),
                ..Default::default()
            });
            match (truth, r) {
                (Some(t), Ok(plan)) => prop_assert!((plan.cost_m - t.to_f64()).abs() < 1e-9, "{planner}: {} vs {}", plan.cost_m, t.to_f64()),
                (None, Err(e)) => prop_assert_eq!(e.kind, FailureKind::NoPath, "{}: {}", planner, e),
                (t, r) => prop_assert!(false, "{planner}: oracle {t:?}, plan {:?}", r.map(|p| p.cost_m)),
            }
        }
    }
}
