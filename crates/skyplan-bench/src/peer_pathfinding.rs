//! The Rust `pathfinding` crate's A\* as a benchmark peer, with exact octile costs (its costs
//! must be `Ord`, so they are [`OctileCost`]s compared exactly) and hashed `(row, col)` nodes,
//! the way its users write it.

use pathfinding::num_traits::Zero;
use skyplan_cspace::{Cell, Grid2, NEIGHBOURS_8};
use skyplan_search::MoveModel;
use skyplan_search::oracle::OctileCost;
use std::ops::Add;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
struct Cost(OctileCost);

impl Add for Cost {
    type Output = Cost;
    fn add(self, o: Cost) -> Cost {
        Cost(OctileCost {
            straight: self.0.straight + o.0.straight,
            diagonal: self.0.diagonal + o.0.diagonal,
        })
    }
}

impl Zero for Cost {
    fn zero() -> Self {
        Cost::default()
    }
    fn is_zero(&self) -> bool {
        self.0 == OctileCost::default()
    }
}

/// Optimal cost in cells, or `None` without a path.
pub(crate) fn astar_cost(grid: &Grid2, model: MoveModel, start: Cell, goal: Cell) -> Option<f64> {
    let free = |r: i64, c: i64| grid.is_free_at(r, c);
    let successors = |&(r, c): &(i64, i64)| {
        let mut out = Vec::with_capacity(8);
        // Neighbour order only breaks ties among equal-cost paths; the cost is the same.
        for (dr, dc) in NEIGHBOURS_8 {
            let diagonal = dr != 0 && dc != 0;
            if !free(r + dr, c + dc) || (diagonal && !model.has_diagonals()) {
                continue;
            }
            if diagonal
                && model != MoveModel::OctileCornerCutting
                && !(free(r + dr, c) && free(r, c + dc))
            {
                continue;
            }
            let step = if diagonal {
                OctileCost {
                    straight: 0,
                    diagonal: 1,
                }
            } else {
                OctileCost {
                    straight: 1,
                    diagonal: 0,
                }
            };
            out.push(((r + dr, c + dc), Cost(step)));
        }
        out
    };
    let goal_rc = (i64::from(goal.row), i64::from(goal.col));
    let heuristic = |&(r, c): &(i64, i64)| {
        let (a, b) = (
            (r - goal_rc.0).unsigned_abs(),
            (c - goal_rc.1).unsigned_abs(),
        );
        match model {
            MoveModel::FourConnected => Cost(OctileCost {
                straight: a + b,
                diagonal: 0,
            }),
            _ => Cost(OctileCost {
                straight: a.max(b) - a.min(b),
                diagonal: a.min(b),
            }),
        }
    };
    let start_rc = (i64::from(start.row), i64::from(start.col));
    pathfinding::prelude::astar(&start_rc, successors, heuristic, |&n| n == goal_rc)
        .map(|(_, c)| c.0.to_f64())
}
