//! D\* Lite (Koenig & Likhachev 2002, the optimized version) on an 8-connected [`Grid2`].
//!
//! The search runs backwards, from the goal to the start, so that the start may move along the
//! path (`km` grows by the heuristic distance moved) and cell edits only repair what they change.
//! Moves and costs are exactly the grid planners' ([`MoveModel`]: octile costs, the same corner
//! rule as `skyplan-search`), so D\* Lite's cost equals A\*'s from scratch after every edit.

use skyplan_cspace::{Cell, Grid2, OutsideGrid};
use skyplan_search::{MoveModel, octile_cost};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Costs are integers: one straight move is 2⁴⁰, a diagonal `round(√2 · 2⁴⁰)`. Integer sums are
/// exact and associative, so keys and `g + c` comparisons never disagree by a rounding (floats
/// did: a stale g-value one ulp above the start's key was left in the queue and the path
/// extraction looped). The rounding of √2 (≤ 2⁻⁴¹ per diagonal) cannot reorder two paths of
/// fewer than about 10⁵ moves, whose exact costs differ by more than 10⁻⁶.
type Cost = i64;
const INF: Cost = i64::MAX;
const STRAIGHT: Cost = 1 << 40;
const DIAGONAL: Cost = 1_554_944_255_988;

/// Why a [`DStarLite`] cannot be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DStarError {
    /// The start or the goal cell is outside the grid.
    #[error("{which} {outside}")]
    Outside {
        /// `start` or `goal`.
        which: &'static str,
        /// The cell and the grid's size.
        outside: OutsideGrid,
    },
}

/// [`DStarLite::compute_within`] spent its expansions before the path was known.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("D* Lite spent its expansion budget before the path was known")]
pub struct BudgetSpent;

/// A path found by [`DStarLite::compute`].
#[derive(Debug, Clone, PartialEq)]
pub struct DStarPath {
    /// The cells, the current start first and the goal last.
    pub cells: Vec<Cell>,
    /// Orthogonal moves.
    pub straight_moves: u64,
    /// Diagonal moves.
    pub diagonal_moves: u64,
}

impl DStarPath {
    /// The cost in the search's integer units.
    fn units(&self) -> Cost {
        let s = i64::try_from(self.straight_moves).unwrap_or(INF);
        let d = i64::try_from(self.diagonal_moves).unwrap_or(INF);
        s.saturating_mul(STRAIGHT)
            .saturating_add(d.saturating_mul(DIAGONAL))
    }

    /// Cost in cells, `straight + √2 · diagonal` (the formula every grid planner uses).
    pub fn cost_cells(&self) -> f64 {
        octile_cost(self.straight_moves, self.diagonal_moves)
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Key(Cost, Cost);

impl Key {
    fn cmp(self, other: Key) -> Ordering {
        self.0.cmp(&other.0).then_with(|| self.1.cmp(&other.1))
    }
    fn lt(self, other: Key) -> bool {
        self.cmp(other) == Ordering::Less
    }
}

/// A heap entry; the heap is a min-heap on the key (stale entries are skipped on pop).
#[derive(Debug, Clone)]
struct Entry {
    key: Key,
    index: u32,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .key
            .cmp(self.key)
            .then_with(|| other.index.cmp(&self.index))
    }
}

/// Incremental shortest paths from a moving start to a fixed goal on a grid whose cells change.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_replan::DStarLite;
/// use skyplan_search::MoveModel;
/// let grid = Grid2::from_ascii(".....\n.....\n.....")?;
/// let mut d = DStarLite::new(&grid, Cell::new(1, 0), Cell::new(1, 4), MoveModel::Octile)?;
/// assert_eq!(d.compute().map(|p| p.cost_cells()), Some(4.0));
/// // A wall appears across the middle row: the way round costs two diagonals more.
/// d.update_cells(&[(Cell::new(1, 2), true)]);
/// let path = d.compute().expect("a way round");
/// assert_eq!((path.straight_moves, path.diagonal_moves), (2, 2));
/// // The vehicle moves on; the search is reused.
/// d.move_start(path.cells[1]);
/// assert!(d.compute().is_some());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct DStarLite {
    grid: Grid2,
    model: MoveModel,
    start: Cell,
    last: Cell,
    goal: Cell,
    km: Cost,
    g: Vec<Cost>,
    rhs: Vec<Cost>,
    /// The key a cell is queued with; `None` when it is not in the queue.
    queued: Vec<Option<Key>>,
    live: usize,
    heap: BinaryHeap<Entry>,
    expansions: u64,
}

impl DStarLite {
    /// A search on (a copy of) `grid` from `start` to `goal` under `model`. Nothing is searched
    /// until [`DStarLite::compute`].
    pub fn new(
        grid: &Grid2,
        start: Cell,
        goal: Cell,
        model: MoveModel,
    ) -> Result<Self, DStarError> {
        for (which, cell) in [("start", start), ("goal", goal)] {
            grid.check_contains(cell)
                .map_err(|outside| DStarError::Outside { which, outside })?;
        }
        let n = grid.len();
        let mut d = Self {
            grid: grid.clone(),
            model,
            start,
            last: start,
            goal,
            km: 0,
            g: vec![INF; n],
            rhs: vec![INF; n],
            queued: vec![None; n],
            live: 0,
            heap: BinaryHeap::new(),
            expansions: 0,
        };
        let gi = d.grid.index(goal);
        d.rhs[gi] = 0;
        let k = d.key(gi);
        d.push(gi, k);
        Ok(d)
    }

    /// The grid as edited so far.
    pub fn grid(&self) -> &Grid2 {
        &self.grid
    }

    /// The current start cell.
    pub fn start(&self) -> Cell {
        self.start
    }

    /// The goal cell.
    pub fn goal(&self) -> Cell {
        self.goal
    }

    /// Cells expanded (taken off the queue and made consistent) since the search was built.
    pub fn expansions(&self) -> u64 {
        self.expansions
    }

    /// Blocks (`true`) or frees (`false`) cells; cells outside the grid are ignored. Only the
    /// edges the edits touch are repaired, at the next [`DStarLite::compute`].
    pub fn update_cells(&mut self, edits: &[(Cell, bool)]) {
        let mut touched = Vec::with_capacity(edits.len() * 9);
        for &(cell, blocked) in edits {
            if !self.grid.contains(cell) || self.grid.is_blocked(cell) == blocked {
                continue;
            }
            self.grid.set_blocked(cell, blocked);
            // Every edge whose cost can change has an end in the 3 × 3 block around the cell:
            // the cell's own edges, and diagonals between two of its neighbours that pass its
            // corner.
            let (r, c) = (i64::from(cell.row), i64::from(cell.col));
            for dr in -1..=1 {
                for dc in -1..=1 {
                    if let Some(n) = self.grid.checked_cell(r + dr, c + dc) {
                        touched.push(self.grid.index(n));
                    }
                }
            }
        }
        touched.sort_unstable();
        touched.dedup();
        for i in touched {
            if i != self.grid.index(self.goal) {
                self.rhs[i] = self.best_successor(i).0;
            }
            self.update_vertex(i);
        }
    }

    /// The vehicle moved to `cell` (it need not be a neighbour of the old start).
    pub fn move_start(&mut self, cell: Cell) {
        if !self.grid.contains(cell) || cell == self.start {
            return;
        }
        self.start = cell;
        self.km = self.km.saturating_add(self.h(self.last, self.start));
        self.last = self.start;
    }

    /// Repairs the search and returns the shortest path from the start to the goal, or `None`
    /// if there is none (either end blocked, or walled off).
    pub fn compute(&mut self) -> Option<DStarPath> {
        self.compute_within(u64::MAX).unwrap_or(None)
    }

    /// [`DStarLite::compute`] that stops after `max_expansions` expansions with `Err` (the
    /// search stays valid: a later call goes on where this one stopped). For callers with a
    /// deadline, who then search from scratch for this once.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2, GridFrame};
    /// use skyplan_replan::DStarLite;
    /// use skyplan_search::MoveModel;
    /// let grid = Grid2::new(50, 50, vec![false; 2500], GridFrame::default())?;
    /// let mut d = DStarLite::new(&grid, Cell::new(0, 0), Cell::new(49, 49), MoveModel::Octile)?;
    /// assert!(d.compute_within(10).is_err());
    /// let path = d.compute_within(u64::MAX).expect("within budget").expect("a path");
    /// assert_eq!(path.diagonal_moves, 49);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn compute_within(
        &mut self,
        max_expansions: u64,
    ) -> Result<Option<DStarPath>, BudgetSpent> {
        if self.grid.is_blocked(self.start) || self.grid.is_blocked(self.goal) {
            return Ok(None);
        }
        let until = self.expansions.saturating_add(max_expansions);
        self.repair(false, until)?;
        let s = self.grid.index(self.start);
        Ok(match self.path() {
            Some(p) if p.units() == self.rhs[s] => Some(p),
            _ if self.rhs[s] == INF => None,
            _ => {
                // A state whose key ties the start's was left stale and the walk along g took
                // it: expand the ties too, then walk again.
                self.repair(true, until)?;
                self.path()
            }
        })
    }

    /// ComputeShortestPath of the optimized D\* Lite; with `ties`, also expands every state
    /// whose key equals the start's. Stops with `Err` when the expansions reach `until`.
    fn repair(&mut self, ties: bool, until: u64) -> Result<(), BudgetSpent> {
        let s = self.grid.index(self.start);
        while let Some((u, k_old)) = self.top() {
            let start_key = self.key(s);
            let more = if ties {
                !start_key.lt(k_old) || self.rhs[s] != self.g[s]
            } else {
                k_old.lt(start_key) || self.rhs[s] > self.g[s]
            };
            if !more {
                break;
            }
            if self.expansions >= until {
                return Err(BudgetSpent);
            }
            let k_new = self.key(u);
            if k_old.lt(k_new) {
                self.push(u, k_new);
            } else if self.g[u] > self.rhs[u] {
                self.g[u] = self.rhs[u];
                self.remove(u);
                self.expansions += 1;
                let gu = self.g[u];
                self.for_each_move(u, |d, p, cost| {
                    if p != d.grid.index(d.goal) {
                        let via = cost.saturating_add(gu);
                        if via < d.rhs[p] {
                            d.rhs[p] = via;
                        }
                    }
                    d.update_vertex(p);
                });
            } else {
                let g_old = self.g[u];
                self.g[u] = INF;
                self.expansions += 1;
                let goal = self.grid.index(self.goal);
                // rhs(u) does not depend on g(u) (no self-loops): only u's queue entry changes.
                self.update_vertex(u);
                self.for_each_move(u, |d, p, cost| {
                    if p != goal && d.rhs[p] == cost.saturating_add(g_old) {
                        d.rhs[p] = d.best_successor(p).0;
                    }
                    d.update_vertex(p);
                });
            }
        }
        Ok(())
    }

    /// Follows the best successors from the start to the goal.
    fn path(&self) -> Option<DStarPath> {
        let mut at = self.grid.index(self.start);
        if self.rhs[at] == INF {
            return None;
        }
        let goal = self.grid.index(self.goal);
        let mut cells = vec![self.start];
        let (mut straight, mut diagonal) = (0, 0);
        while at != goal {
            let (best, next) = self.best_successor(at);
            let next = next?;
            if best == INF || cells.len() > self.grid.len() {
                return None;
            }
            let (a, b) = (self.grid.cell(at), self.grid.cell(next));
            if a.row != b.row && a.col != b.col {
                diagonal += 1;
            } else {
                straight += 1;
            }
            cells.push(b);
            at = next;
        }
        Some(DStarPath {
            cells,
            straight_moves: straight,
            diagonal_moves: diagonal,
        })
    }

    /// `min over moves u → s' of c(u, s') + g(s')`, and the `s'` that attains it (first in the
    /// fixed neighbour order on ties).
    fn best_successor(&self, u: usize) -> (Cost, Option<usize>) {
        let mut best = (INF, None);
        self.moves(u, |s, cost| {
            let v = cost.saturating_add(self.g[s]);
            if v < best.0 {
                best = (v, Some(s));
            }
        });
        best
    }

    /// Calls `f(neighbour, cost)` for every legal move out of `u` (the grid is undirected, so
    /// these are also the moves into `u`).
    fn moves(&self, u: usize, mut f: impl FnMut(usize, Cost)) {
        let cell = self.grid.cell(u);
        if self.grid.is_blocked(cell) {
            return;
        }
        let (r, c) = (i64::from(cell.row), i64::from(cell.col));
        for (dr, dc) in NEIGHBOURS {
            let diagonal = dr != 0 && dc != 0;
            if diagonal && !self.model.has_diagonals() {
                continue;
            }
            let Some(n) = self.grid.checked_cell(r + dr, c + dc) else {
                continue;
            };
            if self.grid.is_blocked(n)
                || (diagonal && !self.model.corner_ok(&self.grid, cell, dr, dc))
            {
                continue;
            }
            f(
                self.grid.index(n),
                if diagonal { DIAGONAL } else { STRAIGHT },
            );
        }
    }

    fn for_each_move(&mut self, u: usize, mut f: impl FnMut(&mut Self, usize, Cost)) {
        let mut buf = [(0usize, 0 as Cost); 8];
        let mut n = 0;
        self.moves(u, |s, cost| {
            buf[n] = (s, cost);
            n += 1;
        });
        for &(s, cost) in &buf[..n] {
            f(self, s, cost);
        }
    }

    fn key(&self, i: usize) -> Key {
        let m = self.g[i].min(self.rhs[i]);
        Key(
            m.saturating_add(self.h(self.start, self.grid.cell(i)))
                .saturating_add(self.km),
            m,
        )
    }

    /// The move model's heuristic in integer costs (octile, or Manhattan when 4-connected).
    fn h(&self, a: Cell, b: Cell) -> Cost {
        let dr = Cost::from(a.row.abs_diff(b.row));
        let dc = Cost::from(a.col.abs_diff(b.col));
        if self.model.has_diagonals() {
            let (lo, hi) = (dr.min(dc), dr.max(dc));
            lo * DIAGONAL + (hi - lo) * STRAIGHT
        } else {
            (dr + dc) * STRAIGHT
        }
    }

    fn update_vertex(&mut self, i: usize) {
        if self.g[i] != self.rhs[i] {
            let k = self.key(i);
            self.push(i, k);
        } else {
            self.remove(i);
        }
    }

    fn push(&mut self, i: usize, key: Key) {
        match self.queued[i] {
            Some(k) if k.cmp(key) == Ordering::Equal => return, // already queued so
            Some(_) => {}
            None => self.live += 1,
        }
        self.queued[i] = Some(key);
        self.heap.push(Entry {
            key,
            index: i as u32,
        });
        if self.heap.len() > 64 && self.heap.len() > 4 * self.live {
            self.compact();
        }
    }

    fn remove(&mut self, i: usize) {
        if self.queued[i].take().is_some() {
            self.live -= 1;
        }
    }

    /// The smallest live entry (stale entries are dropped on the way).
    fn top(&mut self) -> Option<(usize, Key)> {
        while let Some(e) = self.heap.peek() {
            let i = e.index as usize;
            match self.queued[i] {
                Some(k) if k.cmp(e.key) == Ordering::Equal => return Some((i, k)),
                _ => {
                    self.heap.pop();
                }
            }
        }
        None
    }

    /// Drops stale heap entries (the queue holds at most one live entry per cell).
    fn compact(&mut self) {
        let entries = std::mem::take(&mut self.heap).into_vec();
        self.heap = entries
            .into_iter()
            .filter(|e| {
                self.queued[e.index as usize].is_some_and(|k| k.cmp(e.key) == Ordering::Equal)
            })
            .collect();
    }
}

// Neighbour order: N, E, S, W, then the diagonals.
use skyplan_cspace::NEIGHBOURS_8 as NEIGHBOURS;
