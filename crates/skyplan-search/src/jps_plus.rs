//! JPS+ (Rabin & Sturtevant): Jump Point Search with every scan precomputed, in one byte per
//! cell and direction.
//!
//! For each cell and each of the 8 directions the table holds where the goal-free scan of
//! [`crate::Planner::Jps`] from that cell would stop, as one byte:
//!
//! * *wall* `w` (`0 ≤ w ≤ E`): no jump point; the scan examines `w` cells and then stops;
//! * *jump* `k` (`1 ≤ k ≤ E`): a jump point `k` cells away;
//! * *escape* (Harabor & Grastien's saturating entries): the next `E` cells hold no jump point
//!   and the scan goes on past them — continue with the entry of the cell `E` steps away. Two
//!   escape codes say whether the scan eventually meets a jump point, which is all a diagonal
//!   entry needs to know about the straight scans it spawns.
//!
//! `E` is the table's escape length ([`ESCAPE_CELLS`] = 126 by default; tests use tiny ones so
//! that escapes happen on small grids). A query replaces every scan by one lookup per `E` cells
//! plus an O(1) test for the goal lying on the scanned ray, so it returns exactly what JPS
//! returns (the tests compare both, path for path). Building the table is linear in the grid
//! size; build it once per grid and reuse it for many queries.

use crate::Landmarks;
use crate::jps::{DIRS, View, dir_index};
use crate::{GridPath, GridSearch, MoveModel, SearchError};
use skyplan_cspace::{Cell, Grid2};
use std::sync::{Arc, OnceLock};

/// Default escape length of a table: the longest distance one byte stores exactly (cells).
pub const ESCAPE_CELLS: u8 = 126;

/// Escape code: `E` cells without a jump point, the scan goes on, and it never meets one.
pub(crate) const ESCAPE_TO_WALL: u8 = 127;
/// Jump codes are `JUMP_BASE + k − 1` for a jump point `k` cells away.
pub(crate) const JUMP_BASE: u8 = 128;
/// Escape code: `E` cells without a jump point, the scan goes on, and it meets one later.
pub(crate) const ESCAPE_TO_JUMP: u8 = 255;

/// One table byte, decoded (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Entry {
    /// No jump point; the scan examines this many cells.
    Wall(u8),
    /// A jump point this many cells away.
    Jump(u8),
    /// `E` cells without a jump point; look up again `E` cells on.
    Escape,
}

/// Decodes a table byte of a table with escape length `escape` (`None`: impossible code).
#[inline(always)]
pub(crate) fn decode(code: u8, escape: u8) -> Option<Entry> {
    match code {
        ESCAPE_TO_WALL | ESCAPE_TO_JUMP => Some(Entry::Escape),
        w if w <= escape => Some(Entry::Wall(w)),
        c if c >= JUMP_BASE && c - JUMP_BASE < escape => Some(Entry::Jump(c - JUMP_BASE + 1)),
        _ => None,
    }
}

/// True if the scan described by `code` meets a jump point (here or after escapes).
#[inline(always)]
fn meets_jump_point(code: u8) -> bool {
    code >= JUMP_BASE
}

/// The code of the cell one step behind a cell whose own scan is `code`, when that cell is
/// free, not a jump point, and the scan goes on from it.
#[inline(always)]
fn extend(code: u8, escape: u8) -> u8 {
    match code {
        ESCAPE_TO_WALL | ESCAPE_TO_JUMP => code,
        w if w < JUMP_BASE => {
            if w < escape {
                w + 1
            } else {
                ESCAPE_TO_WALL
            }
        }
        c => {
            if c - JUMP_BASE + 1 < escape {
                c + 1
            } else {
                ESCAPE_TO_JUMP
            }
        }
    }
}

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
/// planning session can keep it across requests: 8 bytes per cell (module docs). Saved and
/// loaded with [`JpsPlusTable::write_to`] / [`JpsPlusTable::read_from`] (file layout in
/// [`crate::table_file`]).
#[derive(Debug)]
pub struct JpsPlusTable {
    grid: Arc<Grid2>,
    model: MoveModel,
    /// Escape length `E` in cells (1 ..= [`ESCAPE_CELLS`]).
    pub(crate) escape: u8,
    /// Per cell, per direction of [`DIRS`], one code.
    pub(crate) table: Vec<[u8; 8]>,
    /// Landmark distances that tighten the heuristic, once built or loaded
    /// ([`JpsPlusTable::add_landmarks`]).
    pub(crate) landmarks: OnceLock<Landmarks>,
}

/// Landmarks a query reads per cell ([`Landmarks::to_goal`]): the four that bound the start's
/// distance best (on Paris_1_256 with 8 or 16 kept, 2 to 4 active gave the fewest
/// expansions per µs).
pub const ACTIVE_LANDMARKS: usize = 4;

/// Landmarks to keep with a table that is saved (for many later queries): 8 on grids up
/// to 4 Mi cells (32 bytes per cell), 4 above (16 bytes per cell: 1.4 GB on the 9.3 km city).
pub fn landmarks_for(cells: usize) -> usize {
    if cells <= 1 << 22 { 8 } else { 4 }
}

impl JpsPlusTable {
    /// Precomputes the jump table of `grid` (linear in its cells; `FourConnected` is built as
    /// [`MoveModel::Octile`]).
    pub fn build(grid: Arc<Grid2>, model: MoveModel) -> Self {
        Self::build_with_escape(grid, model, ESCAPE_CELLS)
    }

    /// [`JpsPlusTable::build`] with escape length `escape_cells` (clamped to
    /// 1 ..= [`ESCAPE_CELLS`]): shorter escapes mean more lookups per scan and the same paths.
    /// Tests use tiny ones so that escapes happen on small grids.
    pub fn build_with_escape(grid: Arc<Grid2>, model: MoveModel, escape_cells: u8) -> Self {
        let model = if model == MoveModel::FourConnected {
            MoveModel::Octile
        } else {
            model
        };
        let escape = escape_cells.clamp(1, ESCAPE_CELLS);
        let view = View::new(&grid, Cell::new(0, 0), model);
        let (rows, cols) = (view.rows, view.cols);
        let mut table = vec![[0u8; 8]; grid.len()];
        for (k, &(dr, dc)) in DIRS.iter().enumerate() {
            let diagonal = dr != 0 && dc != 0;
            let (vert, horiz) = if diagonal {
                (dir_index(dr, 0), dir_index(0, dc))
            } else {
                (0, 0)
            };
            // Visit p after p + d so that table[p + d] is ready.
            for rr in 0..rows {
                let r = if dr > 0 { rows - 1 - rr } else { rr };
                let qr = r + dr;
                let row_free = qr >= 0 && qr < rows;
                for cc in 0..cols {
                    let c = if dc > 0 { cols - 1 - cc } else { cc };
                    let qc = c + dc;
                    let value = if !row_free || !view.free(qr, qc) {
                        0
                    } else {
                        let q = (qr * cols + qc) as usize;
                        let stops_here = if diagonal {
                            view.forced_diagonal(qr, qc, dr, dc)
                                || meets_jump_point(table[q][vert])
                                || meets_jump_point(table[q][horiz])
                        } else {
                            view.forced_straight(qr, qc, dr, dc)
                        };
                        if stops_here {
                            JUMP_BASE
                        } else if diagonal && !view.diagonal_continues(qr, qc, dr, dc) {
                            1
                        } else {
                            extend(table[q][k], escape)
                        }
                    };
                    table[(r * cols + c) as usize][k] = value;
                }
            }
        }
        Self {
            grid,
            model,
            escape,
            table,
            landmarks: OnceLock::new(),
        }
    }

    /// A table read from a file (codes already checked).
    pub(crate) fn from_parts(
        grid: Arc<Grid2>,
        model: MoveModel,
        escape: u8,
        table: Vec<[u8; 8]>,
    ) -> Self {
        Self {
            grid,
            model,
            escape,
            table,
            landmarks: OnceLock::new(),
        }
    }

    /// Builds `count` landmarks for this table's grid and model ([`Landmarks::build`]) unless
    /// it has some; later searches use them (same paths' costs, fewer expansions where walls
    /// force detours). Returns the table's landmarks.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_search::{GridSearch, JpsPlusTable, MoveModel};
    /// use std::sync::Arc;
    /// let grid = Arc::new(Grid2::from_ascii(".....\n####.\n.....")?);
    /// let table = JpsPlusTable::build(Arc::clone(&grid), MoveModel::Octile);
    /// let plain = table.search(&mut GridSearch::new(), Cell::new(0, 0), Cell::new(2, 0))?;
    /// assert_eq!(table.add_landmarks(2).cells().len(), 2);
    /// let guided = table.search(&mut GridSearch::new(), Cell::new(0, 0), Cell::new(2, 0))?;
    /// assert_eq!(guided.cost_cells(), plain.cost_cells());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn add_landmarks(&self, count: usize) -> &Landmarks {
        self.landmarks
            .get_or_init(|| Landmarks::build(&self.grid, self.model, count))
    }

    /// The landmarks the table holds, if any ([`JpsPlusTable::add_landmarks`]; none when the
    /// largest connected region of the grid is a single cell).
    pub fn landmarks(&self) -> Option<&Landmarks> {
        self.landmarks.get().filter(|l| !l.cells().is_empty())
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

    /// The escape length in cells (module docs).
    pub fn escape_cells(&self) -> u8 {
        self.escape
    }

    /// Bytes held by the jump table (not counting the grid): 8 per cell.
    pub fn table_bytes(&self) -> usize {
        self.table.len() * std::mem::size_of::<[u8; 8]>()
    }

    /// An optimal path from `start` to `goal` on the table's grid (the same path
    /// [`crate::Planner::Jps`] returns), with `search` as the workspace.
    pub fn search(
        &self,
        search: &mut GridSearch,
        start: Cell,
        goal: Cell,
    ) -> Result<GridPath, SearchError> {
        match self.landmarks() {
            Some(landmarks) => {
                crate::astar::check_endpoints(&self.grid, start, goal)?;
                let (s, g) = (self.grid.index(start), self.grid.index(goal));
                let bound = landmarks.to_goal(s, g, ACTIVE_LANDMARKS);
                self.search_bounded(search, start, goal, |i| bound.at(i))
            }
            _ => self.search_bounded(search, start, goal, |_| 0.0),
        }
    }

    fn search_bounded(
        &self,
        search: &mut GridSearch,
        start: Cell,
        goal: Cell,
        lower: impl Fn(usize) -> f64,
    ) -> Result<GridPath, SearchError> {
        let grid = &*self.grid;
        crate::astar::check_endpoints(grid, start, goal)?;
        let view = View::new(grid, goal, self.model);
        let scan = Scan {
            table: &self.table,
            escape: self.escape,
            esc: i64::from(self.escape),
            cols: view.cols,
            goal: view.goal,
        };
        let table = &self.table;
        // A cell's free neighbours, read from its own entry (same cache line as its jumps): a
        // direction's code is 0 exactly when the neighbour that way is blocked or off the grid.
        let mask = |_: i64, _: i64, i: usize| -> u8 {
            table[i]
                .iter()
                .enumerate()
                .fold(0u8, |m, (k, &code)| m | (u8::from(code != 0) << k))
        };
        let jump = |r: i64, c: i64, dr: i64, dc: i64| scan.jump(r, c, dr, dc);
        search.jump_point_search(grid, (start, goal), &view, mask, jump, lower)
    }
}

/// One query's scans over a table: the jumps of [`JpsPlusTable::search`], goal-aware.
struct Scan<'a> {
    /// The table's entries, one row of 8 codes per cell.
    table: &'a [[u8; 8]],
    /// The escape length `E` (module docs).
    escape: u8,
    /// `E` as a step count.
    esc: i64,
    /// Grid columns (cell index = `r * cols + c`).
    cols: i64,
    /// The goal cell (row, column).
    goal: (i64, i64),
}

impl Scan<'_> {
    /// The decoded entry of cell (r, c) in direction `k`.
    #[inline(always)]
    fn entry(&self, r: i64, c: i64, k: usize) -> Entry {
        // Codes are checked when built or loaded; an impossible one reads as a wall.
        decode(self.table[(r * self.cols + c) as usize][k], self.escape).unwrap_or(Entry::Wall(0))
    }

    /// How many cells one entry lets the scan examine.
    #[inline(always)]
    fn reach(&self, e: Entry) -> i64 {
        match e {
            Entry::Wall(w) => i64::from(w),
            Entry::Jump(k) => i64::from(k),
            Entry::Escape => self.esc,
        }
    }

    /// True if the straight scan from (r, c) along `DIRS[k]` examines the cell `t` steps on.
    #[inline(always)]
    fn straight_reaches(&self, mut r: i64, mut c: i64, k: usize, mut t: i64) -> bool {
        if t < 1 {
            return false;
        }
        let (dr, dc) = DIRS[k];
        loop {
            match self.entry(r, c, k) {
                Entry::Escape if t > self.esc => {
                    r += self.esc * dr;
                    c += self.esc * dc;
                    t -= self.esc;
                }
                e => return t <= self.reach(e),
            }
        }
    }

    /// A jump point found: its entry is read now, so that the memory access overlaps the
    /// offer's own (the entry is needed again if the point is expanded).
    #[inline(always)]
    fn found(&self, r: i64, c: i64) -> Option<(i64, i64)> {
        std::hint::black_box(self.table[(r * self.cols + c) as usize]);
        Some((r, c))
    }

    /// The jump point the scan from (r, c) along (dr, dc) stops at (the goal included), if any.
    #[inline(always)]
    fn jump(&self, r: i64, c: i64, dr: i64, dc: i64) -> Option<(i64, i64)> {
        if dr == 0 || dc == 0 {
            self.jump_straight(r, c, dr, dc)
        } else {
            self.jump_diagonal(r, c, dr, dc)
        }
    }

    /// A straight scan: the next table jump point, or the goal if the scan passes over it.
    #[inline(always)]
    fn jump_straight(&self, mut r: i64, mut c: i64, dr: i64, dc: i64) -> Option<(i64, i64)> {
        let k = dir_index(dr, dc);
        let (gr, gc) = self.goal;
        loop {
            let e = self.entry(r, c, k);
            let t = if dr == 0 {
                (gr == r).then(|| (gc - c) * dc)
            } else {
                (gc == c).then(|| (gr - r) * dr)
            };
            if let Some(t) = t
                && t >= 1
                && t <= self.reach(e)
            {
                return self.found(gr, gc);
            }
            match e {
                Entry::Jump(s) => {
                    let s = i64::from(s);
                    return self.found(r + s * dr, c + s * dc);
                }
                Entry::Wall(_) => return None,
                Entry::Escape => {
                    r += self.esc * dr;
                    c += self.esc * dc;
                }
            }
        }
    }

    /// A diagonal scan: the first of the table's jump point, the goal, and a cell in the goal's
    /// row or column whose straight scan reaches the goal.
    #[inline(always)]
    fn jump_diagonal(&self, mut r: i64, mut c: i64, dr: i64, dc: i64) -> Option<(i64, i64)> {
        let k = dir_index(dr, dc);
        let (gr, gc) = self.goal;
        let (vert, horiz) = (dir_index(dr, 0), dir_index(0, dc));
        loop {
            let e = self.entry(r, c, k);
            let limit = self.reach(e);
            let mut best = match e {
                Entry::Jump(s) => Some(i64::from(s)),
                _ => None,
            };
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
                if self.straight_reaches(qr, qc, vert, (gr - qr) * dr) {
                    consider(i_col);
                }
            }
            if i_row >= 1 && i_row <= limit {
                let (qr, qc) = (r + i_row * dr, c + i_row * dc);
                if self.straight_reaches(qr, qc, horiz, (gc - qc) * dc) {
                    consider(i_row);
                }
            }
            if let Some(i) = best {
                return self.found(r + i * dr, c + i * dc);
            }
            if e != Entry::Escape {
                return None;
            }
            r += self.esc * dr;
            c += self.esc * dc;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Planner;
    use crate::oracle::dijkstra_exact;
    use proptest::prelude::*;
    use skyplan_cspace::GridFrame;

    #[test]
    fn codes_round_trip() {
        for escape in [1u8, 2, 5, ESCAPE_CELLS] {
            for w in 0..=escape {
                assert_eq!(decode(w, escape), Some(Entry::Wall(w)));
            }
            for k in 1..=escape {
                assert_eq!(decode(JUMP_BASE + k - 1, escape), Some(Entry::Jump(k)));
            }
            assert_eq!(decode(ESCAPE_TO_WALL, escape), Some(Entry::Escape));
            assert_eq!(decode(ESCAPE_TO_JUMP, escape), Some(Entry::Escape));
            assert_eq!(extend(escape, escape), ESCAPE_TO_WALL);
            assert_eq!(extend(JUMP_BASE + escape - 1, escape), ESCAPE_TO_JUMP);
        }
        assert_eq!(decode(3, 2), None);
        assert_eq!(decode(JUMP_BASE + 2, 2), None);
    }

    /// An open 1 × 300 corridor: the scans from its west end escape twice (E = 126) before the
    /// wall, and the goal at its far end is still found.
    #[test]
    fn long_corridors_escape() {
        let g = Arc::new(Grid2::new(1, 300, vec![false; 300], GridFrame::default()).expect("grid"));
        let t = JpsPlusTable::build(Arc::clone(&g), MoveModel::Octile);
        let east = dir_index(0, 1);
        assert_eq!(t.table[0][east], ESCAPE_TO_WALL);
        assert_eq!(t.table[299 - 126][east], 126);
        let path = t
            .search(&mut GridSearch::new(), Cell::new(0, 0), Cell::new(0, 299))
            .expect("path");
        assert_eq!(path.cost_cells(), 299.0);
    }

    /// A direction's code is 0 exactly when the neighbour that way is blocked or off the grid
    /// (the search reads free-neighbour masks from the table).
    #[test]
    fn zero_codes_are_the_blocked_neighbours() {
        let g = Grid2::from_ascii("..#..\n.#...\n....#\n#....").expect("grid");
        for model in [MoveModel::Octile, MoveModel::OctileCornerCutting] {
            let t = JpsPlusTable::build_with_escape(Arc::new(g.clone()), model, 2);
            let view = View::new(&g, Cell::new(0, 0), model);
            for (i, entry) in t.table.iter().enumerate() {
                let (r, c) = (i as i64 / view.cols, i as i64 % view.cols);
                for (k, &code) in entry.iter().enumerate() {
                    let free = view.neighbour_mask(r, c) & (1 << k) != 0;
                    assert_eq!(code != 0, free, "cell {i} direction {k}");
                }
            }
        }
    }

    fn grid_strategy() -> impl Strategy<Value = Grid2> {
        (1u32..24, 1u32..24, 0.0f64..0.4).prop_flat_map(|(rows, cols, density)| {
            proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize)
                .prop_map(move |b| Grid2::new(rows, cols, b, GridFrame::default()).expect("size"))
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(600))]

        /// With escape lengths of 1–4 cells nearly every scan escapes at least once: the
        /// paths are still exactly JPS's, and the costs the exact oracle's.
        #[test]
        fn tiny_escapes_answer_exactly_like_jps(
            grid in grid_strategy(),
            escape in 1u8..5,
            ends in proptest::collection::vec((0u32..24, 0u32..24, 0u32..24, 0u32..24), 1..4),
        ) {
            let g = Arc::new(grid);
            let (rows, cols) = (g.rows(), g.cols());
            let mut search = GridSearch::new();
            let mut online = GridSearch::new();
            for model in [MoveModel::Octile, MoveModel::OctileCornerCutting] {
                let t = JpsPlusTable::build_with_escape(Arc::clone(&g), model, escape);
                for &(a, b, c, d) in &ends {
                    let (s, e) = (Cell::new(a % rows, b % cols), Cell::new(c % rows, d % cols));
                    let got = t.search(&mut search, s, e);
                    prop_assert_eq!(&got, &online.search(&g, s, e, model, Planner::Jps), "{:?}", model);
                    let truth = dijkstra_exact(&g, s, e, model);
                    prop_assert_eq!(got.ok().map(|p| p.cost_cells()), truth.map(|c| c.to_f64()));
                }
            }
        }

        /// With landmarks the heuristic is tighter and the cost is still the oracle's, on a
        /// valid path from the start to the goal.
        #[test]
        fn landmarks_keep_the_optimal_cost(
            grid in grid_strategy(),
            count in 1usize..6,
            ends in proptest::collection::vec((0u32..24, 0u32..24, 0u32..24, 0u32..24), 1..5),
        ) {
            let g = Arc::new(grid);
            let (rows, cols) = (g.rows(), g.cols());
            let mut search = GridSearch::new();
            for model in [MoveModel::Octile, MoveModel::OctileCornerCutting] {
                let t = JpsPlusTable::build_with_escape(Arc::clone(&g), model, 3);
                t.add_landmarks(count);
                for &(a, b, c, d) in &ends {
                    let (s, e) = (Cell::new(a % rows, b % cols), Cell::new(c % rows, d % cols));
                    let got = t.search(&mut search, s, e);
                    let truth = dijkstra_exact(&g, s, e, model);
                    prop_assert_eq!(got.as_ref().ok().map(|p| p.cost_cells()), truth.map(|c| c.to_f64()), "{:?}", model);
                    if let Ok(p) = got {
                        prop_assert_eq!((p.cells.first(), p.cells.last()), (Some(&s), Some(&e)));
                        prop_assert!(crate::check_path(&g, &p.cells, model).is_ok());
                    }
                }
            }
        }
    }
}
