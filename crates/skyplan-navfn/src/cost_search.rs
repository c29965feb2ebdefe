//! Planning on a cost map: minimise length + weight · cost.
//!
//! A move of length `ℓ` (1 or √2 cells) into a cell of cost `c` costs `ℓ · (1 + weight · c / 252)`:
//! the path length plus `weight` times the path integral of the normalised cost. Cells of cost
//! ≥ [`INSCRIBED`](crate::INSCRIBED) are impassable. With weight 0 this is the plain octile length.

use crate::field::{check_endpoint, descend_by, finite_value};
use crate::moves::{for_each_move, key};
use crate::{Costmap, Endpoint, MAX_NON_OBSTACLE, NavError};
use skyplan_cspace::{Cell, Grid2};
use skyplan_search::{MoveModel, OpenEntry, OpenList, octile_cost};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::f64::consts::SQRT_2;

/// A path on a cost map: source first, goal last.
#[derive(Debug, Clone, PartialEq)]
pub struct CostPath {
    /// The cells, source first.
    pub cells: Vec<Cell>,
    /// Orthogonal moves.
    pub straight_moves: u64,
    /// Diagonal moves.
    pub diagonal_moves: u64,
    /// The minimised objective, length + weight · cost, in cells.
    pub objective_cells: f64,
    /// Cells expanded (0 for a descent on a [`CostToGo`] field).
    pub expansions: u64,
}

impl CostPath {
    /// Geometric length in cells, `straight + √2 · diagonal`.
    pub fn length_cells(&self) -> f64 {
        octile_cost(self.straight_moves, self.diagonal_moves)
    }
}

/// What both searches start from: the costmap's passable grid and each cell's factor
/// `1 + weight · cost / 252` of a move's length. A weight that is not finite and ≥ 0 is refused.
fn weighted_grid(costmap: &Costmap, weight: f64) -> Result<(Grid2, Vec<f64>), NavError> {
    if !(weight.is_finite() && weight >= 0.0) {
        return Err(NavError::BadParameter {
            name: "cost weight",
            value: weight,
            expected: "a finite weight ≥ 0",
        });
    }
    let multipliers = costmap
        .costs()
        .iter()
        .map(|&c| 1.0 + weight * f64::from(c) / f64::from(MAX_NON_OBSTACLE))
        .collect();
    Ok((costmap.passable_grid(), multipliers))
}

#[inline]
fn step_length(diagonal: bool) -> f64 {
    if diagonal { SQRT_2 } else { 1.0 }
}

fn check_endpoints(grid: &Grid2, source: Cell, goal: Cell) -> Result<(), NavError> {
    check_endpoint(grid, source, Endpoint::Source)?;
    check_endpoint(grid, goal, Endpoint::Destination)
}

/// A\* (or, with `heuristic = false`, Dijkstra) from `source` to `goal` on a cost map, minimising
/// length + `weight` · cost. The heuristic is the move model's distance, admissible because every
/// move costs at least its length.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_navfn::{cost_search, Costmap, Inflation, MoveModel};
/// let grid = Grid2::from_ascii(".....\n.....\n..#..\n.....\n.....")?;
/// let p = Inflation { inscribed_radius_m: 0.0, inflation_radius_m: 1.5, cost_scaling_factor: 1.0 };
/// let costmap = Costmap::inflate(&grid, p)?;
/// let plain = cost_search(&costmap, Cell::new(0, 2), Cell::new(4, 2), MoveModel::Octile, 0.0, true)?;
/// let careful = cost_search(&costmap, Cell::new(0, 2), Cell::new(4, 2), MoveModel::Octile, 10.0, true)?;
/// assert!(careful.length_cells() > plain.length_cells()); // a wider berth round the obstacle
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn cost_search(
    costmap: &Costmap,
    source: Cell,
    goal: Cell,
    model: MoveModel,
    weight: f64,
    heuristic: bool,
) -> Result<CostPath, NavError> {
    let (grid, mult) = weighted_grid(costmap, weight)?;
    check_endpoints(&grid, source, goal)?;
    let n = grid.len();
    let mut g = vec![f64::INFINITY; n];
    let mut parent = vec![u32::MAX; n];
    let h = |c: Cell| {
        if heuristic {
            model.heuristic(c, goal)
        } else {
            0.0
        }
    };
    let (s, t) = (grid.index(source), grid.index(goal));
    g[s] = 0.0;
    let mut open = OpenList::new(n);
    open.push(OpenEntry {
        f: h(source),
        g: 0.0,
        node: s as u32,
    });
    while let Some(OpenEntry { node: index, .. }) = open.pop() {
        let i = index as usize;
        if i == t {
            break;
        }
        let cell = grid.cell(i);
        for_each_move(&grid, cell, model, |next, diagonal| {
            let j = grid.index(next);
            if open.is_closed(j as u32) {
                return;
            }
            let candidate = g[i] + step_length(diagonal) * mult[j];
            if candidate < g[j] {
                g[j] = candidate;
                parent[j] = index;
                open.push(OpenEntry {
                    f: candidate + h(next),
                    g: candidate,
                    node: j as u32,
                });
            }
        });
    }
    if !open.is_closed(t as u32) {
        return Err(NavError::Unreachable {
            source_cell: source,
            destination_cell: goal,
        });
    }
    let mut cells = vec![goal];
    let mut i = t;
    while i != s {
        i = parent[i] as usize;
        cells.push(grid.cell(i));
    }
    cells.reverse();
    let (straight_moves, diagonal_moves) = count_moves(&cells);
    Ok(CostPath {
        cells,
        straight_moves,
        diagonal_moves,
        objective_cells: g[t],
        expansions: open.expansions(),
    })
}

fn count_moves(cells: &[Cell]) -> (u64, u64) {
    let diagonal = cells
        .windows(2)
        .filter(|w| w[0].row != w[1].row && w[0].col != w[1].col)
        .count() as u64;
    (cells.len().saturating_sub(1) as u64 - diagonal, diagonal)
}

/// The cost-to-go field of a cost map: for every cell, the least length + weight · cost of a path
/// from it to the goal (`f64::INFINITY` where the goal cannot be reached).
#[derive(Debug, Clone, PartialEq)]
pub struct CostToGo {
    grid: Grid2,
    goal: Cell,
    model: MoveModel,
    multipliers: Vec<f64>,
    values: Vec<f64>,
}

/// Grows the cost-to-go field from `goal` (Dijkstra over the reversed moves).
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_navfn::{cost_search, cost_to_go, Costmap, Inflation, MoveModel};
/// let grid = Grid2::from_ascii("......\n..##..\n......")?;
/// let costmap = Costmap::inflate(&grid, Inflation { inscribed_radius_m: 0.0, inflation_radius_m: 2.0, cost_scaling_factor: 0.5 })?;
/// let field = cost_to_go(&costmap, Cell::new(1, 5), MoveModel::Octile, 2.0)?;
/// let astar = cost_search(&costmap, Cell::new(1, 0), Cell::new(1, 5), MoveModel::Octile, 2.0, true)?;
/// let ride = field.descend(Cell::new(1, 0))?;
/// assert!((field.value(Cell::new(1, 0)).unwrap() - astar.objective_cells).abs() < 1e-9);
/// assert!((ride.objective_cells - astar.objective_cells).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn cost_to_go(
    costmap: &Costmap,
    goal: Cell,
    model: MoveModel,
    weight: f64,
) -> Result<CostToGo, NavError> {
    let (grid, multipliers) = weighted_grid(costmap, weight)?;
    check_endpoint(&grid, goal, Endpoint::Destination)?;
    let mut values = vec![f64::INFINITY; grid.len()];
    let t = grid.index(goal);
    values[t] = 0.0;
    let mut heap = BinaryHeap::from([Reverse((key(0.0), t as u32))]);
    while let Some(Reverse((k, index))) = heap.pop() {
        let i = index as usize;
        if key(values[i]) != k {
            continue;
        }
        let cell = grid.cell(i);
        // A move from `prev` into `cell` costs its length times `cell`'s multiplier.
        let into_here = multipliers[i];
        for_each_move(&grid, cell, model, |prev, diagonal| {
            let j = grid.index(prev);
            let candidate = values[i] + step_length(diagonal) * into_here;
            if candidate < values[j] {
                values[j] = candidate;
                heap.push(Reverse((key(candidate), j as u32)));
            }
        });
    }
    Ok(CostToGo {
        grid,
        goal,
        model,
        multipliers,
        values,
    })
}

impl CostToGo {
    /// The goal.
    pub fn goal(&self) -> Cell {
        self.goal
    }
    /// The cost-to-go of a cell, `None` if blocked, unreachable or off the grid.
    pub fn value(&self, cell: Cell) -> Option<f64> {
        finite_value(&self.grid, &self.values, cell)
    }
    /// The grid the vehicle moves in (cells of cost ≥ 253 blocked).
    pub fn grid(&self) -> &Grid2 {
        &self.grid
    }
    /// Row-major values in cells; `f64::INFINITY` where the goal cannot be reached.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// One gradient step from `cell`: the neighbour minimising `value + move cost` among those with
    /// a strictly lower value (ties in the order N, E, S, W, NE, SE, SW, NW), with the move's cost.
    /// `None` at the goal or where the goal is unreachable.
    pub fn step(&self, cell: Cell) -> Option<(Cell, bool, f64)> {
        let here = self.value(cell)?;
        let mut best: Option<(f64, Cell, bool, f64)> = None;
        for_each_move(&self.grid, cell, self.model, |next, diagonal| {
            let j = self.grid.index(next);
            let v = self.values[j];
            if v >= here {
                return;
            }
            let cost = step_length(diagonal) * self.multipliers[j];
            if best.is_none_or(|(b, ..)| v + cost < b) {
                best = Some((v + cost, next, diagonal, cost));
            }
        });
        best.map(|(_, next, diagonal, cost)| (next, diagonal, cost))
    }

    /// Follows the gradient from `source` to the goal. Each step strictly lowers the value, so the
    /// descent never oscillates and ends after at most as many steps as there are cells.
    pub fn descend(&self, source: Cell) -> Result<CostPath, NavError> {
        let (descent, objective_cells) =
            descend_by(&self.grid, &self.values, self.goal, source, |cell| {
                self.step(cell)
            })?;
        Ok(CostPath {
            cells: descent.cells,
            straight_moves: descent.straight_moves,
            diagonal_moves: descent.diagonal_moves,
            objective_cells,
            expansions: 0,
        })
    }
}
