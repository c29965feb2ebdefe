//! Theta\* (Nash, Daniel, Koenig & Felner 2007): any-angle search on the grid.
//!
//! Like A\*, but a successor may take its grandparent as parent when the straight segment
//! between them has line of sight under the move model's corner rule, so paths turn only at
//! obstacle corners and are shorter than any 8-connected path (never shorter than the straight
//! line). Theta\* is not guaranteed to find the shortest any-angle path; its length lies between
//! the Euclidean distance and the octile optimum, and the pipeline reports both.

use crate::astar::NO_PARENT;
use crate::jps::DIRS;
use crate::{GridPath, GridSearch, MoveModel, SearchError};
use skyplan_cspace::{Cell, Grid2};

#[inline]
fn euclid(a: Cell, b: Cell) -> f64 {
    (f64::from(a.row) - f64::from(b.row)).hypot(f64::from(a.col) - f64::from(b.col))
}

impl GridSearch {
    /// Theta\*: an any-angle path from `start` to `goal` whose turning points are cell centres;
    /// every segment has line of sight under `model.touch()`. [`GridPath::cost_cells`] is its
    /// Euclidean length.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_search::{GridSearch, MoveModel};
    /// let grid = Grid2::from_ascii(".......\n.......\n.......")?;
    /// let path = GridSearch::new().theta_star(&grid, Cell::new(0, 0), Cell::new(2, 6), MoveModel::Octile)?;
    /// assert_eq!(path.cells, vec![Cell::new(0, 0), Cell::new(2, 6)]); // one straight segment
    /// assert!((path.cost_cells() - 40f64.sqrt()).abs() < 1e-12);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn theta_star(
        &mut self,
        grid: &Grid2,
        start: Cell,
        goal: Cell,
        model: MoveModel,
    ) -> Result<GridPath, SearchError> {
        crate::astar::check_endpoints(grid, start, goal)?;
        self.reset(grid, false);
        let touch = model.touch();
        let cols = i64::from(grid.cols());
        let start_i = grid.index(start);
        self.offer(start_i, 0.0, euclid(start, goal), NO_PARENT);
        // The straight moves are the first four of `DIRS`.
        let moves: &[(i64, i64)] = if model.has_diagonals() {
            &DIRS
        } else {
            &DIRS[..4]
        };
        let mut expansions = 0u64;
        while let Some((g, index)) = self.expand_next() {
            let i = index as usize;
            expansions += 1;
            let cell = grid.cell(i);
            if cell == goal {
                let mut path = self.reconstruct(grid, index, expansions);
                path.any_angle_cells =
                    Some(path.cells.windows(2).map(|w| euclid(w[0], w[1])).sum());
                path.straight_moves = 0;
                path.diagonal_moves = 0;
                return Ok(path);
            }
            let parent = self.parent(i);
            let (r, c) = (i64::from(cell.row), i64::from(cell.col));
            for &(dr, dc) in moves {
                let Some(next) = grid.checked_cell(r + dr, c + dc) else {
                    continue;
                };
                if grid.is_blocked(next)
                    || (dr != 0 && dc != 0 && !model.corner_ok(grid, cell, dr, dc))
                {
                    continue;
                }
                let ni = (r + dr) * cols + (c + dc);
                let ni = ni as usize;
                if self.is_closed(ni) {
                    continue;
                }
                // Path 2 of Theta*: straight from the grandparent when it sees `next`.
                let (via, via_g) = if parent != NO_PARENT
                    && grid.line_of_sight(grid.cell(parent as usize), next, touch)
                {
                    (parent, self.g(parent as usize))
                } else {
                    (index, g)
                };
                let ng = via_g + euclid(grid.cell(via as usize), next);
                self.offer(ni, ng, euclid(next, goal), via);
            }
        }
        Err(SearchError::Unreachable { expansions })
    }
}
