//! Every planner against the exact Dijkstra oracle on random grids, for every move model.

use proptest::prelude::*;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_search::oracle::{OctileCost, dijkstra_exact};
use skyplan_search::{
    ChQuery, Components, ContractionHierarchy, GridPath, GridSearch, JpsPlus, MoveModel, Planner,
    SearchError, check_path,
};

const MODELS: [MoveModel; 3] = [
    MoveModel::FourConnected,
    MoveModel::Octile,
    MoveModel::OctileCornerCutting,
];

fn grid_strategy() -> impl Strategy<Value = Grid2> {
    (1u32..26, 1u32..26, 0.0f64..0.45).prop_flat_map(|(rows, cols, density)| {
        proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize)
            .prop_map(move |blocked| Grid2::new(rows, cols, blocked, GridFrame::default()).unwrap())
    })
}

fn query_strategy() -> impl Strategy<Value = (Grid2, Cell, Cell)> {
    grid_strategy().prop_flat_map(|g| {
        let (r, c) = (g.rows(), g.cols());
        (Just(g), 0..r, 0..c, 0..r, 0..c)
            .prop_map(|(g, a, b, x, y)| (g, Cell::new(a, b), Cell::new(x, y)))
    })
}

/// A planner's answer against the oracle's: the oracle's move counts, a valid path between the
/// ends; or, where the oracle finds none, an error that says why (a blocked end, unreachable).
fn agrees_with_oracle(
    grid: &Grid2,
    (start, goal): (Cell, Cell),
    model: MoveModel,
    planner: &str,
    found: Result<GridPath, SearchError>,
    truth: Option<OctileCost>,
) -> Result<(), TestCaseError> {
    match (found, truth) {
        (Ok(path), Some(cost)) => {
            prop_assert_eq!(
                (path.straight_moves, path.diagonal_moves),
                (cost.straight, cost.diagonal)
            );
            prop_assert_eq!(path.cells.first(), Some(&start));
            prop_assert_eq!(path.cells.last(), Some(&goal));
            prop_assert_eq!(check_path(grid, &path.cells, model), Ok(()));
        }
        (Err(e), None) => {
            let expected = grid.is_blocked(start)
                || grid.is_blocked(goal)
                || matches!(e, SearchError::Unreachable { .. });
            prop_assert!(expected, "unexpected error {e:?}");
        }
        (got, want) => prop_assert!(false, "{model:?} {planner}: got {got:?}, oracle {want:?}"),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn planners_are_optimal_valid_and_agree_on_reachability((grid, start, goal) in query_strategy()) {
        let mut search = GridSearch::new();
        for model in MODELS {
            let truth = dijkstra_exact(&grid, start, goal, model);
            let components = Components::new(&grid, model);
            prop_assert_eq!(components.connected(start, goal), truth.is_some());
            for planner in [Planner::AStar, Planner::Dijkstra, Planner::Jps, Planner::JpsPlus] {
                let found = search.search(&grid, start, goal, model, planner);
                if let (Ok(path), Some(cost)) = (&found, &truth) {
                    prop_assert_eq!(path.cost_cells(), cost.to_f64());
                }
                agrees_with_oracle(&grid, (start, goal), model, &format!("{planner:?}"), found, truth)?;
            }
        }
    }

    /// JPS+ replaces every scan of JPS by a table lookup: same paths, same expansions.
    #[test]
    fn jps_plus_returns_exactly_what_jps_returns((grid, start, goal) in query_strategy()) {
        let mut search = GridSearch::new();
        for model in [MoveModel::Octile, MoveModel::OctileCornerCutting] {
            let mut plus = JpsPlus::new(&grid, model);
            let online = search.search(&grid, start, goal, model, Planner::Jps);
            prop_assert_eq!(plus.search(start, goal), online, "{:?}", model);
            // And again on the same table (buffers are reused between queries).
            prop_assert_eq!(plus.search(goal, start), search.search(&grid, goal, start, model, Planner::Jps));
        }
    }
}

#[test]
fn endpoint_errors_say_which() {
    let grid = Grid2::from_ascii("..#\n...").unwrap();
    let mut s = GridSearch::new();
    let m = MoveModel::Octile;
    let p = Planner::AStar;
    assert!(matches!(
        s.search(&grid, Cell::new(5, 0), Cell::new(0, 0), m, p),
        Err(SearchError::StartOutside { .. })
    ));
    assert!(matches!(
        s.search(&grid, Cell::new(0, 0), Cell::new(0, 9), m, p),
        Err(SearchError::GoalOutside { .. })
    ));
    assert_eq!(
        s.search(&grid, Cell::new(0, 2), Cell::new(0, 0), m, p),
        Err(SearchError::StartBlocked(Cell::new(0, 2)))
    );
    assert_eq!(
        s.search(&grid, Cell::new(0, 0), Cell::new(0, 2), m, p),
        Err(SearchError::GoalBlocked(Cell::new(0, 2)))
    );
}

#[test]
fn corner_rule_changes_the_answer() {
    // The only way from bottom-left to top-right squeezes between two blocked corners.
    let grid = Grid2::from_ascii(".#\n#.").unwrap();
    let mut s = GridSearch::new();
    let (a, b) = (Cell::new(0, 0), Cell::new(1, 1));
    assert!(matches!(
        s.search(&grid, a, b, MoveModel::Octile, Planner::AStar),
        Err(SearchError::Unreachable { .. })
    ));
    let cut = s
        .search(&grid, a, b, MoveModel::OctileCornerCutting, Planner::AStar)
        .unwrap();
    assert_eq!(cut.diagonal_moves, 1);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    /// Theta*: reachability as the oracle, every segment in sight under the corner rule, and a
    /// length between the straight line and the octile optimum.
    #[test]
    fn theta_star_is_valid_and_between_the_bounds((grid, start, goal) in query_strategy()) {
        let mut search = GridSearch::new();
        for model in MODELS {
            let truth = dijkstra_exact(&grid, start, goal, model);
            match (search.theta_star(&grid, start, goal, model), truth) {
                (Ok(path), Some(octile)) => {
                    prop_assert_eq!(path.cells.first(), Some(&start));
                    prop_assert_eq!(path.cells.last(), Some(&goal));
                    for w in path.cells.windows(2) {
                        prop_assert!(grid.segment_is_free_ne(grid.center_ne(w[0]), grid.center_ne(w[1]), model.touch()));
                    }
                    let straight = (f64::from(start.row) - f64::from(goal.row)).hypot(f64::from(start.col) - f64::from(goal.col));
                    prop_assert!(path.cost_cells() >= straight - 1e-9);
                    prop_assert!(path.cost_cells() <= octile.to_f64() + 1e-9, "{} > {}", path.cost_cells(), octile.to_f64());
                }
                (Err(_), None) => {}
                (got, want) => prop_assert!(false, "{model:?}: got {got:?}, oracle {want:?}"),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    /// The contraction hierarchy: one preprocessing per grid and model, then queries both ways
    /// (buffers reused), each against the oracle's exact cost, a valid path and its ends.
    #[test]
    fn contraction_hierarchy_is_optimal_and_valid(
        (grid, start, goal) in query_strategy(),
        extra in proptest::collection::vec((0u32..26, 0u32..26, 0u32..26, 0u32..26), 0..4),
    ) {
        let grid = std::sync::Arc::new(grid);
        let mut queries = vec![(start, goal), (goal, start)];
        queries.extend(extra.iter().map(|&(a, b, c, d)| {
            (Cell::new(a % grid.rows(), b % grid.cols()), Cell::new(c % grid.rows(), d % grid.cols()))
        }));
        for model in MODELS {
            let ch = ContractionHierarchy::build(std::sync::Arc::clone(&grid), model).unwrap();
            let mut query = ChQuery::default();
            for &(start, goal) in &queries {
                let truth = dijkstra_exact(&grid, start, goal, model);
                let found = ch.search(&mut query, start, goal);
                agrees_with_oracle(&grid, (start, goal), model, "ch", found, truth)?;
            }
        }
    }
}
