//! Gradient navigation through targets, with a change of target mid-ride.

use skyplan_cspace::{Cell, Grid2};
use skyplan_navfn::{
    Costmap, Inflation, MoveModel, NavError, NavRequest, TargetChange, cost_search, navigate,
};

fn corridor_map() -> Grid2 {
    // Row 0 first (south); a wall with one gap at column 5.
    Grid2::from_ascii(
        "...........\n\
         ...........\n\
         .....#.....\n\
         #####.#####\n\
         ...........\n\
         ...........",
    )
    .unwrap()
    .clone()
}

#[test]
fn rides_through_targets_and_replans_on_change() {
    let grid = Grid2::from_ascii(
        "...........\n\
         ...........\n\
         ...........\n\
         ....###....\n\
         ...........\n\
         ...........",
    )
    .unwrap();
    let params = Inflation {
        inscribed_radius_m: 0.0,
        inflation_radius_m: 2.0,
        cost_scaling_factor: 1.0,
    };
    let costmap = Costmap::inflate(&grid, params).unwrap();
    let request = NavRequest {
        source: Cell::new(0, 0),
        targets: vec![Cell::new(5, 10), Cell::new(0, 10)],
        changes: vec![TargetChange {
            at_step: 4,
            target: Cell::new(5, 0),
        }],
        model: MoveModel::Octile,
        weight: 1.0,
    };
    let run = navigate(&costmap, &request).unwrap();
    assert!(run.reached, "{run:?}");
    assert_eq!(run.failure, None);
    assert_eq!(run.legs.len(), 3);
    assert!(run.legs[0].replaced && !run.legs[0].reached);
    assert_eq!(run.legs[0].to_step, 4);
    assert_eq!(run.legs[1].target, Cell::new(5, 0));
    assert!(run.legs[1].reached && run.legs[2].reached);
    assert_eq!(run.trace.last(), Some(&Cell::new(0, 10)));
    assert_eq!(run.steps as usize, run.trace.len() - 1);
    // Every step is one move, and no cell repeats within a leg (strict descent).
    for leg in &run.legs {
        let cells = &run.trace[leg.from_step as usize..=leg.to_step as usize];
        let mut seen = std::collections::HashSet::new();
        assert!(
            cells.iter().all(|c| seen.insert(*c)),
            "a leg revisits a cell"
        );
    }
    // The last two legs are optimal: the same objective as A* from where each began.
    let leg = &run.legs[2];
    let from = run.trace[leg.from_step as usize];
    let astar = cost_search(&costmap, from, leg.target, MoveModel::Octile, 1.0, true).unwrap();
    assert_eq!(
        (leg.to_step - leg.from_step) as usize,
        astar.cells.len() - 1
    );
    // The obstacle row keeps the vehicle at least one cell away.
    assert!(run.min_clearance_cells >= 1.0);
}

#[test]
fn unreachable_target_stops_the_ride() {
    let grid = corridor_map();
    let mut blocked = grid.blocked_cells().to_vec();
    blocked[3 * 11 + 5] = true; // close the gap
    let grid = Grid2::new(6, 11, blocked, grid.frame()).unwrap();
    let costmap = Costmap::inflate(&grid, Inflation::default()).unwrap();
    let request = NavRequest {
        source: Cell::new(0, 0),
        targets: vec![Cell::new(1, 3), Cell::new(5, 5)],
        changes: vec![],
        model: MoveModel::Octile,
        weight: 0.0,
    };
    let run = navigate(&costmap, &request).unwrap();
    assert!(!run.reached);
    assert!(run.legs[0].reached);
    assert_eq!(
        run.failure,
        Some(NavError::Unreachable {
            source_cell: Cell::new(1, 3),
            destination_cell: Cell::new(5, 5)
        })
    );
    // A target on an obstacle is refused before the ride.
    let bad = NavRequest {
        targets: vec![Cell::new(3, 0)],
        ..request
    };
    assert!(matches!(
        navigate(&costmap, &bad),
        Err(NavError::AtObstacle { .. })
    ));
}
