//! Search state: a flat array on small grids, pages allocated on touch on big ones.
//!
//! Grids of at most [`FLAT_MAX_CELLS`] cells get one row-major node array (16 bytes per cell;
//! the fastest layout), allocated zeroed by the system: its pages are mapped when a search first
//! touches them, so a single query on a large grid pays for the area it searches, not for the
//! whole array ([`Slot`]). On bigger grids the grid is cut into 8 × 8-cell tiles; a tile's 64
//! nodes (1 KiB) are allocated the first time a search touches one of its cells, back to back
//! in one pool. Memory therefore grows with the
//! area searches visit (plus a 4-byte page entry per tile, 1/16 byte per cell), not with the
//! map's area, and neighbouring cells share a page. Pages stay between queries (a node's stamp
//! says whether it belongs to the current query, so nothing is cleared per query) until the pool
//! outgrows [`KEEP_BYTES`]; then the next query starts from an empty pool.

use crate::astar::NO_PARENT;

/// `straight + √2 · diagonal`, always computed the same way: equal counts give equal bits.
#[inline(always)]
pub(crate) fn counts_cost(straight: u32, diagonal: u32) -> f64 {
    f64::from(straight) + f64::from(diagonal) * std::f64::consts::SQRT_2
}

/// Tile side, as a shift: 8 cells.
const SHIFT: usize = 3;
const SIDE: usize = 1 << SHIFT;
const PAGE: usize = SIDE * SIDE;
const NO_PAGE: u32 = u32::MAX;

/// Largest grid (cells, with a one-cell border) whose nodes are one flat array: 2²² cells
/// (4.2 M), 64 MiB.
pub(crate) const FLAT_MAX_CELLS: usize = 1 << 22;

/// Pool size above which the next query drops every page (256 MiB).
pub(crate) const KEEP_BYTES: usize = 256 << 20;

/// One cell's search state. `stamp` is `open_stamp` (reached) or `open_stamp + 1` (expanded) in
/// the current query; anything older means "unseen" (`g` and `parent` then mean nothing).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    pub(crate) g: f64,
    pub(crate) parent: u32,
    pub(crate) stamp: u32,
}

/// A [`Node`] as the pool stores it, `(g, parent, stamp)`: a tuple of numbers, so that
/// `vec![EMPTY; n]` is one zeroed allocation that the system maps lazily (a struct would be
/// written cell by cell: on the 9.3 km city's 0.85 M-cell tiles that was 40 % of a one-query
/// `plan`). All zeros is an unseen node: stamp 0 is never a query's.
pub(crate) type Slot = (f64, u32, u32);

/// An unseen node.
pub(crate) const EMPTY: Slot = (0.0, 0, 0);

/// What an unseen node reads as.
const FRESH: Node = Node {
    g: f64::INFINITY,
    parent: NO_PARENT,
    stamp: 0,
};

#[derive(Debug)]
pub(crate) struct PagedNodes {
    /// Grids up to this many cells are flat ([`FLAT_MAX_CELLS`]; tests lower it).
    pub(crate) flat_max_cells: usize,
    rows: u32,
    cols: usize,
    /// One row-major array (`pool`), no pages.
    flat: bool,
    tiles_per_row: usize,
    /// Page number of each tile in `pool`, or `NO_PAGE`.
    table: Vec<u32>,
    pool: Vec<Slot>,
    /// `2 × query number` (module docs).
    open_stamp: u32,
}

impl Default for PagedNodes {
    fn default() -> Self {
        Self {
            flat_max_cells: FLAT_MAX_CELLS,
            rows: 0,
            cols: 0,
            flat: false,
            tiles_per_row: 0,
            table: Vec::new(),
            pool: Vec::new(),
            open_stamp: 0,
        }
    }
}

impl PagedNodes {
    /// Starts a query on a `rows × cols` grid.
    pub(crate) fn reset(&mut self, rows: u32, cols: u32) {
        let cells = (rows as usize + 2) * (cols as usize + 2);
        let same_grid = self.rows == rows && self.cols == cols as usize && !self.pool.is_empty();
        let too_big = !self.flat && self.pool.len() * std::mem::size_of::<Slot>() > KEEP_BYTES;
        if !same_grid || too_big {
            self.rows = rows;
            self.cols = cols as usize;
            self.flat = cells <= self.flat_max_cells;
            self.table.clear();
            self.pool = Vec::new();
            if self.flat {
                self.table.shrink_to_fit();
                // Zeroed by the system, mapped on first touch (not written here).
                self.pool = vec![EMPTY; cells];
            } else {
                self.tiles_per_row = (cols as usize).div_ceil(SIDE);
                let tiles = self.tiles_per_row * (rows as usize).div_ceil(SIDE);
                self.table.resize(tiles, NO_PAGE);
            }
            self.open_stamp = 0;
        }
        if self.open_stamp >= u32::MAX - 3 {
            self.pool.fill(EMPTY);
            self.open_stamp = 0;
        }
        self.open_stamp += 2;
    }

    /// Heap bytes held (capacity of the page table and the pool).
    pub(crate) fn bytes(&self) -> usize {
        self.table.capacity() * std::mem::size_of::<u32>()
            + self.pool.capacity() * std::mem::size_of::<Slot>()
    }

    #[inline(always)]
    fn tile(&self, r: usize, c: usize) -> (usize, usize) {
        (
            (r >> SHIFT) * self.tiles_per_row + (c >> SHIFT),
            ((r & (SIDE - 1)) << SHIFT) | (c & (SIDE - 1)),
        )
    }

    /// Flat layout: the index of cell (r, c) in a row-major array with a one-cell border
    /// (`cols + 2` wide), so that every cell of the grid has eight neighbours in the array.
    #[inline(always)]
    pub(crate) fn padded(&self, r: usize, c: usize) -> usize {
        (r + 1) * (self.cols + 2) + c + 1
    }

    /// The flat array (with its border, [`PagedNodes::padded`]) and the current query's open
    /// stamp, or `None` if the nodes are paged.
    #[inline]
    pub(crate) fn flat_pool(&mut self) -> Option<(&mut [Slot], u32)> {
        self.flat.then_some((&mut self.pool[..], self.open_stamp))
    }

    /// Row and column of a row-major index.
    #[inline(always)]
    pub(crate) fn rc(&self, i: usize) -> (usize, usize) {
        // Indices and widths fit in u32 (the grid has at most `MAX_CELLS` cells): 32-bit division.
        let (i, cols) = (i as u32, self.cols as u32);
        ((i / cols) as usize, (i % cols) as usize)
    }

    #[inline(always)]
    fn node(&self, r: usize, c: usize) -> Node {
        let (g, parent, stamp) = if self.flat {
            self.pool[self.padded(r, c)]
        } else {
            let (t, o) = self.tile(r, c);
            match self.table[t] {
                NO_PAGE => return FRESH,
                p => self.pool[p as usize * PAGE + o],
            }
        };
        if stamp < self.open_stamp {
            return FRESH;
        }
        Node { g, parent, stamp }
    }

    /// The node of cell (r, c), allocating its tile's page on first touch.
    #[inline(always)]
    fn node_mut(&mut self, r: usize, c: usize) -> &mut Slot {
        if self.flat {
            let p = self.padded(r, c);
            return &mut self.pool[p];
        }
        let (t, o) = self.tile(r, c);
        let mut p = self.table[t];
        if p == NO_PAGE {
            p = self.new_page(t);
        }
        &mut self.pool[p as usize * PAGE + o]
    }

    #[cold]
    fn new_page(&mut self, tile: usize) -> u32 {
        let p = (self.pool.len() / PAGE) as u32;
        self.pool.resize(self.pool.len() + PAGE, EMPTY);
        self.table[tile] = p;
        p
    }

    /// True if cell (r, c) was expanded in this query.
    #[inline(always)]
    pub(crate) fn is_closed(&self, r: usize, c: usize) -> bool {
        self.node(r, c).stamp == self.open_stamp + 1
    }

    /// Best cost to cell (r, c) in this query (infinite if unseen).
    #[inline(always)]
    pub(crate) fn g(&self, r: usize, c: usize) -> f64 {
        // An unseen node reads as `FRESH`, whose cost is infinite.
        self.node(r, c).g
    }

    /// Parent of cell (r, c) on its best path.
    #[inline(always)]
    pub(crate) fn parent(&self, r: usize, c: usize) -> u32 {
        self.node(r, c).parent
    }

    /// Records a better path to cell (r, c) if it is not expanded yet; false if it is expanded
    /// or the path is not better.
    #[inline(always)]
    pub(crate) fn relax(&mut self, r: usize, c: usize, g: f64, parent: u32) -> bool {
        let open = self.open_stamp;
        let n = self.node_mut(r, c);
        if n.2 == open + 1 || (n.2 == open && g >= n.0) {
            return false;
        }
        *n = (g, parent, open);
        true
    }

    /// Like [`PagedNodes::relax`] for A\*, which keeps a cost as its move counts (`straight`,
    /// `diagonal`) in the node's `g` slot (so equal costs are equal bits, module
    /// [`crate::astar`]); [`PagedNodes::g`] means nothing for such nodes.
    #[inline(always)]
    pub(crate) fn relax_counts(
        &mut self,
        r: usize,
        c: usize,
        straight: u32,
        diagonal: u32,
        parent: u32,
    ) -> bool {
        let open = self.open_stamp;
        let n = self.node_mut(r, c);
        if n.2 == open + 1 {
            return false;
        }
        let bits = (u64::from(diagonal) << 32) | u64::from(straight);
        if n.2 == open {
            let old = n.0.to_bits();
            if counts_cost(straight, diagonal) >= counts_cost(old as u32, (old >> 32) as u32) {
                return false;
            }
        }
        *n = (f64::from_bits(bits), parent, open);
        true
    }

    /// Like [`PagedNodes::close`] for nodes written by [`PagedNodes::relax_counts`]: the move
    /// counts (straight, diagonal).
    #[inline(always)]
    pub(crate) fn close_counts(&mut self, r: usize, c: usize) -> Option<(u32, u32)> {
        self.close(r, c).map(|g| {
            let bits = g.to_bits();
            (bits as u32, (bits >> 32) as u32)
        })
    }

    /// Marks cell (r, c) expanded and returns its best cost, or `None` if it was expanded
    /// already.
    #[inline(always)]
    pub(crate) fn close(&mut self, r: usize, c: usize) -> Option<f64> {
        let closed = self.open_stamp + 1;
        let n = self.node_mut(r, c);
        if n.2 == closed {
            return None;
        }
        n.2 = closed;
        Some(n.0)
    }
}

#[cfg(test)]
mod tests {
    use crate::{GridSearch, MoveModel, Planner};
    use proptest::prelude::*;
    use skyplan_cspace::{Cell, Grid2, GridFrame};

    proptest! {
        /// Pages give exactly the flat array's answers (paths, costs, expansions), including
        /// grids whose sides are not multiples of the tile and queries reusing the pages.
        #[test]
        fn pages_answer_like_the_flat_array(
            rows in 1u32..40, cols in 1u32..40, seed in proptest::collection::vec(proptest::bool::weighted(0.25), 1600),
            ends in proptest::collection::vec((0u32..40, 0u32..40, 0u32..40, 0u32..40), 1..4),
        ) {
            let cells = seed[..(rows * cols) as usize].to_vec();
            let grid = Grid2::new(rows, cols, cells, GridFrame::default()).expect("size");
            let mut flat = GridSearch::new();
            let mut paged = GridSearch::new();
            paged.nodes.flat_max_cells = 0;
            for &(a, b, c, d) in &ends {
                let (start, goal) = (Cell::new(a % rows, b % cols), Cell::new(c % rows, d % cols));
                for model in [MoveModel::FourConnected, MoveModel::Octile, MoveModel::OctileCornerCutting] {
                    for planner in [Planner::AStar, Planner::Dijkstra, Planner::Jps, Planner::ThetaStar] {
                        prop_assert_eq!(
                            flat.search(&grid, start, goal, model, planner),
                            paged.search(&grid, start, goal, model, planner)
                        );
                    }
                }
            }
            prop_assert!(paged.node_bytes() <= flat.node_bytes() + 64 * 16 * 64);
        }
    }
}
