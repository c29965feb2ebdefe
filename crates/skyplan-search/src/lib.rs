//! Grid search for skyplan.
//!
//! * [`GridSearch`]: A\* (octile or Manhattan heuristic) and Dijkstra on a [`Grid2`], with flat
//!   arrays, `u32` cell indices and buffers reused between queries.
//! * [`oracle`]: an independent Dijkstra in exact arithmetic, the truth the tests compare against.
//! * [`Components`]: connected free regions under a move model, to tell "unreachable" up front.
//! * [`ContractionHierarchy`]: exact shortest paths with a per-grid preprocessing (shortcuts
//!   over the grid graph, bidirectional upward queries), for many queries on one grid.
//! * [`check_path`]: re-checks a path against the grid and the move model.
//! * [`OpenList`], [`OpenEntry`]: the binary-heap open list of the float-cost searches (graph
//!   A\*, roadmaps, voxel lattices, cost maps).
//!
//! Costs are in cells (multiply by the cell size for metres). A path's cost is computed from its
//! counts of straight and diagonal moves, so two optimal paths report bit-identical costs.
//!
//! ```
//! use skyplan_cspace::{Cell, Grid2};
//! use skyplan_search::{GridSearch, MoveModel, Planner};
//! let grid = Grid2::from_ascii("....\n.##.\n....")?;
//! let path = GridSearch::new().search(&grid, Cell::new(0, 0), Cell::new(2, 3), MoveModel::Octile, Planner::AStar)?;
//! assert_eq!(path.cells.first(), Some(&Cell::new(0, 0)));
//! assert_eq!((path.straight_moves, path.diagonal_moves), (5, 0)); // the wall forbids cut corners
//! assert_eq!(path.cost_cells(), 5.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod astar;
mod bidirectional;
mod bits;
pub mod ch_file;
mod components;
mod contraction;
mod first_move;
pub mod first_move_file;
mod hub_labels;
mod jps;
mod jps_plus;
pub mod landmarks;
mod nodes;
mod open;
pub mod oracle;
mod queue;
mod subgoal;
pub mod subgoal_file;
pub mod table_file;
mod theta;

pub use astar::GridSearch;
pub use bidirectional::bidirectional_astar;
pub use components::Components;
pub use contraction::{
    ChQuery, ContractionError, ContractionHierarchy, DIAGONAL as CH_DIAGONAL_COST,
    MAX_CELLS as CH_MAX_CELLS, STRAIGHT as CH_STRAIGHT_COST,
};
pub use first_move::{AT_TARGET, FirstMoveError, FirstMoveTable, UNREACHABLE};
pub use jps::BlockJps;
pub use jps_plus::{ACTIVE_LANDMARKS, ESCAPE_CELLS, JpsPlus, JpsPlusTable, landmarks_for};
pub use landmarks::Landmarks;
pub use open::{OpenEntry, OpenList};
pub use subgoal::{SubgoalError, SubgoalGraph, SubgoalQuery};

use skyplan_cspace::{Cell, Grid2, OutsideGrid};
use std::f64::consts::SQRT_2;

/// How a vehicle may move between grid cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum MoveModel {
    /// 4-connected: north, south, east, west; cost 1.
    FourConnected,
    /// 8-connected, diagonals cost √2 and need both orthogonally adjacent cells free
    /// (no corner cutting; the MovingAI convention). The default.
    #[default]
    Octile,
    /// 8-connected, diagonals cost √2 and need only the target cell free (the FCND move model).
    OctileCornerCutting,
}

impl MoveModel {
    /// True if the model allows diagonal moves.
    pub fn has_diagonals(self) -> bool {
        !matches!(self, MoveModel::FourConnected)
    }

    /// True if a diagonal move `from → from + (dr, dc)` may pass the corner between its two
    /// orthogonal neighbours: always with corner cutting, otherwise only when both are free.
    #[inline]
    pub fn corner_ok(self, grid: &Grid2, from: Cell, dr: i64, dc: i64) -> bool {
        match self {
            MoveModel::OctileCornerCutting => true,
            _ => {
                let (r, c) = (i64::from(from.row), i64::from(from.col));
                grid.is_free_at(r + dr, c) && grid.is_free_at(r, c + dc)
            }
        }
    }

    /// The line-of-sight rule that respects the model's corner rule: only the corner-cutting
    /// model may pass between two diagonally adjacent blocked cells.
    pub fn touch(self) -> skyplan_cspace::Touch {
        match self {
            MoveModel::OctileCornerCutting => skyplan_cspace::Touch::Open,
            MoveModel::FourConnected | MoveModel::Octile => skyplan_cspace::Touch::Closed,
        }
    }

    /// An admissible, consistent heuristic in cells between two cells.
    #[inline]
    pub fn heuristic(self, a: Cell, b: Cell) -> f64 {
        let dr = f64::from(a.row.abs_diff(b.row));
        let dc = f64::from(a.col.abs_diff(b.col));
        match self {
            MoveModel::FourConnected => dr + dc,
            _ => {
                let (lo, hi) = if dr < dc { (dr, dc) } else { (dc, dr) };
                (hi - lo) + lo * SQRT_2
            }
        }
    }
}

/// Which search algorithm [`GridSearch::search`] runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Planner {
    /// A\* with the move model's heuristic: the reference the fast planners are tested against.
    #[default]
    AStar,
    /// Dijkstra (A\* with a zero heuristic).
    Dijkstra,
    /// Jump Point Search: A\*'s costs with far fewer expansions on octile grids
    /// (4-connected grids fall back to A\*).
    Jps,
    /// Theta\*: any-angle paths (turning only at obstacle corners), shorter than the octile
    /// optimum; not optimal among any-angle paths.
    ThetaStar,
    /// JPS+ : JPS with every scan precomputed. Through [`GridSearch::search`] the table is
    /// rebuilt per query; build a [`JpsPlus`] once to answer many queries on one grid.
    JpsPlus,
}

/// A path of grid cells from start to goal, both included.
#[derive(Debug, Clone, PartialEq)]
pub struct GridPath {
    /// The cells, start first.
    pub cells: Vec<Cell>,
    /// Number of orthogonal moves (cost 1 each).
    pub straight_moves: u64,
    /// Number of diagonal moves (cost √2 each).
    pub diagonal_moves: u64,
    /// Number of cells expanded by the search.
    pub expansions: u64,
    /// For any-angle paths (Theta\*), whose consecutive cells need not be neighbours: the
    /// Euclidean length in cells. `None` for grid paths.
    pub any_angle_cells: Option<f64>,
}

impl GridPath {
    /// Cost in cells: `straight + √2 · diagonal` for grid paths, the Euclidean length for
    /// any-angle paths.
    pub fn cost_cells(&self) -> f64 {
        self.any_angle_cells
            .unwrap_or_else(|| octile_cost(self.straight_moves, self.diagonal_moves))
    }
}

/// `straight + √2 · diagonal`, the one place a move count becomes a float cost.
#[inline]
pub fn octile_cost(straight: u64, diagonal: u64) -> f64 {
    straight as f64 + diagonal as f64 * SQRT_2
}

/// Why a search has no path.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SearchError {
    /// The start cell is outside the grid.
    #[error("start {0}")]
    StartOutside(OutsideGrid),
    /// The goal cell is outside the grid.
    #[error("goal {0}")]
    GoalOutside(OutsideGrid),
    /// The start cell is blocked.
    #[error("start cell (row {}, col {}) is blocked", .0.row, .0.col)]
    StartBlocked(Cell),
    /// The goal cell is blocked.
    #[error("goal cell (row {}, col {}) is blocked", .0.row, .0.col)]
    GoalBlocked(Cell),
    /// The search exhausted every reachable cell without meeting the goal.
    #[error("goal is unreachable from start: the search expanded all {expansions} reachable cells")]
    Unreachable {
        /// Cells expanded before giving up.
        expansions: u64,
    },
    /// Preprocessing loaded from a file led off the free cells or round in a cycle (a file
    /// that passed its checksum but was written wrong): no path is given.
    #[error("the loaded preprocessing is damaged: {0}")]
    Damaged(String),
}

/// A defect found by [`check_path`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PathDefect {
    /// The path has no cells.
    #[error("the path is empty")]
    Empty,
    /// A cell is blocked or off the grid.
    #[error("cell {index} (row {}, col {}) is blocked or off the grid", .cell.row, .cell.col)]
    Blocked {
        /// Position in the path.
        index: usize,
        /// The cell.
        cell: Cell,
    },
    /// Two consecutive cells are not neighbours under the move model.
    #[error("step {index} → {} is not a move of the model", .index + 1)]
    NotAMove {
        /// Position of the first cell in the path.
        index: usize,
    },
    /// A diagonal step cuts a blocked corner.
    #[error("step {index} → {} cuts a blocked corner", .index + 1)]
    CutsCorner {
        /// Position of the first cell in the path.
        index: usize,
    },
}

/// Checks that a path is non-empty, stays on free cells, and moves only as the model allows.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_search::{check_path, MoveModel, PathDefect};
/// let grid = Grid2::from_ascii(".#\n..")?;
/// let cut = [Cell::new(0, 0), Cell::new(1, 1)];
/// assert_eq!(check_path(&grid, &cut, MoveModel::Octile), Err(PathDefect::CutsCorner { index: 0 }));
/// assert_eq!(check_path(&grid, &cut, MoveModel::OctileCornerCutting), Ok(()));
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn check_path(grid: &Grid2, cells: &[Cell], model: MoveModel) -> Result<(), PathDefect> {
    if cells.is_empty() {
        return Err(PathDefect::Empty);
    }
    for (index, &cell) in cells.iter().enumerate() {
        if grid.is_blocked(cell) {
            return Err(PathDefect::Blocked { index, cell });
        }
    }
    for (index, w) in cells.windows(2).enumerate() {
        let dr = i64::from(w[1].row) - i64::from(w[0].row);
        let dc = i64::from(w[1].col) - i64::from(w[0].col);
        let step = (dr.abs(), dc.abs());
        let is_move = match step {
            (1, 0) | (0, 1) => true,
            (1, 1) => model.has_diagonals(),
            _ => false,
        };
        if !is_move {
            return Err(PathDefect::NotAMove { index });
        }
        if step == (1, 1) && !model.corner_ok(grid, w[0], dr, dc) {
            return Err(PathDefect::CutsCorner { index });
        }
    }
    Ok(())
}
