//! D* Lite against the exact oracle (`skyplan_search::oracle::dijkstra_exact`, an independent
//! Dijkstra from scratch) after every batch of random cell edits, with the start moving along
//! the current path (and repairs cut into small budgets half of the time); every path is
//! re-checked under the move model with `check_path`.

use proptest::prelude::*;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_replan::DStarLite;
use skyplan_search::oracle::dijkstra_exact;
use skyplan_search::{MoveModel, check_path};

fn grid_strategy() -> impl Strategy<Value = (u32, u32, Vec<bool>)> {
    (2u32..14, 2u32..14).prop_flat_map(|(rows, cols)| {
        let n = (rows * cols) as usize;
        (
            Just(rows),
            Just(cols),
            proptest::collection::vec(proptest::bool::weighted(0.3), n),
        )
    })
}

fn model_strategy() -> impl Strategy<Value = MoveModel> {
    prop_oneof![
        Just(MoveModel::Octile),
        Just(MoveModel::OctileCornerCutting),
        Just(MoveModel::FourConnected)
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    #[test]
    fn dstar_lite_matches_the_exact_oracle_after_every_batch(
        (rows, cols, blocked) in grid_strategy(),
        model in model_strategy(),
        ends in (0u32..1000, 0u32..1000, 0u32..1000, 0u32..1000),
        batches in proptest::collection::vec(
            proptest::collection::vec((0u32..1000, 0u32..1000, proptest::bool::weighted(0.6)), 1..8),
            1..6),
        steps in proptest::collection::vec(0usize..4, 6),
        budget in prop_oneof![Just(u64::MAX), 1u64..40],
    ) {
        let mut grid = Grid2::new(rows, cols, blocked, GridFrame::default()).expect("grid");
        let start = Cell::new(ends.0 % rows, ends.1 % cols);
        let goal = Cell::new(ends.2 % rows, ends.3 % cols);
        let mut d = DStarLite::new(&grid, start, goal, model).expect("inside");
        let mut at = start;
        let check = |d: &mut DStarLite, grid: &Grid2, at: Cell| -> Result<Option<Vec<Cell>>, TestCaseError> {
            let truth = dijkstra_exact(grid, at, goal, model);
            // With a small budget, repeated calls resume the same repair until it finishes.
            let found = loop {
                if let Ok(found) = d.compute_within(budget) {
                    break found;
                }
            };
            match (&truth, &found) {
                (None, None) => Ok(None),
                (Some(t), Some(p)) => {
                    prop_assert!((t.to_f64() - p.cost_cells()).abs() < 1e-9,
                        "oracle {} vs D* Lite {}", t.to_f64(), p.cost_cells());
                    prop_assert_eq!((t.straight, t.diagonal), (p.straight_moves, p.diagonal_moves));
                    prop_assert_eq!(p.cells.first(), Some(&at));
                    prop_assert_eq!(p.cells.last(), Some(&goal));
                    prop_assert_eq!(check_path(grid, &p.cells, model), Ok(()));
                    Ok(Some(p.cells.clone()))
                }
                _ => Err(TestCaseError::fail(format!("oracle {truth:?} but D* Lite {found:?}"))),
            }
        };
        let mut path = check(&mut d, &grid, at)?;
        for (k, batch) in batches.iter().enumerate() {
            // The vehicle moves a few cells along the current path first.
            if let Some(p) = &path {
                let s = steps[k % steps.len()].min(p.len() - 1);
                at = p[s];
                d.move_start(at);
            }
            let edits: Vec<(Cell, bool)> = batch
                .iter()
                .map(|&(r, c, b)| (Cell::new(r % rows, c % cols), b))
                .collect();
            for &(cell, b) in &edits {
                grid.set_blocked(cell, b);
            }
            d.update_cells(&edits);
            prop_assert_eq!(d.grid(), &grid);
            path = check(&mut d, &grid, at)?;
        }
    }
}
