//! Post-processing on optimal paths of random grids: every output segment is re-checked with
//! the independent floating-point segment test, lengths never grow, endpoints are kept.

use proptest::prelude::*;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_postprocess::{
    polyline_length_cells, prune_collinear, prune_collinear_eps, shortcut, touch_for,
};
use skyplan_search::{GridSearch, MoveModel, Planner};

fn query() -> impl Strategy<Value = (Grid2, Cell, Cell)> {
    (2u32..30, 2u32..30, 0.0f64..0.4).prop_flat_map(|(rows, cols, density)| {
        (
            proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize),
            0..rows,
            0..cols,
            0..rows,
            0..cols,
        )
            .prop_map(move |(mut blocked, a, b, c, d)| {
                // Start and goal in free cells joined by a free L-shaped corridor (along the
                // start's row, then the goal's column), so that every case has a path.
                for col in b.min(d)..=b.max(d) {
                    blocked[(a * cols + col) as usize] = false;
                }
                for row in a.min(c)..=a.max(c) {
                    blocked[(row * cols + d) as usize] = false;
                }
                let frame = GridFrame {
                    origin_north_m: 10.0,
                    origin_east_m: -4.0,
                    cell_m: 1.5,
                };
                (
                    Grid2::new(rows, cols, blocked, frame).unwrap(),
                    Cell::new(a, b),
                    Cell::new(c, d),
                )
            })
    })
}

fn all_segments_free(grid: &Grid2, cells: &[Cell], model: MoveModel) -> bool {
    cells.windows(2).all(|w| {
        grid.segment_is_free_ne(grid.center_ne(w[0]), grid.center_ne(w[1]), touch_for(model))
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn passes_keep_paths_valid_and_never_longer((grid, start, goal) in query(), eps in 0.0f64..3.0) {
        let mut search = GridSearch::new();
        for model in [MoveModel::FourConnected, MoveModel::Octile, MoveModel::OctileCornerCutting] {
            let path = search
                .search(&grid, start, goal, model, Planner::AStar)
                .map_err(|e| TestCaseError::fail(format!("the corridor connects start and goal: {e}")))?;
            let raw_len = polyline_length_cells(&path.cells);
            prop_assert!((raw_len - path.cost_cells()).abs() < 1e-9);
            let pruned = prune_collinear(&path.cells);
            prop_assert!((polyline_length_cells(&pruned) - raw_len).abs() < 1e-9, "exact pruning keeps the length");
            prop_assert!(all_segments_free(&grid, &pruned, model));
            let short = shortcut(&grid, &pruned, touch_for(model));
            let fcnd = prune_collinear_eps(&grid, &path.cells, eps, touch_for(model));
            for out in [&pruned, &short, &fcnd] {
                prop_assert_eq!(out.first(), Some(&start));
                prop_assert_eq!(out.last(), Some(&goal));
                prop_assert!(all_segments_free(&grid, out, model), "{model:?}: {out:?}");
                prop_assert!(polyline_length_cells(out) <= raw_len + 1e-9);
            }
            prop_assert!(short.len() <= pruned.len());
        }
    }
}
