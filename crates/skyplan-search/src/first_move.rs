//! First-move tables: for every pair of free cells, the first move of a shortest path from one
//! to the other — the uncompressed form of the compressed path databases (Botea, "Ultra-Fast
//! Optimal Pathfinding without Runtime Search", AIIDE 2011; SRC, a winner of the optimal track of
//! the Grid-Based Path Planning Competition 2014). A query searches nothing: it follows the
//! table's moves from the start, one lookup per cell of the path.
//!
//! * **Build.** One exact Dijkstra search from every free cell `t` (integer costs
//!   [`crate::CH_STRAIGHT_COST`] / [`crate::CH_DIAGONAL_COST`], ordered exactly like `1` / `√2`)
//!   gives the shortest-path tree towards `t`; each cell's entry is the move to its parent in
//!   that tree. Moves are symmetric under every [`MoveModel`], so the tree of searches *from*
//!   `t` is the tree of shortest paths *to* `t`. The searches run on every core
//!   (`std::thread::scope`), one target row per search.
//! * **Layout.** Row `t` holds, for every cell `s` of the grid (row-major), 4 bits: the move
//!   index (0–7, straight moves first), [`AT_TARGET`] for `t` itself, or [`UNREACHABLE`]
//!   (blocked cells too). A query reads one row only and steps by a constant offset per move.
//! * **Size.** Half a byte per cell for each of the `n` free cells: 6.4 MB for den312d's 2,445
//!   free of 5,265 cells; the build makes `n` searches over `n` cells. That is why it is for
//!   small maps ([`FirstMoveTable::bytes_for`] tells a caller beforehand).

use crate::astar::check_endpoints;
use crate::contraction::{DIAGONAL, NONE, STRAIGHT};
use crate::{GridPath, MoveModel, SearchError};
use skyplan_cspace::{Cell, Grid2};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

/// The entry of the target itself.
pub const AT_TARGET: u8 = 8;
/// The entry of a cell from which the target cannot be reached.
pub const UNREACHABLE: u8 = 15;

/// The eight moves: (row step, column step), straight ones first (index < 4 is straight).
pub(crate) const MOVES: [(i32, i32); 8] = [
    (-1, 0),
    (1, 0),
    (0, -1),
    (0, 1),
    (-1, -1),
    (-1, 1),
    (1, -1),
    (1, 1),
];

/// The index of the opposite move in [`MOVES`].
const OPPOSITE: [u8; 8] = [1, 0, 3, 2, 7, 6, 5, 4];

/// Why a first-move table was not built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FirstMoveError {
    /// The table would hold more than the caller allows.
    #[error(
        "a first-move table of this grid's {free} free cells takes {:.1} MB, more than the {:.1} MB allowed; \
         it is for small maps (its size grows with the square of the free cells)",
        *bytes as f64 / 1e6, *max as f64 / 1e6
    )]
    TooLarge {
        /// Free cells of the grid.
        free: usize,
        /// Bytes the table would take.
        bytes: u64,
        /// Bytes allowed.
        max: u64,
    },
    /// The deadline passed during preprocessing.
    #[error("first-move table preprocessing passed its deadline after {done} of {free} searches")]
    Deadline {
        /// Target rows finished.
        done: usize,
        /// Free cells (rows) in all.
        free: usize,
    },
}

/// The first moves of shortest paths between all pairs of free cells of one grid (module docs),
/// owning its grid so a session can keep it.
#[derive(Debug)]
pub struct FirstMoveTable {
    pub(crate) grid: Arc<Grid2>,
    pub(crate) model: MoveModel,
    /// The free cells (rows of the table), by row-major cell index.
    pub(crate) targets: Vec<u32>,
    /// The table's row of each cell, or `NONE` when the cell is blocked.
    pub(crate) row_of: Vec<u32>,
    /// Per cell, a bit per move of [`MOVES`] the move model allows from it (none from blocked
    /// cells): what a query checks every step against.
    pub(crate) allowed: Vec<u8>,
    /// One row per free target cell, [`FirstMoveTable::row_bytes`] bytes each: an entry per
    /// cell of the grid (blocked ones [`UNREACHABLE`]), two per byte (the even-indexed cell in
    /// the low 4 bits). Indexing by cell rather than by free cell lets a query step by a
    /// constant offset per move, with no lookup but the entry.
    pub(crate) moves: Vec<u8>,
}

/// The free cells of a grid, numbered in row-major order, and the moves between them.
pub(crate) struct FreeCells {
    pub index_of: Vec<u32>,
    pub cell_of: Vec<u32>,
    pub next: Vec<[u32; 8]>,
}

impl FreeCells {
    /// Per cell, a bit per allowed move ([`FirstMoveTable`]'s `allowed`).
    pub(crate) fn allowed(&self) -> Vec<u8> {
        let mut allowed = vec![0u8; self.index_of.len()];
        for (&cell, next) in self.cell_of.iter().zip(&self.next) {
            allowed[cell as usize] = (next.iter().enumerate())
                .fold(0u8, |bits, (k, &v)| bits | (u8::from(v != NONE) << k));
        }
        allowed
    }
}

impl FreeCells {
    pub(crate) fn of(grid: &Grid2, model: MoveModel) -> Self {
        let (rows, cols) = (grid.rows() as i32, grid.cols() as i32);
        let blocked = grid.blocked_cells();
        let mut index_of = vec![NONE; blocked.len()];
        let mut cell_of = Vec::new();
        for (i, &b) in blocked.iter().enumerate() {
            if !b {
                index_of[i] = cell_of.len() as u32;
                cell_of.push(i as u32);
            }
        }
        let free = |r: i32, c: i32| {
            r >= 0 && c >= 0 && r < rows && c < cols && !blocked[(r * cols + c) as usize]
        };
        let moves = if model.has_diagonals() { 8 } else { 4 };
        let next = (cell_of.iter())
            .map(|&i| {
                let (r, c) = (i as i32 / cols, i as i32 % cols);
                let mut out = [NONE; 8];
                for (k, &(dr, dc)) in MOVES.iter().enumerate().take(moves) {
                    let corner = k < 4
                        || model == MoveModel::OctileCornerCutting
                        || (free(r + dr, c) && free(r, c + dc));
                    if free(r + dr, c + dc) && corner {
                        out[k] = index_of[((r + dr) * cols + c + dc) as usize];
                    }
                }
                out
            })
            .collect();
        Self {
            index_of,
            cell_of,
            next,
        }
    }
}

impl FirstMoveTable {
    /// Bytes of the table of a grid of `cells` cells, `free` of them free: half a byte per
    /// cell for every free target.
    ///
    /// ```
    /// use skyplan_search::FirstMoveTable;
    /// assert_eq!(FirstMoveTable::bytes_for(5_265, 2_445), 2_445 * 2_633); // den312d: 6.4 MB
    /// ```
    pub fn bytes_for(cells: usize, free: usize) -> u64 {
        free as u64 * cells.div_ceil(2) as u64
    }

    /// Builds the table of `grid` under `model`, refusing with [`FirstMoveError::TooLarge`] a
    /// table over `max_bytes`.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_search::{FirstMoveTable, GridSearch, MoveModel, Planner};
    /// use std::sync::Arc;
    /// let grid = Arc::new(Grid2::from_ascii("......\n.####.\n......\n###...")?);
    /// let table = FirstMoveTable::build(Arc::clone(&grid), MoveModel::Octile, 1 << 20)?;
    /// assert_eq!(table.table_bytes(), 17 * 12 + 4 * (24 + 17));
    /// let (a, b) = (Cell::new(0, 2), Cell::new(3, 3));
    /// let path = table.search(a, b)?;
    /// let reference = GridSearch::new().search(&grid, a, b, MoveModel::Octile, Planner::AStar)?;
    /// assert_eq!(path.cost_cells(), reference.cost_cells());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn build(
        grid: Arc<Grid2>,
        model: MoveModel,
        max_bytes: u64,
    ) -> Result<Self, FirstMoveError> {
        Self::build_until(grid, model, max_bytes, None)
    }

    /// [`FirstMoveTable::build`] that gives up with [`FirstMoveError::Deadline`] once
    /// `deadline` has passed (checked before every search).
    pub fn build_until(
        grid: Arc<Grid2>,
        model: MoveModel,
        max_bytes: u64,
        deadline: Option<Instant>,
    ) -> Result<Self, FirstMoveError> {
        let free = grid.blocked_cells().iter().filter(|&&b| !b).count();
        let bytes = Self::bytes_for(grid.len(), free);
        if bytes > max_bytes {
            return Err(FirstMoveError::TooLarge {
                free,
                bytes,
                max: max_bytes,
            });
        }
        let cells = FreeCells::of(&grid, model);
        let n = cells.cell_of.len();
        let row_bytes = grid.len().div_ceil(2);
        let mut moves = vec![0u8; row_bytes * n];
        let threads = std::thread::available_parallelism()
            .map_or(1, |t| t.get())
            .clamp(1, 8);
        // Rows are handed out one at a time from a shared counter, so the threads finish
        // together whatever the rows cost.
        let taken = AtomicUsize::new(0);
        let late = AtomicBool::new(false);
        if row_bytes > 0 {
            let rows: Vec<&mut [u8]> = moves.chunks_mut(row_bytes).collect();
            let rows = std::sync::Mutex::new(rows.into_iter().enumerate());
            std::thread::scope(|scope| {
                for _ in 0..threads {
                    scope.spawn(|| {
                        let mut dijkstra = Dijkstra::new(n);
                        loop {
                            if late.load(Ordering::Relaxed) {
                                return;
                            }
                            if deadline.is_some_and(|d| Instant::now() >= d) {
                                late.store(true, Ordering::Relaxed);
                                return;
                            }
                            let next = rows.lock().ok().and_then(|mut r| r.next());
                            let Some((t, row)) = next else { return };
                            dijkstra.row(&cells, t as u32, row);
                            taken.fetch_add(1, Ordering::Relaxed);
                        }
                    });
                }
            });
        }
        if late.load(Ordering::Relaxed) {
            return Err(FirstMoveError::Deadline {
                done: taken.load(Ordering::Relaxed),
                free: n,
            });
        }
        Ok(Self::from_parts(grid, model, cells, moves))
    }

    /// The table of `grid`'s free `cells` with its rows `moves` (built, or read from a file).
    pub(crate) fn from_parts(
        grid: Arc<Grid2>,
        model: MoveModel,
        cells: FreeCells,
        moves: Vec<u8>,
    ) -> Self {
        Self {
            grid,
            model,
            allowed: cells.allowed(),
            targets: cells.cell_of,
            row_of: cells.index_of,
            moves,
        }
    }

    /// The grid this table was built for.
    pub fn grid(&self) -> &Arc<Grid2> {
        &self.grid
    }

    /// The move model it was built for.
    pub fn model(&self) -> MoveModel {
        self.model
    }

    /// The free cells (the table's rows).
    pub fn free_cells(&self) -> usize {
        self.targets.len()
    }

    /// Bytes of one target's row: half a byte per cell of the grid.
    pub fn row_bytes(&self) -> usize {
        self.grid.len().div_ceil(2)
    }

    /// Bytes held: the moves, and 4 bytes per cell and per free cell to number the rows.
    pub fn table_bytes(&self) -> usize {
        self.moves.len() + 4 * (self.row_of.len() + self.targets.len())
    }

    /// The entry for source `s` in a target's row.
    #[inline]
    fn entry(row: &[u8], s: usize) -> u8 {
        (row[s >> 1] >> ((s & 1) * 4)) & 15
    }

    /// A shortest path from `start` to `goal` (the table's move model): one lookup per cell.
    pub fn search(&self, start: Cell, goal: Cell) -> Result<GridPath, SearchError> {
        check_endpoints(&self.grid, start, goal)?;
        let cols = self.grid.cols() as usize;
        let s = start.row as usize * cols + start.col as usize;
        let t_cell = goal.row as usize * cols + goal.col as usize;
        let t = self.row_of[t_cell] as usize;
        let row_bytes = self.row_bytes();
        let row = &self.moves[t * row_bytes..][..row_bytes];
        if Self::entry(row, s) == UNREACHABLE {
            return Err(SearchError::Unreachable { expansions: 0 });
        }
        // The path is a chain of dependent reads in the target's row; when the row is not in
        // the cache each would wait for memory in turn. Reading one byte per cache line of the
        // part of the row between the two ends' grid rows first (independent reads, which the
        // processor overlaps) brings those lines in together.
        let (lo, hi) = (
            s.min(t_cell).saturating_sub(cols),
            (s.max(t_cell) + cols).min(row.len() * 2),
        );
        let touched = (row[lo / 2..hi.div_ceil(2)].iter().step_by(64)).fold(0u8, |a, &b| a ^ b);
        std::hint::black_box(touched);
        // The octile distance is a lower bound on the cells to come; paths on the maps the
        // table is for are rarely twice as long.
        let span = start
            .row
            .abs_diff(goal.row)
            .max(start.col.abs_diff(goal.col)) as usize;
        let mut cells = Vec::with_capacity(2 * span + 16);
        cells.push(start);
        let (mut straight, mut diagonal) = (0u64, 0u64);
        let (mut r, mut c, mut at) = (start.row, start.col, s);
        let most = self.targets.len();
        loop {
            let m = Self::entry(row, at) as usize;
            if m >= AT_TARGET as usize {
                if m == AT_TARGET as usize && (r, c) == (goal.row, goal.col) {
                    break;
                }
                return Err(damaged(
                    r,
                    c,
                    "a cell on the way is marked unreachable or as the target",
                ));
            }
            // Every step is checked (one byte read): a table loaded from a file leads only over
            // free cells by moves the model allows, whatever the file holds.
            if self.allowed[at] >> m & 1 == 0 || cells.len() > most {
                return Err(damaged(
                    r,
                    c,
                    "a move the move model does not allow there, or a cycle",
                ));
            }
            let (dr, dc) = MOVES[m];
            let (nr, nc) = (r.wrapping_add_signed(dr), c.wrapping_add_signed(dc));
            if m < 4 {
                straight += 1;
            } else {
                diagonal += 1;
            }
            (r, c) = (nr, nc);
            at = at.wrapping_add_signed(dr as isize * cols as isize + dc as isize);
            cells.push(Cell::new(r, c));
        }
        Ok(GridPath {
            cells,
            straight_moves: straight,
            diagonal_moves: diagonal,
            expansions: 0,
            any_angle_cells: None,
        })
    }
}

/// The error of a table that leads a path astray at (row `r`, column `c`).
fn damaged(r: u32, c: u32, what: &str) -> SearchError {
    SearchError::Damaged(format!(
        "the first-move table at row {r}, column {c}: {what}"
    ))
}

/// One thread's exact Dijkstra search, writing a target's row. Moves have two costs only, so
/// the open list is two first-in-first-out queues, one per cost: a cell enters a queue with the
/// cost of the cell just taken plus that queue's step, and cells are taken in order of cost, so
/// each queue stays sorted and the smaller of the two heads is the next cell (no heap).
struct Dijkstra {
    dist: Vec<u64>,
    queues: [Vec<(u64, u32)>; 2],
}

impl Dijkstra {
    fn new(n: usize) -> Self {
        Self {
            dist: vec![u64::MAX; n],
            queues: [Vec::new(), Vec::new()],
        }
    }

    /// Searches from `t` and writes every free cell's first move towards `t` into `row`.
    fn row(&mut self, cells: &FreeCells, t: u32, row: &mut [u8]) {
        let (next, cell_of) = (&cells.next, &cells.cell_of);
        self.dist.iter_mut().for_each(|d| *d = u64::MAX);
        row.iter_mut()
            .for_each(|b| *b = UNREACHABLE << 4 | UNREACHABLE);
        let set = |row: &mut [u8], s: u32, m: u8| {
            let i = cell_of[s as usize];
            let b = &mut row[(i >> 1) as usize];
            let shift = (i & 1) * 4;
            *b = (*b & !(15 << shift)) | (m << shift);
        };
        set(row, t, AT_TARGET);
        self.dist[t as usize] = 0;
        let [straight, diagonal] = &mut self.queues;
        straight.clear();
        diagonal.clear();
        let (mut hs, mut hd) = (0usize, 0usize);
        let mut current = Some((0u64, t));
        while let Some((d, u)) = current {
            if d == self.dist[u as usize] {
                for (k, &v) in next[u as usize].iter().enumerate() {
                    if v == NONE {
                        continue;
                    }
                    let nd = d + if k < 4 { STRAIGHT } else { DIAGONAL };
                    if nd < self.dist[v as usize] {
                        self.dist[v as usize] = nd;
                        // From v, the first move towards t is back along this move.
                        set(row, v, OPPOSITE[k]);
                        if k < 4 {
                            straight.push((nd, v));
                        } else {
                            diagonal.push((nd, v));
                        }
                    }
                }
            }
            current = match (straight.get(hs), diagonal.get(hd)) {
                (Some(&a), Some(&b)) if b.0 < a.0 => {
                    hd += 1;
                    Some(b)
                }
                (Some(&a), _) => {
                    hs += 1;
                    Some(a)
                }
                (None, Some(&b)) => {
                    hd += 1;
                    Some(b)
                }
                (None, None) => None,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::dijkstra_exact;

    fn random_grid(rows: u32, cols: u32, seed: u64, density: u64) -> Grid2 {
        let mut state = seed;
        let text: Vec<String> = (0..rows)
            .map(|_| {
                (0..cols)
                    .map(|_| {
                        state = state
                            .wrapping_mul(6_364_136_223_846_793_005)
                            .wrapping_add(1_442_695_040_888_963_407);
                        if (state >> 33) % 100 < density {
                            '#'
                        } else {
                            '.'
                        }
                    })
                    .collect()
            })
            .collect();
        Grid2::from_ascii(&text.join("\n")).unwrap()
    }

    #[test]
    fn every_pair_matches_the_oracle_in_every_move_model() {
        for model in [
            MoveModel::Octile,
            MoveModel::OctileCornerCutting,
            MoveModel::FourConnected,
        ] {
            for seed in 0..4 {
                let grid = Arc::new(random_grid(9, 11, seed, 30));
                let table = FirstMoveTable::build(Arc::clone(&grid), model, 1 << 20).unwrap();
                let free: Vec<Cell> = (0..grid.rows())
                    .flat_map(|r| (0..grid.cols()).map(move |c| Cell::new(r, c)))
                    .filter(|&c| !grid.is_blocked(c))
                    .collect();
                for &a in &free {
                    for &b in &free {
                        let oracle = dijkstra_exact(&grid, a, b, model);
                        match (table.search(a, b), oracle) {
                            (Ok(p), Some(o)) => {
                                assert_eq!(
                                    (p.straight_moves, p.diagonal_moves),
                                    (o.straight, o.diagonal),
                                    "{model:?} {a:?} {b:?}"
                                );
                                crate::check_path(&grid, &p.cells, model).unwrap();
                                assert_eq!((p.cells[0], *p.cells.last().unwrap()), (a, b));
                            }
                            (Err(SearchError::Unreachable { .. }), None) => {}
                            (got, want) => {
                                panic!("{model:?} {a:?} {b:?}: {got:?} against {want:?}")
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn too_large_and_late_tables_are_refused() {
        let grid = Arc::new(random_grid(20, 20, 7, 20));
        let err = FirstMoveTable::build(Arc::clone(&grid), MoveModel::Octile, 100).unwrap_err();
        assert!(
            matches!(err, FirstMoveError::TooLarge { max: 100, .. }),
            "{err}"
        );
        let past = Instant::now() - std::time::Duration::from_millis(1);
        let err = FirstMoveTable::build_until(grid, MoveModel::Octile, 1 << 20, Some(past));
        assert!(matches!(err, Err(FirstMoveError::Deadline { done: 0, .. })));
    }
}
