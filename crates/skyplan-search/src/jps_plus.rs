//! JPS+ (Rabin & Sturtevant): Jump Point Search with every scan precomputed.
//!
//! For each cell and each of the 8 directions the table holds where the goal-free scan of
//! [`crate::Planner::Jps`] would stop: `k > 0` means "a jump point `k` steps away", `−w ≤ 0` means
//! "no jump point; `w` cells can be scanned before a wall". A query then replaces every scan by a
//! lookup plus an O(1) test for the goal lying on the scanned ray, so it returns exactly what JPS
//! returns (the tests compare both, path for path) in a fraction of the time. Building the table
//! is linear in the grid size; build it once per grid and reuse it for many queries.

use crate::jps::{DIRS, View, dir_index};
use crate::{GridPath, GridSearch, MoveModel, SearchError};
use skyplan_cspace::{Cell, Grid2};
use std::sync::Arc;

/// A JPS+ planner bound to one grid and one corner rule (a [`JpsPlusTable`] and a search
/// workspace).
#[derive(Debug)]
pub struct JpsPlus<'g> {
    grid: &'g Grid2,
    table: JpsPlusTable,
    search: GridSearch,
}

impl<'g> JpsPlus<'g> {
    /// Precomputes the jump table of `grid` for an octile move model (`FourConnected` is
    /// treated as [`MoveModel::Octile`]'s corner rule would be meaningless; use A\* for it).
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_search::{GridSearch, JpsPlus, MoveModel, Planner};
    /// let grid = Grid2::from_ascii("......\n.####.\n......")?;
    /// let mut jps_plus = JpsPlus::new(&grid, MoveModel::Octile);
    /// let fast = jps_plus.search(Cell::new(0, 0), Cell::new(2, 5))?;
    /// let reference = GridSearch::new().search(&grid, Cell::new(0, 0), Cell::new(2, 5), MoveModel::Octile, Planner::AStar)?;
    /// assert_eq!(fast.cost_cells(), reference.cost_cells());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new(grid: &'g Grid2, model: MoveModel) -> Self {
        Self {
            grid,
            table: JpsPlusTable::build(Arc::new(grid.clone()), model),
            search: GridSearch::new(),
        }
    }

    /// The grid this planner was built for.
    pub fn grid(&self) -> &'g Grid2 {
        self.grid
    }

    /// Bytes held by the jump table.
    pub fn table_bytes(&self) -> usize {
        self.table.table_bytes()
    }

    /// An optimal path from `start` to `goal` (the same path [`crate::Planner::Jps`] returns).
    pub fn search(&mut self, start: Cell, goal: Cell) -> Result<GridPath, SearchError> {
        self.table.search(&mut self.search, start, goal)
    }
}

/// The JPS+ preprocessing of one grid under one corner rule, owning its grid (`Arc`), so a
/// planning session can keep it across requests; saved and loaded with
/// [`JpsPlusTable::to_bytes`] / [`JpsPlusTable::from_bytes`] (file layout in [`crate::table_file`]).
#[derive(Debug)]
pub struct JpsPlusTable {
    grid: Arc<Grid2>,
    model: MoveModel,
    pub(crate) table: Vec<[i32; 8]>,
    /// Free-neighbour bit set of every cell (bit `k`: `DIRS[k]`).
    masks: Vec<u8>,
}

impl JpsPlusTable {
    /// Precomputes the jump table of `grid` (linear in its cells; `FourConnected` is built as
    /// [`MoveModel::Octile`]).
    pub fn build(grid: Arc<Grid2>, model: MoveModel) -> Self {
        let model = if model == MoveModel::FourConnected {
            MoveModel::Octile
        } else {
            model
        };
        let view = View::new(&grid, Cell::new(0, 0), model);
        let (rows, cols) = (view.rows, view.cols);
        let mut table = vec![[0i32; 8]; grid.len()];
        for (k, &(dr, dc)) in DIRS.iter().enumerate() {
            // Visit p after p + d so that table[p + d] is ready.
            let row_order: Box<dyn Iterator<Item = i64>> = if dr > 0 {
                Box::new((0..rows).rev())
            } else {
                Box::new(0..rows)
            };
            for r in row_order {
                let col_order: Box<dyn Iterator<Item = i64>> = if dc > 0 {
                    Box::new((0..cols).rev())
                } else {
                    Box::new(0..cols)
                };
                for c in col_order {
                    let (qr, qc) = (r + dr, c + dc);
                    let value = if !view.free(qr, qc) {
                        0
                    } else {
                        let q = (qr * cols + qc) as usize;
                        let stops_here = if dr == 0 || dc == 0 {
                            view.forced_straight(qr, qc, dr, dc)
                        } else {
                            view.forced_diagonal(qr, qc, dr, dc)
                                || table[q][dir_index(dr, 0)] > 0
                                || table[q][dir_index(0, dc)] > 0
                        };
                        if stops_here {
                            1
                        } else if dr != 0 && dc != 0 && !view.diagonal_continues(qr, qc, dr, dc) {
                            -1
                        } else {
                            let s = table[q][k];
                            if s > 0 { s + 1 } else { s - 1 }
                        }
                    };
                    table[(r * cols + c) as usize][k] = value;
                }
            }
        }
        let masks = (0..grid.len() as i64)
            .map(|i| view.neighbour_mask(i / cols, i % cols))
            .collect();
        Self {
            grid,
            model,
            table,
            masks,
        }
    }

    /// A table read from a file: the masks are recomputed from the grid.
    pub(crate) fn from_parts(grid: Arc<Grid2>, model: MoveModel, table: Vec<[i32; 8]>) -> Self {
        let view = View::new(&grid, Cell::new(0, 0), model);
        let cols = view.cols;
        let masks = (0..grid.len() as i64)
            .map(|i| view.neighbour_mask(i / cols, i % cols))
            .collect();
        Self {
            grid,
            model,
            table,
            masks,
        }
    }

    /// The grid this table was built for.
    pub fn grid(&self) -> &Arc<Grid2> {
        &self.grid
    }

    /// The corner rule it was built for ([`MoveModel::Octile`] or
    /// [`MoveModel::OctileCornerCutting`]).
    pub fn model(&self) -> MoveModel {
        self.model
    }

    /// Bytes held by the jump table (not counting the grid).
    pub fn table_bytes(&self) -> usize {
        self.table.len() * std::mem::size_of::<[i32; 8]>() + self.masks.len()
    }

    /// An optimal path from `start` to `goal` on the table's grid (the same path
    /// [`crate::Planner::Jps`] returns), with `search` as the workspace.
    pub fn search(
        &self,
        search: &mut GridSearch,
        start: Cell,
        goal: Cell,
    ) -> Result<GridPath, SearchError> {
        let grid = &*self.grid;
        crate::astar::check_endpoints(grid, start, goal)?;
        let view = View::new(grid, goal, self.model);
        let table = &self.table;
        let cols = view.cols;
        let (gr, gc) = view.goal;
        // Reach of a scan: how many cells along the ray it examines.
        let reach = |s: i32| i64::from(s.unsigned_abs());
        let jump = |r: i64, c: i64, dr: i64, dc: i64| -> Option<(i64, i64)> {
            let s = table[(r * cols + c) as usize][dir_index(dr, dc)];
            let limit = reach(s);
            if dr == 0 || dc == 0 {
                let t = if dr == 0 {
                    (gr == r).then(|| (gc - c) * dc)
                } else {
                    (gc == c).then(|| (gr - r) * dr)
                };
                if let Some(t) = t
                    && t >= 1
                    && t <= limit
                {
                    return Some((gr, gc));
                }
                return (s > 0).then(|| (r + i64::from(s) * dr, c + i64::from(s) * dc));
            }
            let mut best = (s > 0).then_some(i64::from(s));
            let mut consider = |i: i64| {
                if i >= 1 && i <= limit && best.is_none_or(|b| i < b) {
                    best = Some(i);
                }
            };
            let i_col = (gc - c) * dc; // step at which the scan stands in the goal's column
            let i_row = (gr - r) * dr; // step at which it stands in the goal's row
            if i_col == i_row {
                consider(i_col);
            }
            if i_col >= 1 && i_col <= limit {
                let (qr, qc) = (r + i_col * dr, c + i_col * dc);
                let t = (gr - qr) * dr;
                if t >= 1 && t <= reach(table[(qr * cols + qc) as usize][dir_index(dr, 0)]) {
                    consider(i_col);
                }
            }
            if i_row >= 1 && i_row <= limit {
                let (qr, qc) = (r + i_row * dr, c + i_row * dc);
                let t = (gc - qc) * dc;
                if t >= 1 && t <= reach(table[(qr * cols + qc) as usize][dir_index(0, dc)]) {
                    consider(i_row);
                }
            }
            best.map(|i| (r + i * dr, c + i * dc))
        };
        let masks = &self.masks;
        search.jump_point_search(grid, start, goal, &view, |_, _, i| masks[i], jump)
    }
}
