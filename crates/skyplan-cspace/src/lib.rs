//! Configuration spaces for skyplan.
//!
//! [`Grid2`] is a 2D occupancy grid: cell `(row, col)` covers north
//! `[origin_north_m + row·cell_m, … + cell_m)` and east `[origin_east_m + col·cell_m, … + cell_m)`,
//! so row 0 is the southern edge and column 0 the western edge. Planners only see rows and columns;
//! the [`GridFrame`] turns them into local north/east metres. [`Grid2::from_colliders`] and
//! [`Grid2::from_footprints`] build the grid of a map at a flight altitude.
//!
//! ```
//! use skyplan_cspace::{Cell, Grid2};
//! let grid = Grid2::from_ascii("..#\n...")?;
//! assert!(grid.is_blocked(Cell::new(0, 2)));
//! assert_eq!(grid.blocked_count(), 1);
//! # Ok::<(), skyplan_cspace::GridError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod colliders_grid;
mod footprint_grid;
mod line_of_sight;
mod zone_grid;

pub use colliders_grid::GridSpec;
pub use line_of_sight::Touch;

/// The eight neighbour offsets `(d_row, d_col)`: the four straight moves (north, east, south,
/// west) first, then the diagonals (north-east, south-east, south-west, north-west). Planners
/// that break ties by neighbour order use this one.
pub const NEIGHBOURS_8: [(i64, i64); 8] = [
    (1, 0),
    (0, 1),
    (-1, 0),
    (0, -1),
    (1, 1),
    (-1, 1),
    (-1, -1),
    (1, -1),
];

/// Largest grid skyplan builds, in cells (a 20 000 × 20 000 grid).
pub const MAX_CELLS: usize = 400_000_000;

/// A grid cell: `row` counts north, `col` counts east.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell {
    /// Row index (north).
    pub row: u32,
    /// Column index (east).
    pub col: u32,
}

impl Cell {
    /// A cell from its row and column.
    pub const fn new(row: u32, col: u32) -> Self {
        Self { row, col }
    }
}

/// Placement of a grid in the local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridFrame {
    /// North coordinate of the southern edge of row 0, metres.
    pub origin_north_m: f64,
    /// East coordinate of the western edge of column 0, metres.
    pub origin_east_m: f64,
    /// Edge length of a square cell, metres.
    pub cell_m: f64,
}

impl Default for GridFrame {
    fn default() -> Self {
        Self {
            origin_north_m: 0.0,
            origin_east_m: 0.0,
            cell_m: 1.0,
        }
    }
}

/// Why a grid could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    /// A parameter out of its range.
    #[error("{name} = {value}: expected {expected}")]
    BadParameter {
        /// Parameter name, with its unit.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What was expected.
        expected: &'static str,
    },
    /// The grid would be too large.
    #[error("a {rows} × {cols} grid has more than {MAX_CELLS} cells; use a larger cell size")]
    TooLarge {
        /// Rows requested.
        rows: u64,
        /// Columns requested.
        cols: u64,
    },
    /// Occupancy data whose length does not match the size.
    #[error("occupancy has {found} cells, expected {rows} × {cols}")]
    SizeMismatch {
        /// Rows.
        rows: u32,
        /// Columns.
        cols: u32,
        /// Cells given.
        found: usize,
    },
    /// A character other than `.` or `#` in [`Grid2::from_ascii`].
    #[error("row {row}: expected `.` (free) or `#` (blocked) and rows of equal length")]
    BadAscii {
        /// 0-based row in the text.
        row: usize,
    },
}

/// A cell that is not on a grid, with the grid's size: the one refusal every planner gives for
/// a start, goal or other endpoint off the grid ([`Grid2::check_contains`]). Planner errors
/// name which endpoint and show this one's message after it.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2, OutsideGrid};
/// let grid = Grid2::from_ascii("...\n...")?;
/// assert_eq!(grid.check_contains(Cell::new(1, 2)), Ok(()));
/// let err = grid.check_contains(Cell::new(5, 0)).unwrap_err();
/// assert_eq!(err, OutsideGrid { cell: Cell::new(5, 0), rows: 2, cols: 3 });
/// assert_eq!(err.to_string(), "cell (row 5, col 0) is outside the 2 × 3 grid");
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("cell (row {}, col {}) is outside the {rows} × {cols} grid", .cell.row, .cell.col)]
pub struct OutsideGrid {
    /// The cell.
    pub cell: Cell,
    /// Grid rows.
    pub rows: u32,
    /// Grid columns.
    pub cols: u32,
}

/// A 2D occupancy grid (row-major, `true` = blocked).
#[derive(Debug, Clone)]
pub struct Grid2 {
    rows: u32,
    cols: u32,
    blocked: Vec<bool>,
    frame: GridFrame,
    /// The number of blocked cells, counted on first asking (every plan reports it, and a
    /// city of 86 M cells takes tens of milliseconds to count); emptied by every change.
    count: std::sync::OnceLock<usize>,
}

impl PartialEq for Grid2 {
    fn eq(&self, other: &Self) -> bool {
        (self.rows, self.cols, self.frame) == (other.rows, other.cols, other.frame)
            && self.blocked == other.blocked
    }
}

impl Grid2 {
    /// A grid from row-major occupancy (`true` = blocked) and its frame.
    pub fn new(
        rows: u32,
        cols: u32,
        blocked: Vec<bool>,
        frame: GridFrame,
    ) -> Result<Self, GridError> {
        check_size(u64::from(rows), u64::from(cols))?;
        if blocked.len() != rows as usize * cols as usize {
            return Err(GridError::SizeMismatch {
                rows,
                cols,
                found: blocked.len(),
            });
        }
        Ok(Self {
            rows,
            cols,
            blocked,
            frame,
            count: std::sync::OnceLock::new(),
        })
    }

    /// A fixed grid (default frame) from row-major *passable* flags, as map formats such as
    /// MovingAI's store them (row = y, column = x, in file order).
    ///
    /// ```
    /// let grid = skyplan_cspace::Grid2::from_passable(1, 3, &[true, false, true])?;
    /// assert_eq!(grid.blocked_cells(), &[false, true, false]);
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn from_passable(rows: u32, cols: u32, passable: &[bool]) -> Result<Self, GridError> {
        let blocked = passable.iter().map(|&p| !p).collect();
        Self::new(rows, cols, blocked, GridFrame::default())
    }

    /// A grid from text: `#` blocked, anything else `.` free; the first line is row 0.
    pub fn from_ascii(text: &str) -> Result<Self, GridError> {
        let lines: Vec<&str> = text
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect();
        let cols = lines.first().map_or(0, |l| l.len());
        let mut blocked = Vec::with_capacity(lines.len() * cols);
        for (row, line) in lines.iter().enumerate() {
            if line.len() != cols || !line.bytes().all(|b| b == b'.' || b == b'#') {
                return Err(GridError::BadAscii { row });
            }
            blocked.extend(line.bytes().map(|b| b == b'#'));
        }
        let rows = u32::try_from(lines.len()).map_err(|_| GridError::TooLarge {
            rows: lines.len() as u64,
            cols: cols as u64,
        })?;
        let cols = u32::try_from(cols).map_err(|_| GridError::TooLarge {
            rows: u64::from(rows),
            cols: cols as u64,
        })?;
        Self::new(rows, cols, blocked, GridFrame::default())
    }

    /// Number of rows (north extent in cells).
    pub fn rows(&self) -> u32 {
        self.rows
    }
    /// Number of columns (east extent in cells).
    pub fn cols(&self) -> u32 {
        self.cols
    }
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.blocked.len()
    }
    /// True for a grid without cells.
    pub fn is_empty(&self) -> bool {
        self.blocked.is_empty()
    }
    /// The grid's placement in the local frame.
    pub fn frame(&self) -> GridFrame {
        self.frame
    }
    /// Row-major occupancy, `true` = blocked.
    pub fn blocked_cells(&self) -> &[bool] {
        &self.blocked
    }
    /// Number of blocked cells (counted once, kept until the grid changes).
    pub fn blocked_count(&self) -> usize {
        let count = *self
            .count
            .get_or_init(|| self.blocked.iter().filter(|&&b| b).count());
        debug_assert_eq!(
            count,
            self.blocked.iter().filter(|&&b| b).count(),
            "a change to the grid kept a stale count"
        );
        count
    }

    /// Forgets the kept count: every change to `blocked` calls this.
    pub(crate) fn forget_count(&mut self) {
        self.count.take();
    }
    /// Row-major index of an in-bounds cell.
    #[inline]
    pub fn index(&self, cell: Cell) -> usize {
        cell.row as usize * self.cols as usize + cell.col as usize
    }
    /// The cell of a row-major index.
    #[inline]
    pub fn cell(&self, index: usize) -> Cell {
        let cols = self.cols as usize;
        Cell::new((index / cols) as u32, (index % cols) as u32)
    }
    /// The cell at signed coordinates, if inside the grid.
    #[inline]
    pub fn checked_cell(&self, row: i64, col: i64) -> Option<Cell> {
        (row >= 0 && col >= 0 && row < i64::from(self.rows) && col < i64::from(self.cols))
            .then(|| Cell::new(row as u32, col as u32))
    }
    /// True if the cell is inside the grid.
    #[inline]
    pub fn contains(&self, cell: Cell) -> bool {
        cell.row < self.rows && cell.col < self.cols
    }
    /// `Ok` if the cell is inside the grid, else the [`OutsideGrid`] refusal naming it and the
    /// grid's size.
    pub fn check_contains(&self, cell: Cell) -> Result<(), OutsideGrid> {
        if self.contains(cell) {
            Ok(())
        } else {
            Err(OutsideGrid {
                cell,
                rows: self.rows,
                cols: self.cols,
            })
        }
    }
    /// True if the cell is blocked; cells outside the grid count as blocked.
    #[inline]
    pub fn is_blocked(&self, cell: Cell) -> bool {
        !self.contains(cell) || self.blocked[self.index(cell)]
    }
    /// True if signed coordinates are inside the grid and free.
    #[inline]
    pub fn is_free_at(&self, row: i64, col: i64) -> bool {
        self.checked_cell(row, col)
            .is_some_and(|c| !self.blocked[self.index(c)])
    }
    /// Sets a cell's occupancy (ignored outside the grid).
    pub fn set_blocked(&mut self, cell: Cell, blocked: bool) {
        if self.contains(cell) {
            let i = self.index(cell);
            self.blocked[i] = blocked;
            self.forget_count();
        }
    }

    /// Local (north, east) metres of a cell's centre.
    pub fn center_ne(&self, cell: Cell) -> (f64, f64) {
        let f = self.frame;
        (
            f.origin_north_m + (f64::from(cell.row) + 0.5) * f.cell_m,
            f.origin_east_m + (f64::from(cell.col) + 0.5) * f.cell_m,
        )
    }

    /// The cell containing a local (north, east) point, if it is on the grid.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2, GridFrame};
    /// let frame = GridFrame { origin_north_m: -10.0, origin_east_m: -5.0, cell_m: 2.0 };
    /// let grid = Grid2::new(10, 10, vec![false; 100], frame)?;
    /// assert_eq!(grid.cell_at_ne(0.0, 0.0), Some(Cell::new(5, 2)));
    /// assert_eq!(grid.cell_at_ne(10.0, 0.0), None);
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn cell_at_ne(&self, north_m: f64, east_m: f64) -> Option<Cell> {
        let (row, col) = self.fractional_rc(north_m, east_m);
        if !(row.is_finite() && col.is_finite()) {
            return None;
        }
        self.checked_cell(row.floor() as i64, col.floor() as i64)
    }

    fn fractional_rc(&self, north_m: f64, east_m: f64) -> (f64, f64) {
        let f = self.frame;
        (
            (north_m - f.origin_north_m) / f.cell_m,
            (east_m - f.origin_east_m) / f.cell_m,
        )
    }

    /// The free cell whose centre is nearest (Euclidean) to a local point, on or off the grid.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2};
    /// let grid = Grid2::from_ascii("###\n##.\n###")?;
    /// assert_eq!(grid.nearest_free_ne(0.5, 0.5), Some(Cell::new(1, 2)));
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn nearest_free_ne(&self, north_m: f64, east_m: f64) -> Option<Cell> {
        if self.is_empty() || !(north_m.is_finite() && east_m.is_finite()) {
            return None;
        }
        let (fr, fc) = self.fractional_rc(north_m, east_m);
        let r0 = (fr.floor() as i64).clamp(0, i64::from(self.rows) - 1);
        let c0 = (fc.floor() as i64).clamp(0, i64::from(self.cols) - 1);
        // Distances in cells; a ring at Chebyshev radius r is at least r - d0 away from the point.
        let d0 = ((fr - (r0 as f64 + 0.5)).powi(2) + (fc - (c0 as f64 + 0.5)).powi(2)).sqrt();
        let mut best: Option<(f64, Cell)> = None;
        let max_r = i64::from(self.rows.max(self.cols));
        for r in 0..=max_r {
            if let Some((d, _)) = best
                && r as f64 - d0 > d
            {
                break;
            }
            let mut consider = |row: i64, col: i64| {
                if self.is_free_at(row, col) {
                    let d = ((fr - (row as f64 + 0.5)).powi(2) + (fc - (col as f64 + 0.5)).powi(2))
                        .sqrt();
                    let cell = Cell::new(row as u32, col as u32);
                    if best.is_none_or(|(bd, bc)| d < bd || (d == bd && cell < bc)) {
                        best = Some((d, cell));
                    }
                }
            };
            if r == 0 {
                consider(r0, c0);
                continue;
            }
            for k in -r..=r {
                consider(r0 - r, c0 + k);
                consider(r0 + r, c0 + k);
            }
            for k in (-r + 1)..r {
                consider(r0 + k, c0 - r);
                consider(r0 + k, c0 + r);
            }
        }
        best.map(|(_, c)| c)
    }
}

fn check_size(rows: u64, cols: u64) -> Result<(), GridError> {
    if rows.saturating_mul(cols) > MAX_CELLS as u64
        || rows > u64::from(u32::MAX)
        || cols > u64::from(u32::MAX)
    {
        return Err(GridError::TooLarge { rows, cols });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kept count follows every change, a clone's changes leave the original's alone, and
    /// equality is the cells' (asked or not).
    #[test]
    fn the_kept_count_follows_the_changes() {
        let mut grid = Grid2::from_ascii("#..\n.#.\n...").unwrap();
        let brute = |g: &Grid2| g.blocked_cells().iter().filter(|&&b| b).count();
        assert_eq!(grid.blocked_count(), 2);
        let mut copy = grid.clone();
        copy.set_blocked(Cell::new(2, 2), true);
        assert_eq!((copy.blocked_count(), grid.blocked_count()), (3, 2));
        assert_ne!(copy, grid);
        grid.set_blocked(Cell::new(2, 2), true);
        assert_eq!(copy, grid);
        grid.set_blocked(Cell::new(0, 0), false);
        grid.set_blocked(Cell::new(1, 1), false);
        assert_eq!(grid.blocked_count(), 1);
        assert_eq!(grid.blocked_count(), brute(&grid));
        let fresh = Grid2::from_ascii("...\n...\n..#").unwrap();
        assert_eq!(fresh, grid, "equal cells, one grid counted and one not");
    }

    #[test]
    fn nearest_free_matches_brute_force() {
        let grid = Grid2::from_ascii("#####\n#####\n####.\n#####\n.####").unwrap();
        for &(n, e) in &[(0.2, 0.2), (4.9, 4.9), (2.5, 2.5), (-3.0, 10.0), (2.5, 4.0)] {
            let got = grid.nearest_free_ne(n, e).unwrap();
            let brute = (0..grid.len())
                .map(|i| grid.cell(i))
                .filter(|&c| !grid.is_blocked(c))
                .min_by(|&a, &b| {
                    let d = |c: Cell| {
                        let (cn, ce) = grid.center_ne(c);
                        (cn - n).hypot(ce - e)
                    };
                    d(a).total_cmp(&d(b)).then(a.cmp(&b))
                })
                .unwrap();
            assert_eq!(got, brute, "point {n},{e}");
        }
        assert_eq!(
            Grid2::from_ascii("##\n##")
                .unwrap()
                .nearest_free_ne(0.0, 0.0),
            None
        );
    }
}
