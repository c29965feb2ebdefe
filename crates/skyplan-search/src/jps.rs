//! Jump Point Search (Harabor & Grastien 2011) for uniform-cost octile grids, in both corner
//! rules: without corner cutting (a diagonal needs both orthogonal cells free; the MovingAI rule)
//! and with it (the diagonal target alone must be free; the FCND rule).
//!
//! JPS skips the symmetric paths of uniform-cost grids: from each expanded node it scans in the
//! pruned directions until it meets a cell with a forced neighbour (a *jump point*) and only
//! pushes those. Costs are exactly those of A\*; the tests compare both with the exact oracle.

use crate::astar::NO_PARENT;
use crate::bits::BlockGrid;
use crate::{GridPath, GridSearch, MoveModel, SearchError};
use skyplan_cspace::{Cell, Grid2};
use std::f64::consts::SQRT_2;

/// Read-only view of the grid with signed, bounds-checked access.
pub(crate) struct View<'a> {
    pub(crate) blocked: &'a [bool],
    pub(crate) rows: i64,
    pub(crate) cols: i64,
    pub(crate) goal: (i64, i64),
    pub(crate) corner_cutting: bool,
}

impl<'a> View<'a> {
    pub(crate) fn new(grid: &'a Grid2, goal: Cell, model: MoveModel) -> Self {
        View {
            blocked: grid.blocked_cells(),
            rows: i64::from(grid.rows()),
            cols: i64::from(grid.cols()),
            goal: (i64::from(goal.row), i64::from(goal.col)),
            corner_cutting: model == MoveModel::OctileCornerCutting,
        }
    }

    #[inline(always)]
    pub(crate) fn free(&self, r: i64, c: i64) -> bool {
        r >= 0
            && c >= 0
            && r < self.rows
            && c < self.cols
            && !self.blocked[(r * self.cols + c) as usize]
    }

    /// True if a straight scan along `(dr, dc)` must stop at the free cell `(r, c)`: it has a
    /// neighbour that only a turn here reaches optimally.
    #[inline]
    pub(crate) fn forced_straight(&self, r: i64, c: i64, dr: i64, dc: i64) -> bool {
        if dc != 0 {
            if self.corner_cutting {
                (self.free(r + 1, c + dc) && !self.free(r + 1, c))
                    || (self.free(r - 1, c + dc) && !self.free(r - 1, c))
            } else {
                (self.free(r + 1, c) && !self.free(r + 1, c - dc))
                    || (self.free(r - 1, c) && !self.free(r - 1, c - dc))
            }
        } else if self.corner_cutting {
            (self.free(r + dr, c + 1) && !self.free(r, c + 1))
                || (self.free(r + dr, c - 1) && !self.free(r, c - 1))
        } else {
            (self.free(r, c + 1) && !self.free(r - dr, c + 1))
                || (self.free(r, c - 1) && !self.free(r - dr, c - 1))
        }
    }

    /// With corner cutting, true if a diagonal scan must stop at `(r, c)` for a forced neighbour
    /// (never without corner cutting, where only the straight sub-scans stop it).
    #[inline]
    pub(crate) fn forced_diagonal(&self, r: i64, c: i64, dr: i64, dc: i64) -> bool {
        self.corner_cutting && forced_diagonal_at(|a, b| self.free(r + a, c + b), dr, dc)
    }

    /// True if a diagonal scan standing on `(r, c)` may take its next step.
    #[inline]
    pub(crate) fn diagonal_continues(&self, r: i64, c: i64, dr: i64, dc: i64) -> bool {
        self.corner_cutting || diagonal_continues_at(|a, b| self.free(r + a, c + b), dr, dc)
    }

    /// Bit `k` set iff the neighbour `DIRS[k]` of `(r, c)` is free.
    #[cfg(test)]
    pub(crate) fn neighbour_mask(&self, r: i64, c: i64) -> u8 {
        neighbour_mask_at(|a, b| self.free(r + a, c + b))
    }

    /// Scans straight from `(r, c)` (the first cell past the expanded node) along `(dr, dc)`,
    /// cell by cell: the reference the block scans are tested against.
    #[cfg(test)]
    fn jump_straight(&self, mut r: i64, mut c: i64, dr: i64, dc: i64) -> Option<(i64, i64)> {
        loop {
            if !self.free(r, c) {
                return None;
            }
            if (r, c) == self.goal {
                return Some((r, c));
            }
            let forced = self.forced_straight(r, c, dr, dc);
            if forced {
                return Some((r, c));
            }
            r += dr;
            c += dc;
        }
    }

    /// Scans from `(r, c)` along `(dr, dc)`, diagonal or straight, cell by cell (the reference
    /// of [`View::jump_blocks`]).
    #[cfg(test)]
    fn jump(&self, mut r: i64, mut c: i64, dr: i64, dc: i64) -> Option<(i64, i64)> {
        if dr == 0 || dc == 0 {
            return self.jump_straight(r, c, dr, dc);
        }
        loop {
            if !self.free(r, c) {
                return None;
            }
            if (r, c) == self.goal {
                return Some((r, c));
            }
            if self.forced_diagonal(r, c, dr, dc)
                || self.jump_straight(r + dr, c, dr, 0).is_some()
                || self.jump_straight(r, c + dc, 0, dc).is_some()
            {
                return Some((r, c));
            }
            if !self.diagonal_continues(r, c, dr, dc) {
                return None;
            }
            r += dr;
            c += dc;
        }
    }

    /// [`View::jump_straight`] 64 cells at a time on the grid's bits (the same stop).
    #[inline]
    fn jump_straight_blocks(
        &self,
        block: &mut BlockGrid,
        r: i64,
        c: i64,
        dr: i64,
        dc: i64,
    ) -> Option<(i64, i64)> {
        let (gr, gc) = self.goal;
        let cc = self.corner_cutting;
        if dc != 0 {
            let goal = (gr == r).then_some(gc);
            block
                .scan(self.blocked, false, r, c, dc, cc, goal)
                .map(|p| (r, p))
        } else {
            let goal = (gc == c).then_some(gr);
            block
                .scan(self.blocked, true, c, r, dr, cc, goal)
                .map(|p| (p, c))
        }
    }

    /// [`View::jump`] on the grid's bits: its straight scans (and those a diagonal scan makes
    /// at each step) 64 cells per step, and a diagonal scan's own tests on the bit rows (the
    /// rows of a 3 × 3 neighbourhood are adjacent words there, usually one cache line, not three
    /// rows of the grid).
    #[inline]
    fn jump_blocks(
        &self,
        block: &mut BlockGrid,
        mut r: i64,
        mut c: i64,
        dr: i64,
        dc: i64,
    ) -> Option<(i64, i64)> {
        if dr == 0 || dc == 0 {
            return self.jump_straight_blocks(block, r, c, dr, dc);
        }
        loop {
            if r < 0 || c < 0 || r >= self.rows || c >= self.cols {
                return None;
            }
            let around = block.around(self.blocked, r, c);
            if !around.free(0, 0) {
                return None;
            }
            if (r, c) == self.goal {
                return Some((r, c));
            }
            if (self.corner_cutting && forced_diagonal_at(|a, b| around.free(a, b), dr, dc))
                || self.jump_straight_blocks(block, r + dr, c, dr, 0).is_some()
                || self.jump_straight_blocks(block, r, c + dc, 0, dc).is_some()
            {
                return Some((r, c));
            }
            if !self.corner_cutting && !diagonal_continues_at(|a, b| around.free(a, b), dr, dc) {
                return None;
            }
            r += dr;
            c += dc;
        }
    }

    /// The pruned neighbour directions of `(r, c)` reached from its parent along `(dr, dc)`
    /// (`(0, 0)` for the start: every legal move).
    pub(crate) fn directions(&self, r: i64, c: i64, dr: i64, dc: i64, out: &mut Vec<(i64, i64)>) {
        out.clear();
        let f = |a: i64, b: i64| self.free(r + a, c + b);
        if dr == 0 && dc == 0 {
            for (a, b) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                if f(a, b) {
                    out.push((a, b));
                }
            }
            for (a, b) in [(1, 1), (1, -1), (-1, 1), (-1, -1)] {
                if f(a, b) && (self.corner_cutting || (f(a, 0) && f(0, b))) {
                    out.push((a, b));
                }
            }
            return;
        }
        if self.corner_cutting {
            if dr != 0 && dc != 0 {
                for (a, b, ok) in [
                    (dr, 0, f(dr, 0)),
                    (0, dc, f(0, dc)),
                    (dr, dc, f(dr, dc)),
                    (dr, -dc, !f(0, -dc) && f(dr, -dc)),
                    (-dr, dc, !f(-dr, 0) && f(-dr, dc)),
                ] {
                    if ok {
                        out.push((a, b));
                    }
                }
            } else if dc != 0 {
                for (a, b, ok) in [
                    (0, dc, f(0, dc)),
                    (1, dc, !f(1, 0) && f(1, dc)),
                    (-1, dc, !f(-1, 0) && f(-1, dc)),
                ] {
                    if ok {
                        out.push((a, b));
                    }
                }
            } else {
                for (a, b, ok) in [
                    (dr, 0, f(dr, 0)),
                    (dr, 1, !f(0, 1) && f(dr, 1)),
                    (dr, -1, !f(0, -1) && f(dr, -1)),
                ] {
                    if ok {
                        out.push((a, b));
                    }
                }
            }
            return;
        }
        if dr != 0 && dc != 0 {
            let (vert, horiz) = (f(dr, 0), f(0, dc));
            if vert {
                out.push((dr, 0));
            }
            if horiz {
                out.push((0, dc));
            }
            if vert && horiz && f(dr, dc) {
                out.push((dr, dc));
            }
        } else {
            // Straight along (dr, dc): the natural neighbour ahead, plus a side (and the diagonal
            // towards it) only when the cell behind that side is blocked, i.e. the side is forced.
            if f(dr, dc) {
                out.push((dr, dc));
            }
            let sides = if dc != 0 {
                [(1, 0), (-1, 0)]
            } else {
                [(0, 1), (0, -1)]
            };
            for (sr, sc) in sides {
                if f(sr, sc) && !f(sr - dr, sc - dc) {
                    out.push((sr, sc));
                    if f(dr, dc) && f(dr + sr, dc + sc) {
                        out.push((dr + sr, dc + sc));
                    }
                }
            }
        }
    }
}

/// With corner cutting, true if a diagonal scan along `(dr, dc)` must stop at a cell whose
/// neighbour at offset `(a, b)` is free iff `free(a, b)`.
#[inline(always)]
fn forced_diagonal_at(free: impl Fn(i64, i64) -> bool, dr: i64, dc: i64) -> bool {
    (free(-dr, dc) && !free(-dr, 0)) || (free(dr, -dc) && !free(0, -dc))
}

/// Without corner cutting, true if a diagonal scan along `(dr, dc)` may step on from a cell
/// whose neighbour at offset `(a, b)` is free iff `free(a, b)`.
#[inline(always)]
fn diagonal_continues_at(free: impl Fn(i64, i64) -> bool, dr: i64, dc: i64) -> bool {
    free(dr, 0) && free(0, dc)
}

/// Bit `k` set iff the neighbour `DIRS[k]` is free, given `free(a, b)` for the neighbour at
/// offset `(a, b)`.
#[inline(always)]
fn neighbour_mask_at(free: impl Fn(i64, i64) -> bool) -> u8 {
    DIRS.iter().enumerate().fold(
        0u8,
        |m, (k, &(a, b))| if free(a, b) { m | (1 << k) } else { m },
    )
}

/// The 8 directions as `(dr, dc)`, straight first; bit `k` of a direction set is `DIRS[k]`.
pub(crate) const DIRS: [(i64, i64); 8] = [
    (1, 0),
    (-1, 0),
    (0, 1),
    (0, -1),
    (1, 1),
    (1, -1),
    (-1, 1),
    (-1, -1),
];

/// Index of a direction in [`DIRS`].
#[inline(always)]
pub(crate) fn dir_index(dr: i64, dc: i64) -> usize {
    // (dr + 1) * 3 + (dc + 1) → index in DIRS.
    const LUT: [usize; 9] = [7, 1, 6, 3, usize::MAX, 2, 5, 0, 4];
    LUT[((dr + 1) * 3 + (dc + 1)) as usize]
}

/// Pruned directions (a bit set over [`DIRS`]) for every corner rule, incoming direction
/// (`(0, 0)` for the start) and 3 × 3 neighbourhood: [`View::directions`] evaluated once on each
/// of the 2 × 9 × 256 cases, so that the search pays one lookup per expansion.
type DirectionTable = [[[u8; 256]; 9]; 2];

fn direction_table() -> &'static DirectionTable {
    static TABLE: std::sync::OnceLock<Box<DirectionTable>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut table = Box::new([[[0u8; 256]; 9]; 2]);
        let mut out = Vec::with_capacity(8);
        for (cc, per_rule) in table.iter_mut().enumerate() {
            for (incoming, per_dir) in per_rule.iter_mut().enumerate() {
                let (dr, dc) = (incoming as i64 / 3 - 1, incoming as i64 % 3 - 1);
                for (mask, slot) in per_dir.iter_mut().enumerate() {
                    let mut blocked = [true; 9];
                    blocked[4] = false;
                    for (k, &(a, b)) in DIRS.iter().enumerate() {
                        if mask & (1 << k) != 0 {
                            blocked[((a + 1) * 3 + (b + 1)) as usize] = false;
                        }
                    }
                    let view = View {
                        blocked: &blocked,
                        rows: 3,
                        cols: 3,
                        goal: (-9, -9),
                        corner_cutting: cc == 1,
                    };
                    view.directions(1, 1, dr, dc, &mut out);
                    *slot = out
                        .iter()
                        .fold(0u8, |set, &(a, b)| set | (1 << dir_index(a, b)));
                }
            }
        }
        table
    })
}

/// The pruned directions of a cell with free-neighbour `mask`, entered along `(dr, dc)`.
#[inline(always)]
pub(crate) fn pruned_directions(corner_cutting: bool, dr: i64, dc: i64, mask: u8) -> u8 {
    direction_table()[usize::from(corner_cutting)][((dr + 1) * 3 + (dc + 1)) as usize]
        [usize::from(mask)]
}

/// Octile distance in cells between two cells of a straight or diagonal segment.
#[inline]
pub(crate) fn octile(dr: i64, dc: i64) -> f64 {
    let (a, b) = (dr.unsigned_abs(), dc.unsigned_abs());
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (hi - lo) as f64 + lo as f64 * SQRT_2
}

impl GridSearch {
    pub(crate) fn search_jps(
        &mut self,
        grid: &Grid2,
        start: Cell,
        goal: Cell,
        model: MoveModel,
    ) -> Result<GridPath, SearchError> {
        let mut block = std::mem::take(&mut self.block);
        block.begin(grid);
        let found = self.search_jps_on(&mut block, grid, start, goal, model);
        self.block = block;
        found
    }

    /// JPS with block scans on `block`, which began this query on `grid`.
    fn search_jps_on(
        &mut self,
        block: &mut BlockGrid,
        grid: &Grid2,
        start: Cell,
        goal: Cell,
        model: MoveModel,
    ) -> Result<GridPath, SearchError> {
        let view = View::new(grid, goal, model);
        // Both the expanded cell's neighbourhood and the jumps read the bits (one at a time).
        let block = std::cell::RefCell::new(block);
        self.jump_point_search(
            grid,
            (start, goal),
            &view,
            |r, c, _| {
                let around = block.borrow_mut().around(view.blocked, r, c);
                neighbour_mask_at(|a, b| around.free(a, b))
            },
            |r, c, a, b| view.jump_blocks(&mut block.borrow_mut(), r + a, c + b, a, b),
            |_| 0.0,
        )
    }

    /// The best-first loop shared by JPS and JPS+: `jump(r, c, dr, dc)` returns the next jump
    /// point from the expanded cell `(r, c)` along `(dr, dc)`; `lower(i)` is a lower bound on
    /// the distance from cell `i` to the goal, consistent (landmarks), or 0: the heuristic is
    /// its maximum with the octile distance. Endpoints are already checked.
    pub(crate) fn jump_point_search(
        &mut self,
        grid: &Grid2,
        (start, goal): (Cell, Cell),
        view: &View<'_>,
        neighbour_mask: impl Fn(i64, i64, usize) -> u8,
        mut jump: impl FnMut(i64, i64, i64, i64) -> Option<(i64, i64)>,
        lower: impl Fn(usize) -> f64,
    ) -> Result<GridPath, SearchError> {
        self.reset(grid, false);
        let cols = view.cols;
        let h = |r: i64, c: i64| {
            octile(r - view.goal.0, c - view.goal.1).max(lower((r * cols + c) as usize))
        };
        let start_i = grid.index(start) as u32;
        let goal_i = grid.index(goal) as u32;
        self.offer(
            start_i as usize,
            0.0,
            h(i64::from(start.row), i64::from(start.col)),
            NO_PARENT,
        );
        let mut expansions = 0u64;
        while let Some((g, index, ur, uc)) = self.expand_next_rc() {
            let i = index as usize;
            expansions += 1;
            if index == goal_i {
                let jump_points = self.reconstruct(grid, goal_i, expansions);
                return Ok(interpolate(jump_points));
            }
            let (r, c) = (ur as i64, uc as i64);
            let (dr, dc) = match self.parent(i) {
                NO_PARENT => (0, 0),
                p => {
                    let (pr, pc) = (i64::from(p) / cols, i64::from(p) % cols);
                    ((r - pr).signum(), (c - pc).signum())
                }
            };
            let mut set = pruned_directions(view.corner_cutting, dr, dc, neighbour_mask(r, c, i));
            while set != 0 {
                let (a, b) = DIRS[set.trailing_zeros() as usize];
                set &= set - 1;
                let Some((jr, jc)) = jump(r, c, a, b) else {
                    continue;
                };
                let ji = (jr * cols + jc) as usize;
                let step = g + octile(jr - r, jc - c);
                self.offer_rc((ji, jr as usize, jc as usize), step, || h(jr, jc), index);
            }
        }
        Err(SearchError::Unreachable { expansions })
    }
}

/// JPS prepared on one grid for many queries: the grid's bit rows and columns packed once. The
/// grid stays borrowed, so it cannot change under the bits and queries skip the check that
/// [`GridSearch::search`] makes of bits it kept from an earlier query (a read of the grid's
/// cells the scans read). Answers exactly what [`GridSearch::search`] with [`crate::Planner::Jps`]
/// answers.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_search::{BlockJps, GridSearch, MoveModel};
/// let grid = Grid2::from_ascii("....\n.##.\n....")?;
/// let mut jps = BlockJps::new(&grid, MoveModel::Octile);
/// let path = jps.search(&mut GridSearch::new(), Cell::new(0, 0), Cell::new(2, 3))?;
/// assert_eq!((path.straight_moves, path.diagonal_moves), (5, 0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct BlockJps<'g> {
    grid: &'g Grid2,
    model: MoveModel,
    block: BlockGrid,
}

impl<'g> BlockJps<'g> {
    /// Packs `grid`'s free cells for JPS under `model` (a 4-connected model runs A\*, as
    /// [`GridSearch::search`] does for JPS).
    pub fn new(grid: &'g Grid2, model: MoveModel) -> Self {
        let mut block = BlockGrid::default();
        if model.has_diagonals() {
            block.begin(grid);
        }
        BlockJps { grid, model, block }
    }

    /// An optimal path from `start` to `goal`, with `search`'s buffers; errors as
    /// [`GridSearch::search`]'s.
    pub fn search(
        &mut self,
        search: &mut GridSearch,
        start: Cell,
        goal: Cell,
    ) -> Result<GridPath, SearchError> {
        if !self.model.has_diagonals() {
            return search.search(self.grid, start, goal, self.model, crate::Planner::Jps);
        }
        crate::astar::check_endpoints(self.grid, start, goal)?;
        // No `begin`: every tile was checked when the bits were packed, and the grid is borrowed.
        search.search_jps_on(&mut self.block, self.grid, start, goal, self.model)
    }
}

/// Expands a path of jump points (each segment straight or diagonal) into every cell.
fn interpolate(jumps: GridPath) -> GridPath {
    let mut cells = Vec::with_capacity(jumps.cells.len() * 8);
    if let Some(&first) = jumps.cells.first() {
        cells.push(first);
    }
    for w in jumps.cells.windows(2) {
        let (mut r, mut c) = (i64::from(w[0].row), i64::from(w[0].col));
        let (tr, tc) = (i64::from(w[1].row), i64::from(w[1].col));
        while (r, c) != (tr, tc) {
            r += (tr - r).signum();
            c += (tc - c).signum();
            cells.push(Cell::new(r as u32, c as u32));
        }
    }
    let diagonal_moves = cells
        .windows(2)
        .filter(|w| w[0].row != w[1].row && w[0].col != w[1].col)
        .count() as u64;
    let straight_moves = cells.len() as u64 - 1 - diagonal_moves;
    GridPath {
        cells,
        straight_moves,
        diagonal_moves,
        expansions: jumps.expansions,
        any_angle_cells: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::dijkstra_exact;
    use proptest::prelude::*;
    use skyplan_cspace::GridFrame;

    /// Grids across 64-cell word edges (up to 2 words and a bit), open to cluttered.
    fn grid_strategy() -> impl Strategy<Value = Grid2> {
        (1u32..140, 1u32..140, 0.0f64..0.6).prop_flat_map(|(rows, cols, density)| {
            proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize)
                .prop_map(move |blocked| {
                    Grid2::new(rows, cols, blocked, GridFrame::default()).unwrap()
                })
        })
    }

    fn query_strategy() -> impl Strategy<Value = (Grid2, Vec<(Cell, Cell)>)> {
        grid_strategy().prop_flat_map(|g| {
            let (r, c) = (g.rows(), g.cols());
            let pair = (0..r, 0..c, 0..r, 0..c)
                .prop_map(|(a, b, x, y)| (Cell::new(a, b), Cell::new(x, y)));
            (Just(g), proptest::collection::vec(pair, 1..6))
        })
    }

    const MODELS: [MoveModel; 2] = [MoveModel::Octile, MoveModel::OctileCornerCutting];

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Block JPS against the exact Dijkstra oracle, several queries per grid on one
        /// workspace (the bits built once and reused): the oracle's move counts, a valid path,
        /// and an error exactly where the oracle finds no path.
        #[test]
        fn block_jps_is_optimal_on_grids_across_word_edges((grid, queries) in query_strategy()) {
            let mut search = GridSearch::new();
            for model in MODELS {
                for &(start, goal) in &queries {
                    let truth = dijkstra_exact(&grid, start, goal, model);
                    let found = search.search(&grid, start, goal, model, crate::Planner::Jps);
                    match (found, truth) {
                        (Ok(path), Some(cost)) => {
                            prop_assert_eq!(
                                (path.straight_moves, path.diagonal_moves),
                                (cost.straight, cost.diagonal)
                            );
                            prop_assert_eq!(path.cells.first(), Some(&start));
                            prop_assert_eq!(path.cells.last(), Some(&goal));
                            prop_assert_eq!(crate::check_path(&grid, &path.cells, model), Ok(()));
                        }
                        (Err(_), None) => {}
                        (got, want) => {
                            prop_assert!(false, "{model:?}: got {got:?}, oracle {want:?}")
                        }
                    }
                }
            }
        }

        /// From every free cell in all 8 directions, the block jump stops exactly where the
        /// cell-by-cell jump stops (straight and diagonal, both corner rules).
        #[test]
        fn block_jumps_equal_cell_jumps(grid in grid_strategy(), goal in (0u32..140, 0u32..140)) {
            let goal = Cell::new(goal.0 % grid.rows(), goal.1 % grid.cols());
            let mut block = BlockGrid::default();
            block.begin(&grid);
            for model in MODELS {
                let view = View::new(&grid, goal, model);
                for r in 0..view.rows {
                    for c in 0..view.cols {
                        if !view.free(r, c) {
                            continue;
                        }
                        for (a, b) in DIRS {
                            prop_assert_eq!(
                                view.jump_blocks(&mut block, r + a, c + b, a, b),
                                view.jump(r + a, c + b, a, b),
                                "from ({}, {}) along ({}, {}), {:?}", r, c, a, b, model
                            );
                        }
                    }
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(100))]

        /// A prepared [`BlockJps`] answers every query exactly as `GridSearch::search` does.
        #[test]
        fn prepared_block_jps_answers_like_grid_search((grid, queries) in query_strategy()) {
            let mut search = GridSearch::new();
            for model in [MoveModel::FourConnected, MoveModel::Octile, MoveModel::OctileCornerCutting] {
                let mut prepared = BlockJps::new(&grid, model);
                let mut own = GridSearch::new();
                for &(start, goal) in &queries {
                    prop_assert_eq!(
                        prepared.search(&mut own, start, goal),
                        search.search(&grid, start, goal, model, crate::Planner::Jps)
                    );
                }
            }
        }
    }

    /// One workspace, a grid edited between two queries: the second query sees the edit.
    #[test]
    fn an_edited_grid_is_searched_as_edited() {
        let open = Grid2::new(3, 70, vec![false; 210], GridFrame::default()).unwrap();
        let mut walled = vec![false; 210];
        for r in 0..3 {
            walled[r * 70 + 65] = true;
        }
        walled[2 * 70 + 65] = false;
        let walled = Grid2::new(3, 70, walled, GridFrame::default()).unwrap();
        let mut search = GridSearch::new();
        let (s, g) = (Cell::new(0, 0), Cell::new(0, 69));
        for (grid, walls) in [(&open, false), (&walled, true), (&open, false)] {
            let path = search
                .search(grid, s, g, MoveModel::Octile, crate::Planner::Jps)
                .unwrap();
            let truth = dijkstra_exact(grid, s, g, MoveModel::Octile).unwrap();
            assert_eq!((truth.straight, truth.diagonal) != (69, 0), walls);
            assert_eq!(
                (path.straight_moves, path.diagonal_moves),
                (truth.straight, truth.diagonal)
            );
        }
    }
}
