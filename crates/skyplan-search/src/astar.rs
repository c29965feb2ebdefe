//! A\* and Dijkstra on a 2D grid with flat arrays and reusable buffers.

use crate::nodes::{PagedNodes, counts_cost};
use crate::queue::{BucketQueue, key, key_index};
use crate::{GridPath, MoveModel, Planner, SearchError};
use skyplan_cspace::{Cell, Grid2};

/// Reusable A\*/Dijkstra workspace: create once, run many queries on grids of any size.
#[derive(Debug, Default)]
pub struct GridSearch {
    /// Per-cell search state: flat on small grids, 8 × 8-cell pages allocated on touch on big
    /// ones (memory grows with the area searched, not with the map).
    pub(crate) nodes: PagedNodes,
    queue: BucketQueue,
    /// The moves each cell allows, on the flat A\*'s bordered layout ([`PagedNodes::padded`]).
    masks: MoveMasks,
    /// The grid's free cells as bit rows and columns for JPS's block scans, kept like `masks`.
    pub(crate) block: crate::bits::BlockGrid,
}

pub(crate) const NO_PARENT: u32 = u32::MAX;

/// Move mask bits: north (row + 1), south, east (column + 1), west, then the diagonals.
const N: u32 = 0;
const S: u32 = 1;
const E: u32 = 2;
const W: u32 = 3;
const NE: u32 = 4;
const NW: u32 = 5;
const SE: u32 = 6;
const SW: u32 = 7;

/// For each cell of a grid with a one-cell border (row-major, `cols + 2` wide), the moves the
/// move model allows from it: bit `N`…`SW` set iff that neighbour is free and, for a diagonal
/// without corner cutting, both cells beside it too. Blocked and border cells allow nothing, so
/// no move leaves the grid. Built once per grid and model, kept while queries use the same grid
/// (checked by comparing its blocked cells, a memory compare).
#[derive(Debug, Default)]
struct MoveMasks {
    /// `(rows, cols, diagonals, corner cutting)` the masks were built for.
    shape: Option<(u32, u32, bool, bool)>,
    /// The grid's blocked cells when built.
    blocked: Vec<bool>,
    masks: Vec<u8>,
}

impl MoveMasks {
    /// The masks of `grid` under the model, rebuilt if the grid or model changed.
    fn get(&mut self, grid: &Grid2, diagonals: bool, corner_cutting: bool) -> &[u8] {
        let shape = Some((grid.rows(), grid.cols(), diagonals, corner_cutting));
        if self.shape != shape || self.blocked != grid.blocked_cells() {
            self.build(grid, diagonals, corner_cutting);
            self.shape = shape;
        }
        &self.masks
    }

    #[cold]
    fn build(&mut self, grid: &Grid2, diagonals: bool, corner_cutting: bool) {
        let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
        let w = cols + 2;
        self.blocked.clear();
        self.blocked.extend_from_slice(grid.blocked_cells());
        // 1 for a free cell, 0 for a blocked or border one.
        let mut free = vec![0u8; w * (rows + 2)];
        for (r, row) in self.blocked.chunks_exact(cols).enumerate() {
            let at = (r + 1) * w + 1;
            for (f, &b) in free[at..at + cols].iter_mut().zip(row) {
                *f = u8::from(!b);
            }
        }
        self.masks.clear();
        self.masks.resize(free.len(), 0);
        // Row by row, over whole rows (branch-free byte arithmetic the compiler vectorises):
        // `x[k]` is the cell `k` columns left of the mask's cell.
        for r in 1..=rows {
            let row = |dr: isize| {
                let at = (r as isize + dr) as usize * w;
                &free[at..at + w]
            };
            let (below, here, above) = (row(-1), row(0), row(1));
            let out = &mut self.masks[r * w + 1..r * w + 1 + cols];
            for (c, m) in out.iter_mut().enumerate() {
                let (n, s) = (above[c + 1], below[c + 1]);
                let (e, west) = (here[c + 2], here[c]);
                let mut bits = n << N | s << S | e << E | west << W;
                if diagonals {
                    let rule = |a: u8, b: u8| if corner_cutting { 1 } else { a & b };
                    bits |= (rule(n, e) & above[c + 2]) << NE;
                    bits |= (rule(n, west) & above[c]) << NW;
                    bits |= (rule(s, e) & below[c + 2]) << SE;
                    bits |= (rule(s, west) & below[c]) << SW;
                }
                // Nothing from a blocked cell.
                *m = bits & here[c + 1].wrapping_neg();
            }
        }
    }
}

/// Division by a fixed `d` of numbers below `2^bits` as a multiply and a shift (Granlund and
/// Montgomery, 1994, theorem 4.2: with `2^(l-1) < d ≤ 2^l` and `m = ⌈2^(bits+l) / d⌉`,
/// `⌊n·m / 2^(bits+l)⌋ = ⌊n / d⌋` for every `n < 2^bits`). A hardware divide takes 20–40 cycles.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DivBy {
    d: usize,
    m: u64,
    shift: u32,
}

impl DivBy {
    /// Division by `d` of numbers below `below` (at most 2³¹, so that `n·m` fits in 64 bits).
    pub(crate) fn new(d: usize, below: usize) -> Self {
        assert!(d > 0 && below <= 1 << 31);
        let bits = usize::BITS - below.saturating_sub(1).leading_zeros();
        let l = usize::BITS - (d - 1).leading_zeros();
        let shift = bits + l;
        let m = (1u128 << shift).div_ceil(d as u128) as u64;
        Self { d, m, shift }
    }

    /// `(n / d, n % d)`.
    #[inline(always)]
    pub(crate) fn div_rem(self, n: usize) -> (usize, usize) {
        let q = ((n as u64 * self.m) >> self.shift) as usize;
        debug_assert_eq!(q, n / self.d);
        (q, n - q * self.d)
    }
}

/// The heuristic from `(r, c)` to `(goal_r, goal_c)` as move counts (straight, diagonal):
/// octile with `DIAGONALS`, Manhattan without, `(0, 0)` without `HEURISTIC` (Dijkstra).
#[inline(always)]
fn heuristic_counts<const DIAGONALS: bool, const HEURISTIC: bool>(
    r: usize,
    c: usize,
    goal_r: usize,
    goal_c: usize,
) -> (u32, u32) {
    if !HEURISTIC {
        return (0, 0);
    }
    let dr = r.abs_diff(goal_r) as u32;
    let dc = c.abs_diff(goal_c) as u32;
    if DIAGONALS {
        let (lo, hi) = if dr < dc { (dr, dc) } else { (dc, dr) };
        (hi - lo, lo)
    } else {
        (dr + dc, 0)
    }
}

/// The endpoint checks every planner makes first.
pub(crate) fn check_endpoints(grid: &Grid2, start: Cell, goal: Cell) -> Result<(), SearchError> {
    grid.check_contains(start)
        .map_err(SearchError::StartOutside)?;
    grid.check_contains(goal)
        .map_err(SearchError::GoalOutside)?;
    if grid.is_blocked(start) {
        return Err(SearchError::StartBlocked(start));
    }
    if grid.is_blocked(goal) {
        return Err(SearchError::GoalBlocked(goal));
    }
    Ok(())
}

impl GridSearch {
    /// An empty workspace; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// Heap bytes of the search state. Grids of up to 2²² (4.2 M) cells use one flat array (16 bytes per
    /// cell, the fastest layout); bigger grids keep nodes in 8 × 8-cell pages allocated on touch
    /// (plus a page table of 4 bytes per page), so the state grows with the area searches visit,
    /// not with the map's area. Pages are kept between queries up to 256 MiB. A\* and Dijkstra
    /// on a flat grid also keep 2 bytes per cell outside this count: the grid's per-cell move
    /// masks and the blocked cells they were built from (rebuilt only when the grid changes).
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2, GridFrame};
    /// use skyplan_search::{GridSearch, MoveModel, Planner};
    /// // 4.4 M cells: above the flat array's limit of 2²² cells, nodes live in pages.
    /// let grid = Grid2::new(2100, 2100, vec![false; 2100 * 2100], GridFrame::default())?;
    /// let mut search = GridSearch::new();
    /// search.search(&grid, Cell::new(5, 5), Cell::new(40, 60), MoveModel::Octile, Planner::AStar)?;
    /// assert!(search.node_bytes() < 500_000); // a full node array would be 70 MB
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn node_bytes(&self) -> usize {
        self.nodes.bytes()
    }

    /// Starts a query on `grid`. `dense`: A\*/Dijkstra, whose keys rise in small steps (the
    /// bucket queue pays); JPS and Theta\* push few, far-apart keys (a plain heap).
    pub(crate) fn reset(&mut self, grid: &Grid2, dense: bool) {
        self.nodes.reset(grid.rows(), grid.cols());
        self.queue.clear(dense);
    }

    /// True if cell `i` was expanded in the current query.
    #[inline(always)]
    pub(crate) fn is_closed(&self, i: usize) -> bool {
        let (r, c) = self.nodes.rc(i);
        self.nodes.is_closed(r, c)
    }

    /// The best cost found so far to cell `i` (infinite if unseen in this query).
    #[inline(always)]
    pub(crate) fn g(&self, i: usize) -> f64 {
        let (r, c) = self.nodes.rc(i);
        self.nodes.g(r, c)
    }

    /// The parent of cell `i` on its best path ([`NO_PARENT`] for the start).
    #[inline(always)]
    pub(crate) fn parent(&self, i: usize) -> u32 {
        let (r, c) = self.nodes.rc(i);
        self.nodes.parent(r, c)
    }

    /// Offers a path of cost `g` to cell `i` through `parent`, with heuristic `h`: queued if the
    /// cell is not expanded yet and the path is better than any found before.
    #[inline(always)]
    pub(crate) fn offer(&mut self, i: usize, g: f64, h: f64, parent: u32) {
        let (r, c) = self.nodes.rc(i);
        if self.nodes.relax(r, c, g, parent) {
            self.queue.push(key(g + h, g, i as u32));
        }
    }

    /// Like [`GridSearch::offer`] for the cell at row `r`, column `c` (index `i`), with the
    /// heuristic computed only when the cell is improved (not for cells already closed or
    /// reached as cheaply).
    #[inline(always)]
    pub(crate) fn offer_rc(
        &mut self,
        (i, r, c): (usize, usize, usize),
        g: f64,
        h: impl FnOnce() -> f64,
        parent: u32,
    ) {
        if self.nodes.relax(r, c, g, parent) {
            self.queue.push(key(g + h(), g, i as u32));
        }
    }

    /// Like [`GridSearch::expand_next`], also returning the cell's row and column.
    #[inline(always)]
    pub(crate) fn expand_next_rc(&mut self) -> Option<(f64, u32, usize, usize)> {
        while let Some(k) = self.queue.pop() {
            let index = key_index(k);
            let (r, c) = self.nodes.rc(index as usize);
            if let Some(g) = self.nodes.close(r, c) {
                return Some((g, index, r, c));
            }
        }
        None
    }

    /// Pops the best queued cell not expanded yet, marks it expanded and returns its best cost
    /// and index. An older entry of a cell (a worse `g`) can only come first on an exact tie of
    /// `f`, and then the cell's best entry has the same `f`: expanding it with its best `g` is
    /// what A\* would do next anyway.
    #[inline(always)]
    pub(crate) fn expand_next(&mut self) -> Option<(f64, u32)> {
        while let Some(k) = self.queue.pop() {
            let index = key_index(k);
            let (r, c) = self.nodes.rc(index as usize);
            if let Some(g) = self.nodes.close(r, c) {
                return Some((g, index));
            }
        }
        None
    }

    /// Finds an optimal path from `start` to `goal` under `model`.
    ///
    /// Errors say which endpoint is off the grid or blocked, or that the goal is unreachable.
    pub fn search(
        &mut self,
        grid: &Grid2,
        start: Cell,
        goal: Cell,
        model: MoveModel,
        planner: Planner,
    ) -> Result<GridPath, SearchError> {
        check_endpoints(grid, start, goal)?;
        if planner == Planner::ThetaStar {
            return self.theta_star(grid, start, goal, model);
        }
        if model.has_diagonals() {
            match planner {
                Planner::Jps => return self.search_jps(grid, start, goal, model),
                Planner::JpsPlus => return crate::JpsPlus::new(grid, model).search(start, goal),
                Planner::AStar | Planner::Dijkstra | Planner::ThetaStar => {}
            }
        }
        let dijkstra = planner == Planner::Dijkstra;
        match (model, dijkstra) {
            (MoveModel::FourConnected, false) => {
                self.astar_any::<false, false, true>(grid, start, goal)
            }
            (MoveModel::FourConnected, true) => {
                self.astar_any::<false, false, false>(grid, start, goal)
            }
            (MoveModel::Octile, false) => self.astar_any::<true, false, true>(grid, start, goal),
            (MoveModel::Octile, true) => self.astar_any::<true, false, false>(grid, start, goal),
            (MoveModel::OctileCornerCutting, false) => {
                self.astar_any::<true, true, true>(grid, start, goal)
            }
            (MoveModel::OctileCornerCutting, true) => {
                self.astar_any::<true, true, false>(grid, start, goal)
            }
        }
    }

    /// A\* on the flat node array (grids up to the flat limit), or on pages ([`GridSearch::astar`]).
    fn astar_any<const DIAGONALS: bool, const CORNER_CUTTING: bool, const HEURISTIC: bool>(
        &mut self,
        grid: &Grid2,
        start: Cell,
        goal: Cell,
    ) -> Result<GridPath, SearchError> {
        self.reset(grid, true);
        match self.astar_flat::<DIAGONALS, CORNER_CUTTING, HEURISTIC>(grid, start, goal) {
            Some(Ok(expansions)) => Ok(self.reconstruct(grid, grid.index(goal) as u32, expansions)),
            Some(Err(expansions)) => Err(SearchError::Unreachable { expansions }),
            None => self.astar::<DIAGONALS, CORNER_CUTTING, HEURISTIC>(grid, start, goal),
        }
    }

    /// [`GridSearch::astar`] on the flat node array, whose one-cell border the move masks
    /// ([`MoveMasks`]) never enter: no edge tests, no corner rule in the loop. A cell is its
    /// bordered index everywhere (queue, nodes) but in `parent`, which holds grid indices.
    /// `None` if the nodes are paged; else the expansions, `Ok` when the goal was reached.
    ///
    /// Neighbours are tried in the paged A\*'s order with the same keys, so both expand the
    /// same cells. The loop per expansion: pop, close, one mask byte, then per allowed move one
    /// node compare and, if better, a push; the row and column (for the heuristic) come from a
    /// multiply by the width's reciprocal ([`DivBy`]), not a divide. Not inlined, so that
    /// callgrind reports it as one function (`examples/city_astar.rs`).
    #[inline(never)]
    fn astar_flat<const DIAGONALS: bool, const CORNER_CUTTING: bool, const HEURISTIC: bool>(
        &mut self,
        grid: &Grid2,
        start: Cell,
        goal: Cell,
    ) -> Option<Result<u64, u64>> {
        let GridSearch {
            nodes,
            queue,
            masks,
            block: _,
        } = self;
        let (pool, open) = nodes.flat_pool()?;
        let moves = masks.get(grid, DIAGONALS, CORNER_CUTTING);
        let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
        let w = cols + 2;
        assert!(pool.len() == w * (rows + 2) && moves.len() == pool.len());
        let div = DivBy::new(w, pool.len());
        let closed = open + 1;
        // Bordered coordinates: the goal's differences are the grid's.
        let (goal_r, goal_c) = (goal.row as usize + 1, goal.col as usize + 1);
        let h = |r: usize, c: usize| heuristic_counts::<DIAGONALS, HEURISTIC>(r, c, goal_r, goal_c);
        let bits = |s: u32, d: u32| f64::from_bits((u64::from(d) << 32) | u64::from(s));
        let start_p = (start.row as usize + 1) * w + start.col as usize + 1;
        let goal_p = goal_r * w + goal_c;
        pool[start_p] = (bits(0, 0), NO_PARENT, open);
        let (hs, hd) = h(start.row as usize + 1, start.col as usize + 1);
        queue.push(key(counts_cost(hs, hd), 0.0, start_p as u32));
        let mut expansions = 0u64;
        while let Some(k) = queue.pop() {
            let p = key_index(k) as usize;
            // (g, parent, stamp): `crate::nodes::Slot`.
            let node = &mut pool[p];
            if node.2 == closed {
                continue;
            }
            node.2 = closed;
            let g_bits = node.0.to_bits();
            let (s, d) = (g_bits as u32, (g_bits >> 32) as u32);
            expansions += 1;
            if p == goal_p {
                return Some(Ok(expansions));
            }
            let (r, c) = div.div_rem(p);
            let parent = ((r - 1) * cols + c - 1) as u32;
            let m = moves[p];
            // The two costs a move gives (as floats and as the node's counts), each computed once.
            let (g_straight, g_diagonal) = (counts_cost(s + 1, d), counts_cost(s, d + 1));
            let (bits_straight, bits_diagonal) = (bits(s + 1, d), bits(s, d + 1));
            macro_rules! try_move {
                ($bit:expr, $q:expr, $nr:expr, $nc:expr, $ns:expr, $nd:expr, $g:expr, $g_bits:expr) => {{
                    if m & (1 << $bit) != 0 {
                        let q: usize = $q;
                        let (ns, nd, g): (u32, u32, f64) = ($ns, $nd, $g);
                        let next = &mut pool[q];
                        let better = next.2 != closed
                            && (next.2 != open || {
                                let old = next.0.to_bits();
                                g < counts_cost(old as u32, (old >> 32) as u32)
                            });
                        if better {
                            *next = ($g_bits, parent, open);
                            let (hs, hd) = h($nr, $nc);
                            queue.push(key(counts_cost(ns + hs, nd + hd), g, q as u32));
                        }
                    }
                }};
            }
            let (gs, bs) = (g_straight, bits_straight);
            try_move!(N, p + w, r + 1, c, s + 1, d, gs, bs);
            try_move!(S, p - w, r - 1, c, s + 1, d, gs, bs);
            try_move!(E, p + 1, r, c + 1, s + 1, d, gs, bs);
            try_move!(W, p - 1, r, c - 1, s + 1, d, gs, bs);
            if DIAGONALS {
                let (gd, bd) = (g_diagonal, bits_diagonal);
                try_move!(NE, p + w + 1, r + 1, c + 1, s, d + 1, gd, bd);
                try_move!(NW, p + w - 1, r + 1, c - 1, s, d + 1, gd, bd);
                try_move!(SE, p - w + 1, r - 1, c + 1, s, d + 1, gd, bd);
                try_move!(SW, p - w - 1, r - 1, c - 1, s, d + 1, gd, bd);
            }
        }
        Some(Err(expansions))
    }

    /// A\* (Dijkstra without `HEURISTIC`), one copy per move model: `DIAGONALS` and
    /// `CORNER_CUTTING` are decided at compile time, not per node.
    ///
    /// Costs are kept as move counts (straight, diagonal) and turned into floats the same way
    /// every time ([`counts_cost`]), so two equal costs — the many cells on open ground whose
    /// `f` equals the optimum — have equal bits and take the queue's O(1) tie stack.
    fn astar<const DIAGONALS: bool, const CORNER_CUTTING: bool, const HEURISTIC: bool>(
        &mut self,
        grid: &Grid2,
        start: Cell,
        goal: Cell,
    ) -> Result<GridPath, SearchError> {
        let blocked = grid.blocked_cells();
        let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
        let (goal_r, goal_c) = (goal.row as usize, goal.col as usize);
        // The heuristic as move counts (straight, diagonal).
        let h = |r: usize, c: usize| heuristic_counts::<DIAGONALS, HEURISTIC>(r, c, goal_r, goal_c);
        let start_i = grid.index(start);
        let goal_i = grid.index(goal) as u32;
        let (sr, sc) = (start.row as usize, start.col as usize);
        self.nodes.relax_counts(sr, sc, 0, 0, NO_PARENT);
        let (hs, hd) = h(sr, sc);
        self.queue
            .push(key(counts_cost(hs, hd), 0.0, start_i as u32));
        let mut expansions = 0u64;
        while let Some(k) = self.queue.pop() {
            let index = key_index(k);
            let i = index as usize;
            let (r, c) = self.nodes.rc(i);
            let Some((s, d)) = self.nodes.close_counts(r, c) else {
                continue;
            };
            expansions += 1;
            if index == goal_i {
                return Ok(self.reconstruct(grid, goal_i, expansions));
            }
            // Which neighbours are on the grid; away from the border all of them.
            let (has_s, has_n, has_w, has_e) = (r > 0, r + 1 < rows, c > 0, c + 1 < cols);
            let free = |ok: bool, j: usize| ok && !blocked[j];
            let n = free(has_n, i + cols);
            let so = free(has_s, i.wrapping_sub(cols));
            let e = free(has_e, i + 1);
            let w = free(has_w, i.wrapping_sub(1));
            // A macro, not a closure: inlined for sure.
            macro_rules! try_move {
                ($ok:expr, $j:expr, $nr:expr, $nc:expr, $ns:expr, $nd:expr) => {{
                    let (nr, nc): (usize, usize) = ($nr, $nc);
                    if $ok && self.nodes.relax_counts(nr, nc, $ns, $nd, index) {
                        let (hs, hd) = h(nr, nc);
                        self.queue.push(key(
                            counts_cost($ns + hs, $nd + hd),
                            counts_cost($ns, $nd),
                            $j as u32,
                        ));
                    }
                }};
            }
            try_move!(n, i + cols, r + 1, c, s + 1, d);
            try_move!(so, i.wrapping_sub(cols), r.wrapping_sub(1), c, s + 1, d);
            try_move!(e, i + 1, r, c + 1, s + 1, d);
            try_move!(w, i.wrapping_sub(1), r, c.wrapping_sub(1), s + 1, d);
            if DIAGONALS {
                let corner = |a: bool, b: bool| CORNER_CUTTING || (a && b);
                let ne = has_n && has_e && corner(n, e) && free(true, i + cols + 1);
                let nw = has_n && has_w && corner(n, w) && free(true, i + cols - 1);
                let se = has_s && has_e && corner(so, e) && free(true, i + 1 - cols);
                let sw = has_s && has_w && corner(so, w) && free(true, i - 1 - cols);
                try_move!(ne, i + cols + 1, r + 1, c + 1, s, d + 1);
                try_move!(nw, i + cols - 1, r + 1, c.wrapping_sub(1), s, d + 1);
                let (rs, ce, cw) = (r.wrapping_sub(1), c + 1, c.wrapping_sub(1));
                try_move!(se, (i + 1).wrapping_sub(cols), rs, ce, s, d + 1);
                try_move!(sw, i.wrapping_sub(1 + cols), rs, cw, s, d + 1);
            }
        }
        Err(SearchError::Unreachable { expansions })
    }

    pub(crate) fn reconstruct(&self, grid: &Grid2, goal: u32, expansions: u64) -> GridPath {
        let mut cells = vec![grid.cell(goal as usize)];
        let mut at = goal;
        while self.parent(at as usize) != NO_PARENT {
            at = self.parent(at as usize);
            cells.push(grid.cell(at as usize));
        }
        cells.reverse();
        let diagonal_moves = cells
            .windows(2)
            .filter(|w| w[0].row != w[1].row && w[0].col != w[1].col)
            .count() as u64;
        let straight_moves = (cells.len() as u64 - 1) - diagonal_moves;
        GridPath {
            cells,
            straight_moves,
            diagonal_moves,
            expansions,
            any_angle_cells: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use skyplan_cspace::GridFrame;

    #[test]
    fn reciprocal_division_is_exact() {
        for d in (1..300).chain([1023, 1024, 1025, 2047, 2050, 4099]) {
            for below in [1usize, 2, 1000, 1 << 16, 1 << 22] {
                let div = DivBy::new(d, below);
                let step = (below / 5000).max(1);
                for n in (0..below).step_by(step).chain([below - 1]) {
                    assert_eq!(div.div_rem(n), (n / d, n % d), "{n} / {d} (below {below})");
                }
            }
        }
        // The largest case: 2³¹ numbers, odd and power-of-two divisors.
        for d in [3, 7, 1000, 4096, 65_537] {
            let div = DivBy::new(d, 1 << 31);
            for n in [0, 1, d - 1, d, (1 << 31) - 1, (1 << 31) - d, 1_234_567_891] {
                assert_eq!(div.div_rem(n), (n / d, n % d), "{n} / {d}");
            }
        }
    }

    proptest! {
        /// A cell's mask allows exactly the moves the model allows: onto a free cell of the
        /// grid, diagonals past the corner only as the model says; blocked cells allow none.
        #[test]
        fn masks_allow_the_models_moves(
            rows in 1u32..12, cols in 1u32..12,
            seed in proptest::collection::vec(proptest::bool::weighted(0.3), 144),
        ) {
            let grid = Grid2::new(rows, cols, seed[..(rows * cols) as usize].to_vec(), GridFrame::default())
                .expect("size");
            let w = cols as usize + 2;
            let dirs: [(u32, i64, i64); 8] =
                [(N, 1, 0), (S, -1, 0), (E, 0, 1), (W, 0, -1), (NE, 1, 1), (NW, 1, -1), (SE, -1, 1), (SW, -1, -1)];
            for model in [MoveModel::FourConnected, MoveModel::Octile, MoveModel::OctileCornerCutting] {
                let mut masks = MoveMasks::default();
                let cc = model == MoveModel::OctileCornerCutting;
                let m = masks.get(&grid, model.has_diagonals(), cc).to_vec();
                prop_assert_eq!(m.len(), w * (rows as usize + 2));
                for r in 0..rows {
                    for c in 0..cols {
                        let cell = Cell::new(r, c);
                        let bits = m[(r as usize + 1) * w + c as usize + 1];
                        for &(bit, dr, dc) in &dirs {
                            let (nr, nc) = (i64::from(r) + dr, i64::from(c) + dc);
                            let diagonal = dr != 0 && dc != 0;
                            let allowed = !grid.is_blocked(cell)
                                && grid.is_free_at(nr, nc)
                                && (!diagonal || (model.has_diagonals() && model.corner_ok(&grid, cell, dr, dc)));
                            prop_assert_eq!(bits & (1 << bit) != 0, allowed, "{:?} {:?} bit {}", model, cell, bit);
                        }
                    }
                }
                // Border cells allow nothing.
                for r in 0..rows as usize + 2 {
                    prop_assert_eq!(m[r * w], 0);
                    prop_assert_eq!(m[r * w + w - 1], 0);
                }
                prop_assert!(m[..w].iter().chain(&m[m.len() - w..]).all(|&b| b == 0));
            }
        }
    }
}
