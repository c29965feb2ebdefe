//! Wavefront distance fields grown from the goal, and gradient descent on them.

use crate::moves::{for_each_move, key};
use crate::{Endpoint, NavError};
use skyplan_cspace::{Cell, Grid2};
use skyplan_search::{MoveModel, octile_cost};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};
use std::f64::consts::SQRT_2;

/// What a [`DistanceField`] counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum FieldMetric {
    /// Number of moves (breadth-first wavefront; every move counts 1, diagonals too).
    Steps,
    /// Path length in cells: straight moves 1, diagonals √2 (Dijkstra). The default; its descent
    /// has the length of an A\* path under the same move model.
    #[default]
    Length,
}

/// Distances to one goal cell for every cell of a grid (`f64::INFINITY` on obstacles and on cells
/// from which the goal cannot be reached).
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceField {
    grid: Grid2,
    goal: Cell,
    model: MoveModel,
    metric: FieldMetric,
    values: Vec<f64>,
}

/// A path found by [`DistanceField::descend`]: source first, goal last.
#[derive(Debug, Clone, PartialEq)]
pub struct Descent {
    /// The cells, source first.
    pub cells: Vec<Cell>,
    /// Orthogonal moves.
    pub straight_moves: u64,
    /// Diagonal moves.
    pub diagonal_moves: u64,
}

impl Descent {
    /// Length in cells, `straight + √2 · diagonal` (the same formula as the grid planners, so an
    /// optimal descent reports a bit-identical length).
    pub fn length_cells(&self) -> f64 {
        octile_cost(self.straight_moves, self.diagonal_moves)
    }
}

/// The finite value of `cell` in row-major `values` over `grid`; `None` if infinite or off the
/// grid.
pub(crate) fn finite_value(grid: &Grid2, values: &[f64], cell: Cell) -> Option<f64> {
    if !grid.contains(cell) {
        return None;
    }
    let v = values[grid.index(cell)];
    v.is_finite().then_some(v)
}

/// A descent from `source` to `goal` over the row-major `values` on `grid`, one `step` (next
/// cell, diagonal, cost) at a time: the cells with their move counts, and the sum of the steps'
/// costs. Errors: the source off the grid or at an obstacle; its value infinite, or a step that
/// finds no lower neighbour ("path could not be found").
pub(crate) fn descend_by(
    grid: &Grid2,
    values: &[f64],
    goal: Cell,
    source: Cell,
    mut step: impl FnMut(Cell) -> Option<(Cell, bool, f64)>,
) -> Result<(Descent, f64), NavError> {
    check_endpoint(grid, source, Endpoint::Source)?;
    let unreachable = NavError::Unreachable {
        source_cell: source,
        destination_cell: goal,
    };
    if finite_value(grid, values, source).is_none() {
        return Err(unreachable);
    }
    let mut descent = Descent {
        cells: vec![source],
        straight_moves: 0,
        diagonal_moves: 0,
    };
    let mut total = 0.0;
    let mut cell = source;
    while cell != goal {
        let Some((next, diagonal, cost)) = step(cell) else {
            return Err(unreachable);
        };
        if diagonal {
            descent.diagonal_moves += 1;
        } else {
            descent.straight_moves += 1;
        }
        total += cost;
        descent.cells.push(next);
        cell = next;
    }
    Ok((descent, total))
}

pub(crate) fn check_endpoint(grid: &Grid2, cell: Cell, which: Endpoint) -> Result<(), NavError> {
    grid.check_contains(cell)
        .map_err(|outside| NavError::Outside { which, outside })?;
    if grid.is_blocked(cell) {
        return Err(NavError::AtObstacle { which, cell });
    }
    Ok(())
}

/// The distance field to `goal` over `grid` under `model`: BFS for [`FieldMetric::Steps`],
/// Dijkstra for [`FieldMetric::Length`]. Linear in the grid size (BFS) or `n log n` (Dijkstra).
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_navfn::{distance_field, FieldMetric, MoveModel};
/// let grid = Grid2::from_ascii("...\n.#.\n...")?;
/// let field = distance_field(&grid, Cell::new(0, 0), MoveModel::Octile, FieldMetric::Length)?;
/// assert_eq!(field.value(Cell::new(2, 2)), Some(4.0)); // no corner cutting past the centre
/// assert_eq!(field.value(Cell::new(1, 1)), None);      // an obstacle
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn distance_field(
    grid: &Grid2,
    goal: Cell,
    model: MoveModel,
    metric: FieldMetric,
) -> Result<DistanceField, NavError> {
    check_endpoint(grid, goal, Endpoint::Destination)?;
    let mut values = vec![f64::INFINITY; grid.len()];
    let goal_index = grid.index(goal);
    values[goal_index] = 0.0;
    let effective = if model.has_diagonals() {
        metric
    } else {
        FieldMetric::Steps
    };
    match effective {
        FieldMetric::Steps => {
            let mut queue = VecDeque::from([goal_index as u32]);
            while let Some(index) = queue.pop_front() {
                let cell = grid.cell(index as usize);
                let next_value = values[index as usize] + 1.0;
                for_each_move(grid, cell, model, |next, _| {
                    let j = grid.index(next);
                    if values[j].is_infinite() {
                        values[j] = next_value;
                        queue.push_back(j as u32);
                    }
                });
            }
        }
        FieldMetric::Length => {
            let mut heap = BinaryHeap::from([Reverse((0u64, goal_index as u32))]);
            while let Some(Reverse((k, index))) = heap.pop() {
                let here = values[index as usize];
                if key(here) != k {
                    continue;
                }
                let cell = grid.cell(index as usize);
                for_each_move(grid, cell, model, |next, diagonal| {
                    let j = grid.index(next);
                    let candidate = here + if diagonal { SQRT_2 } else { 1.0 };
                    if candidate < values[j] {
                        values[j] = candidate;
                        heap.push(Reverse((key(candidate), j as u32)));
                    }
                });
            }
        }
    }
    Ok(DistanceField {
        grid: grid.clone(),
        goal,
        model,
        metric,
        values,
    })
}

impl DistanceField {
    /// The goal the field was grown from.
    pub fn goal(&self) -> Cell {
        self.goal
    }
    /// The move model.
    pub fn model(&self) -> MoveModel {
        self.model
    }
    /// What the values count.
    pub fn metric(&self) -> FieldMetric {
        self.metric
    }
    /// The grid the field covers.
    pub fn grid(&self) -> &Grid2 {
        &self.grid
    }
    /// Row-major values in cells (moves for [`FieldMetric::Steps`]); `f64::INFINITY` on obstacles
    /// and unreachable cells.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// The distance of a cell to the goal, `None` for obstacles, unreachable and off-grid cells.
    pub fn value(&self, cell: Cell) -> Option<f64> {
        finite_value(&self.grid, &self.values, cell)
    }
    /// Number of free cells from which the goal cannot be reached.
    pub fn unreachable_count(&self) -> usize {
        self.values
            .iter()
            .zip(self.grid.blocked_cells())
            .filter(|&(v, &b)| !b && v.is_infinite())
            .count()
    }

    /// Follows the gradient from `source` to the goal: each step moves to the neighbour `n`
    /// minimising `value(n) + move length` (for [`FieldMetric::Steps`]: `value(n) + 1`), ties going
    /// to the first move in the order N, E, S, W, NE, SE, SW, NW. Every step strictly lowers the
    /// value, so the descent never revisits a cell and always terminates; from every reachable cell
    /// it ends at the goal, along a path as short as the field's metric allows.
    ///
    /// Errors: the source off the grid, at an obstacle, or unreachable ("path could not be found").
    pub fn descend(&self, source: Cell) -> Result<Descent, NavError> {
        let step = |cell: Cell| {
            let here = self.values[self.grid.index(cell)];
            let mut best: Option<(f64, Cell, bool)> = None;
            for_each_move(&self.grid, cell, self.model, |next, diagonal| {
                let v = self.values[self.grid.index(next)];
                if v >= here {
                    return;
                }
                let length = match self.metric {
                    FieldMetric::Length if diagonal => SQRT_2,
                    _ => 1.0,
                };
                let score = v + length;
                if best.is_none_or(|(b, _, _)| score < b) {
                    best = Some((score, next, diagonal));
                }
            });
            // A reachable non-goal cell always has a lower neighbour (its predecessor in the
            // wavefront); the guard keeps the loop finite even if it had none.
            best.map(|(_, next, diagonal)| (next, diagonal, 0.0))
        };
        let (descent, _) = descend_by(&self.grid, &self.values, self.goal, source, step)?;
        Ok(descent)
    }
}
