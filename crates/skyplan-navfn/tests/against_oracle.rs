//! Distance fields, gradient descent and cost-map search against independent truth: the exact
//! Dijkstra oracle of skyplan-search and a brute-force Bellman–Ford written here.

use proptest::prelude::*;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_navfn::{
    Costmap, FieldMetric, Inflation, MoveModel, NavError, cost_search, cost_to_go, distance_field,
};
use skyplan_search::check_path;
use skyplan_search::oracle::dijkstra_exact;

const MODELS: [MoveModel; 3] = [
    MoveModel::FourConnected,
    MoveModel::Octile,
    MoveModel::OctileCornerCutting,
];

fn query_strategy() -> impl Strategy<Value = (Grid2, Cell, Cell)> {
    (1u32..22, 1u32..22, 0.0f64..0.45)
        .prop_flat_map(|(rows, cols, density)| {
            proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize)
                .prop_map(move |b| Grid2::new(rows, cols, b, GridFrame::default()).unwrap())
        })
        .prop_flat_map(|g| {
            let (r, c) = (g.rows(), g.cols());
            (Just(g), 0..r, 0..c, 0..r, 0..c)
                .prop_map(|(g, a, b, x, y)| (g, Cell::new(a, b), Cell::new(x, y)))
        })
}

/// Moves of `model` from `cell`, written again here (independent of the crate).
fn moves(grid: &Grid2, cell: Cell, model: MoveModel) -> Vec<(Cell, f64)> {
    let mut out = Vec::new();
    for dr in -1i64..=1 {
        for dc in -1i64..=1 {
            let diagonal = dr != 0 && dc != 0;
            if (dr, dc) == (0, 0) || (diagonal && model == MoveModel::FourConnected) {
                continue;
            }
            let (r, c) = (i64::from(cell.row) + dr, i64::from(cell.col) + dc);
            if !grid.is_free_at(r, c) {
                continue;
            }
            if diagonal
                && model == MoveModel::Octile
                && !(grid.is_free_at(r, i64::from(cell.col))
                    && grid.is_free_at(i64::from(cell.row), c))
            {
                continue;
            }
            out.push((
                Cell::new(r as u32, c as u32),
                if diagonal { 2f64.sqrt() } else { 1.0 },
            ));
        }
    }
    out
}

/// Bellman–Ford on the cost map's objective: the least length · (1 + w·cost/252) sum.
fn bellman_ford(
    costmap: &Costmap,
    source: Cell,
    goal: Cell,
    model: MoveModel,
    w: f64,
) -> Option<f64> {
    let grid = costmap.passable_grid();
    if grid.is_blocked(source) || grid.is_blocked(goal) {
        return None;
    }
    let mut d = vec![f64::INFINITY; grid.len()];
    d[grid.index(source)] = 0.0;
    for _ in 0..grid.len() {
        let mut changed = false;
        for i in 0..grid.len() {
            if d[i].is_infinite() {
                continue;
            }
            for (next, len) in moves(&grid, grid.cell(i), model) {
                let c = f64::from(costmap.cost(next).unwrap());
                let cand = d[i] + len * (1.0 + w * c / 252.0);
                let j = grid.index(next);
                if cand < d[j] - 1e-12 {
                    d[j] = cand;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    let v = d[grid.index(goal)];
    v.is_finite().then_some(v)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    #[test]
    fn descent_is_optimal_valid_and_terminates((grid, source, goal) in query_strategy()) {
        for model in MODELS {
            let truth = dijkstra_exact(&grid, source, goal, model);
            let field = match distance_field(&grid, goal, model, FieldMetric::Length) {
                Ok(f) => f,
                Err(e) => {
                    prop_assert!(grid.is_blocked(goal), "{}", e);
                    let at_obstacle = matches!(e, NavError::AtObstacle { .. });
                    prop_assert!(at_obstacle);
                    continue;
                }
            };
            match (field.descend(source), truth) {
                (Ok(path), Some(cost)) => {
                    prop_assert_eq!((path.straight_moves, path.diagonal_moves), (cost.straight, cost.diagonal));
                    prop_assert_eq!(path.length_cells(), cost.to_f64());
                    prop_assert!((field.value(source).unwrap() - cost.to_f64()).abs() < 1e-9);
                    prop_assert_eq!(path.cells.first(), Some(&source));
                    prop_assert_eq!(path.cells.last(), Some(&goal));
                    prop_assert_eq!(check_path(&grid, &path.cells, model), Ok(()));
                }
                (Err(e), None) => {
                    let ok = grid.is_blocked(source) || matches!(e, NavError::Unreachable { .. });
                    prop_assert!(ok, "{}", e);
                }
                (got, want) => prop_assert!(false, "{model:?}: descent {got:?}, oracle {want:?}"),
            }
            // The BFS wavefront: reaches the goal whenever the oracle does, with as many moves as
            // its value at the source.
            let steps = distance_field(&grid, goal, model, FieldMetric::Steps).unwrap();
            if let (Some(_), Ok(path)) = (truth, steps.descend(source)) {
                prop_assert_eq!((path.cells.len() - 1) as f64, steps.value(source).unwrap());
                prop_assert_eq!(check_path(&grid, &path.cells, model), Ok(()));
                if model == MoveModel::FourConnected {
                    prop_assert_eq!(path.length_cells(), truth.unwrap().to_f64());
                }
            } else {
                prop_assert!(truth.is_none());
            }
        }
    }

    #[test]
    fn cost_search_and_cost_to_go_agree_with_bellman_ford(
        (grid, source, goal) in query_strategy(),
        weight in 0.0f64..20.0,
        inscribed in 0.0f64..1.2,
    ) {
        let params = Inflation { inscribed_radius_m: inscribed, inflation_radius_m: 3.0, cost_scaling_factor: 1.0 };
        let costmap = Costmap::inflate(&grid, params).unwrap();
        for model in MODELS {
            let truth = bellman_ford(&costmap, source, goal, model, weight);
            let astar = cost_search(&costmap, source, goal, model, weight, true);
            let dijkstra = cost_search(&costmap, source, goal, model, weight, false);
            let field = cost_to_go(&costmap, goal, model, weight);
            match truth {
                Some(best) => {
                    let (a, d, f) = (astar.unwrap(), dijkstra.unwrap(), field.unwrap());
                    prop_assert!((a.objective_cells - best).abs() < 1e-9, "A* {} vs {best}", a.objective_cells);
                    prop_assert!((d.objective_cells - best).abs() < 1e-9);
                    prop_assert!((f.value(source).unwrap() - best).abs() < 1e-9);
                    let ride = f.descend(source).unwrap();
                    prop_assert!((ride.objective_cells - best).abs() < 1e-9);
                    prop_assert_eq!(check_path(&costmap.passable_grid(), &ride.cells, model), Ok(()));
                    prop_assert_eq!(check_path(&costmap.passable_grid(), &a.cells, model), Ok(()));
                    if weight == 0.0 {
                        let exact = dijkstra_exact(&costmap.passable_grid(), source, goal, model).unwrap();
                        prop_assert_eq!(a.length_cells(), exact.to_f64());
                    }
                }
                None => {
                    prop_assert!(astar.is_err() && dijkstra.is_err());
                    if let Ok(f) = field {
                        prop_assert!(f.descend(source).is_err());
                    }
                }
            }
        }
    }
}
