//! Contraction hierarchy (Geisberger et al. 2008) over the grid graph: exact shortest paths with
//! a per-grid preprocessing, strong where JPS is weak (random obstacles, mazes).
//!
//! * Preprocessing contracts the free cells one by one in order of importance (edge difference,
//!   contracted neighbours, level, updated lazily). Contracting `v` removes it and adds a shortcut
//!   `u – w` for each pair of its neighbours whose shortest path runs through `v` (a bounded
//!   witness search decides; when it gives up the shortcut is kept, which is always correct).
//!   Contraction stops when the cheapest node has more than 200 neighbours: the nodes left form a
//!   core (open ground makes dense cores) that queries search in every direction.
//! * A query runs Dijkstra upwards (and inside the core) from both ends, with stall-on-demand,
//!   and stops when neither queue can beat the best meeting cost; the shortcuts are then
//!   unpacked into cells.
//!
//! Costs are exact integers: a straight move costs [`STRAIGHT`] = q and a diagonal [`DIAGONAL`] =
//! p, where p/q is a convergent of √2 (p² − 2q² = ±1), so `cost = s·q + d·p`. For two move counts
//! with `|Δs|, |Δd| ≤ M`, the real costs differ by `|Δs − Δd·√2| ≥ 1/(|Δs| + √2|Δd|)` unless
//! they are equal (then the counts are equal, √2 being irrational), while the integer error is
//! `|Δd|·|p − q√2| < M · 6.6e-10`; so `q / (2.42 M) > 6.6e-10 · M` for `M < 5.8e8` and integer
//! order is exactly real order. Paths have at most as many moves as the grid has cells, and sums
//! of two, so grids are limited to [`MAX_CELLS`] = 2²⁸ cells (which also keeps every sum in u64).

use crate::{GridPath, MoveModel, SearchError};
use skyplan_cspace::{Cell, Grid2};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::sync::Arc;

/// Integer cost of an orthogonal move (q of the convergent p/q of √2).
pub const STRAIGHT: u64 = 543_339_720;
/// Integer cost of a diagonal move (p of the convergent p/q of √2).
pub const DIAGONAL: u64 = 768_398_401;
/// Largest grid (in cells) a hierarchy is built for: keeps the integer costs exact (module docs).
pub const MAX_CELLS: usize = 1 << 28;

pub(crate) const NONE: u32 = u32::MAX;
/// Nodes a witness search may settle before it gives up (and keeps the shortcut).
const WITNESS_SETTLE_LIMIT: u32 = 120;
/// Contraction stops when the cheapest node left has more neighbours than this: the rest stay
/// an uncontracted core (open ground makes dense cores whose contraction costs cubic time).
const CORE_DEGREE: usize = 200;

/// Why a hierarchy cannot be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ContractionError {
    /// The grid has more cells than the exact integer costs allow.
    #[error("the grid has {cells} cells; a contraction hierarchy takes at most {max} cells")]
    TooLarge {
        /// Cells of the grid.
        cells: usize,
        /// [`MAX_CELLS`].
        max: usize,
    },
    /// The contraction did not finish before the caller's deadline.
    #[error(
        "preprocessing did not finish within the time allowed ({contracted} of {nodes} cells contracted)"
    )]
    Deadline {
        /// Cells contracted by then.
        contracted: usize,
        /// Free cells of the grid.
        nodes: usize,
    },
}

/// One edge ever created: an original move (`mid == NONE`) or a shortcut `a – mid – b` made of
/// the edges `first` (`a – mid`) and `second` (`mid – b`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Edge {
    pub(crate) a: u32,
    pub(crate) b: u32,
    pub(crate) mid: u32,
    pub(crate) first: u32,
    pub(crate) second: u32,
}

/// An upward arc: its head's rank, its cost and the edge it follows, side by side so that a
/// query reads one cache line for them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct UpArc {
    pub(crate) cost: u64,
    pub(crate) head: u32,
    pub(crate) edge: u32,
}

/// The contraction hierarchy of one grid under one move model, owning its grid (`Arc`) so a
/// planning session can keep it across requests. Queries need a [`ChQuery`] workspace.
///
/// ```
/// use std::sync::Arc;
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_search::{ChQuery, ContractionHierarchy, GridSearch, MoveModel, Planner};
/// let grid = Arc::new(Grid2::from_ascii("......\n.####.\n......")?);
/// let ch = ContractionHierarchy::build(Arc::clone(&grid), MoveModel::Octile)?;
/// let mut query = ChQuery::default();
/// let fast = ch.search(&mut query, Cell::new(0, 0), Cell::new(2, 5))?;
/// let reference = GridSearch::new().search(&grid, Cell::new(0, 0), Cell::new(2, 5), MoveModel::Octile, Planner::AStar)?;
/// assert_eq!((fast.straight_moves, fast.diagonal_moves), (reference.straight_moves, reference.diagonal_moves));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct ContractionHierarchy {
    pub(crate) grid: Arc<Grid2>,
    pub(crate) model: MoveModel,
    /// Rank (query node id) of every cell, `NONE` for blocked cells.
    pub(crate) rank_of_cell: Vec<u32>,
    /// Cell index of every rank.
    pub(crate) cell_of_rank: Vec<u32>,
    /// Upward edges in CSR form, by rank: `arcs[first_out[r]..first_out[r + 1]]`.
    pub(crate) first_out: Vec<u32>,
    pub(crate) arcs: Vec<UpArc>,
    /// Every edge ever created (for unpacking), endpoints as ranks.
    pub(crate) edges: Vec<Edge>,
    /// Tells this hierarchy's unpacked shortcuts in a [`ChQuery`] from another's.
    pub(crate) id: u64,
}

/// A new hierarchy's [`ContractionHierarchy::id`].
pub(crate) fn next_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// Shortcuts unpacked into at least this many nodes (both ends counted) are kept for the next
/// queries…
pub const MEMO_MIN_NODES: usize = 4;
/// …until the kept nodes and their spans take this many bytes, per [`ChQuery`] and kind
/// (ranks for the subgoal graph's hierarchy, cells for the grid's).
pub const MEMO_MAX_BYTES: usize = 32 << 20;

/// Shortcuts already unpacked, for the queries after: each as its nodes from `a` to `b` — ranks
/// (`T = u32`), or for the grid's own hierarchy the cells themselves (`T = Cell`), so that a
/// kept stretch of path is copied out with no lookup per cell.
#[derive(Debug)]
struct Memo<T> {
    /// The hierarchy they are of.
    of: u64,
    /// Per edge id: its span in `items`, or `NONE`.
    slot: Vec<u32>,
    /// Per span: its start in `items`, its length, and the edge's ends `a` and `b` (so a kept
    /// edge is walked without reading the edge).
    spans: Vec<(u32, u32, u32, u32)>,
    items: Vec<T>,
}

impl<T> Default for Memo<T> {
    fn default() -> Self {
        Self {
            of: 0,
            slot: Vec::new(),
            spans: Vec::new(),
            items: Vec::new(),
        }
    }
}

impl<T: Copy> Memo<T> {
    fn for_hierarchy(&mut self, ch: &ContractionHierarchy) {
        if self.of != ch.id || self.slot.len() != ch.edges.len() {
            self.of = ch.id;
            self.slot.clear();
            self.slot.resize(ch.edges.len(), NONE);
            self.spans.clear();
            self.items.clear();
        }
    }

    /// Appends edge `e` walked from its end `x`, if kept, and returns its other end.
    #[inline]
    fn extend(&self, e: u32, x: u32, out: &mut Vec<T>) -> Option<u32> {
        let k = self.slot[e as usize];
        if k == NONE {
            return None;
        }
        let (start, len, a, b) = self.spans[k as usize];
        let kept = &self.items[start as usize..(start + len) as usize];
        if x == a {
            out.extend_from_slice(&kept[1..]);
            Some(b)
        } else {
            out.extend(kept[..kept.len() - 1].iter().rev());
            Some(a)
        }
    }

    /// Keeps `walked`: edge `e` (from `a` to `b`) walked from `from` (whose node is `start`),
    /// without `from`.
    fn keep(&mut self, edge: &Edge, e: u32, from: u32, start: T, walked: &[T]) {
        let bytes = (self.items.len() + walked.len() + 1) * std::mem::size_of::<T>()
            + (self.spans.len() + 1) * std::mem::size_of::<(u32, u32, u32, u32)>();
        if walked.len() + 1 < MEMO_MIN_NODES
            || bytes > MEMO_MAX_BYTES
            || self.slot[e as usize] != NONE
        {
            return;
        }
        let at = self.items.len() as u32;
        if from == edge.a {
            self.items.push(start);
            self.items.extend_from_slice(walked);
        } else {
            // Walked from b: the items run b → a; kept a → b, with b (`start`) last.
            self.items.extend(walked.iter().rev());
            self.items.push(start);
        }
        self.slot[e as usize] = self.spans.len() as u32;
        self.spans
            .push((at, walked.len() as u32 + 1, edge.a, edge.b));
    }
}

/// One step of unpacking: walk edge `e` from `x`, or (`Keep`) what was appended since `at` is
/// edge `e` walked from `x`.
#[derive(Debug, Clone, Copy)]
enum Step {
    Walk { x: u32, e: u32 },
    Keep { x: u32, e: u32, at: u32 },
}

/// A rank's state in one direction of a query: valid when `stamp` is the query's.
#[derive(Debug, Clone, Copy, Default)]
struct Label {
    dist: u64,
    /// The edge it was reached by, or `NONE` for a root.
    parent: u32,
    stamp: u32,
}

/// Reusable buffers of [`ContractionHierarchy::search`] (one per thread).
#[derive(Debug, Default)]
pub struct ChQuery {
    /// Per direction, per rank: what the search knows of it (one cache line holds four).
    label: [Vec<Label>; 2],
    now: u32,
    heap: [BinaryHeap<Reverse<(u64, u32)>>; 2],
    stack: Vec<Step>,
    memo: Memo<u32>,
    cell_memo: Memo<Cell>,
}

impl ContractionHierarchy {
    /// Contracts every free cell of `grid` under `model` (all three move models).
    pub fn build(grid: Arc<Grid2>, model: MoveModel) -> Result<Self, ContractionError> {
        Self::build_until(grid, model, None)
    }

    /// [`ContractionHierarchy::build`] that gives up with [`ContractionError::Deadline`] once
    /// `deadline` has passed (checked before every contraction), so a caller with a time budget
    /// (a server) does not keep preprocessing an open map for minutes.
    ///
    /// ```
    /// use skyplan_cspace::{Grid2, GridFrame};
    /// use skyplan_search::{ContractionError, ContractionHierarchy, MoveModel};
    /// use std::sync::Arc;
    /// let grid = Arc::new(Grid2::new(64, 64, vec![false; 64 * 64], GridFrame::default())?);
    /// let past = std::time::Instant::now();
    /// let late = ContractionHierarchy::build_until(Arc::clone(&grid), MoveModel::Octile, Some(past));
    /// assert!(matches!(late, Err(ContractionError::Deadline { .. })));
    /// assert!(ContractionHierarchy::build_until(grid, MoveModel::Octile, None).is_ok());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn build_until(
        grid: Arc<Grid2>,
        model: MoveModel,
        deadline: Option<std::time::Instant>,
    ) -> Result<Self, ContractionError> {
        if grid.len() > MAX_CELLS {
            return Err(ContractionError::TooLarge {
                cells: grid.len(),
                max: MAX_CELLS,
            });
        }
        let mut b = Builder::new(&grid, model);
        b.contract_all(CORE_DEGREE, deadline)?;
        Ok(b.finish(grid, model))
    }

    /// A hierarchy over an undirected graph whose nodes stand on cells of `grid`
    /// (`node_cells`, grid cell indices, increasing) with `edges` `(a, b, cost)` between node
    /// numbers, each pair once: the subgoal graph's. Its unpacked paths are chains of nodes, not
    /// of neighbouring cells, so it is searched through [`Self::meet`] and [`Self::chain`], not
    /// [`Self::search`].
    pub(crate) fn build_graph(
        grid: Arc<Grid2>,
        model: MoveModel,
        node_cells: Vec<u32>,
        edges: &[(u32, u32, u64)],
        deadline: Option<std::time::Instant>,
    ) -> Result<Self, ContractionError> {
        let mut b = Builder::with_nodes(grid.len(), node_cells);
        for &(u, w, cost) in edges {
            b.add_edge(u, w, cost, NONE, NONE, NONE);
        }
        b.contract_all(CORE_DEGREE, deadline)?;
        Ok(b.finish(grid, model))
    }

    /// The rank of a grid cell index (`NONE` when the cell is no node).
    #[inline]
    pub(crate) fn rank_of(&self, cell_index: usize) -> u32 {
        self.rank_of_cell[cell_index]
    }

    /// The grid cell index of a rank.
    #[inline]
    pub(crate) fn cell_of(&self, rank: u32) -> u32 {
        self.cell_of_rank[rank as usize]
    }

    /// [`ContractionHierarchy::build`] with another core threshold (tests force large cores).
    #[cfg(test)]
    pub(crate) fn build_with_core(grid: Arc<Grid2>, model: MoveModel, core_degree: usize) -> Self {
        let mut b = Builder::new(&grid, model);
        // No deadline: cannot fail.
        let _ = b.contract_all(core_degree, None);
        b.finish(grid, model)
    }

    /// The grid this hierarchy was built for.
    pub fn grid(&self) -> &Arc<Grid2> {
        &self.grid
    }

    /// The move model it was built for.
    pub fn model(&self) -> MoveModel {
        self.model
    }

    /// Upward edges (original moves and shortcuts kept for queries).
    pub fn upward_edges(&self) -> usize {
        self.arcs.len()
    }

    /// Bytes held by the hierarchy (not counting the grid).
    pub fn table_bytes(&self) -> usize {
        (self.rank_of_cell.len() + self.cell_of_rank.len() + self.first_out.len()) * 4
            + self.arcs.len() * std::mem::size_of::<UpArc>()
            + self.edges.len() * std::mem::size_of::<Edge>()
    }

    /// An optimal path from `start` to `goal` with `query` as the workspace.
    pub fn search(
        &self,
        query: &mut ChQuery,
        start: Cell,
        goal: Cell,
    ) -> Result<GridPath, SearchError> {
        let grid = &*self.grid;
        crate::astar::check_endpoints(grid, start, goal)?;
        let s = self.rank_of_cell[grid.index(start)];
        let t = self.rank_of_cell[grid.index(goal)];
        if s == t {
            return Ok(GridPath {
                cells: vec![start],
                straight_moves: 0,
                diagonal_moves: 0,
                expansions: 0,
                any_angle_cells: None,
            });
        }
        let (meet, expansions) = self.meet(query, &[(s, 0)], &[(t, 0)]);
        let Some(meet) = meet else {
            return Err(SearchError::Unreachable { expansions });
        };
        let cells = self.chain_cells(query, meet);
        // Without a branch per move: random maps mix the two kinds unpredictably.
        let diagonal = (cells.windows(2))
            .map(|w| u64::from((w[0].row != w[1].row) & (w[0].col != w[1].col)))
            .sum::<u64>();
        let straight = cells.len() as u64 - 1 - diagonal;
        Ok(GridPath {
            cells,
            straight_moves: straight,
            diagonal_moves: diagonal,
            expansions,
            any_angle_cells: None,
        })
    }

    /// Appends the nodes (`item` of each rank) of edge `e` walked from `from` (excluding
    /// `from`); returns its far end. Shortcuts unpacked before with the same `memo` are copied,
    /// and those unpacked now are kept for the next queries (up to [`MEMO_MAX_BYTES`]).
    fn unpack<T: Copy>(
        &self,
        (stack, memo): (&mut Vec<Step>, &mut Memo<T>),
        (from, e): (u32, u32),
        out: &mut Vec<T>,
        item: &impl Fn(u32) -> T,
    ) -> u32 {
        memo.for_hierarchy(self);
        if let Some(end) = memo.extend(e, from, out) {
            return end;
        }
        stack.clear();
        stack.push(Step::Walk { x: from, e });
        let end = other(&self.edges[e as usize], from);
        while let Some(step) = stack.pop() {
            match step {
                Step::Keep { x, e, at } => {
                    memo.keep(&self.edges[e as usize], e, x, item(x), &out[at as usize..]);
                }
                Step::Walk { x, e } => {
                    if memo.extend(e, x, out).is_some() {
                        continue;
                    }
                    let edge = self.edges[e as usize];
                    if edge.mid == NONE {
                        out.push(item(other(&edge, x)));
                        continue;
                    }
                    // Walk x → mid → far end: push the second half first.
                    let (near, far) = if x == edge.a {
                        (edge.first, edge.second)
                    } else {
                        (edge.second, edge.first)
                    };
                    stack.push(Step::Keep {
                        x,
                        e,
                        at: out.len() as u32,
                    });
                    stack.push(Step::Walk {
                        x: edge.mid,
                        e: far,
                    });
                    stack.push(Step::Walk { x, e: near });
                }
            }
        }
        end
    }

    /// The ranks of the shortest path through `meet` found by the last [`Self::meet`] with
    /// `q`: from the forward search's root to the backward search's, shortcuts unpacked.
    pub(crate) fn chain(&self, q: &mut ChQuery, meet: u32) -> Vec<u32> {
        let ChQuery {
            label, stack, memo, ..
        } = q;
        self.chain_of(label, (stack, memo), meet, &|r| r)
    }

    /// Appends the ranks of edge `e` walked from its end `from` (without `from`), shortcuts
    /// unpacked (kept in `q` for later queries); returns its far end.
    pub(crate) fn unpack_ranks(
        &self,
        q: &mut ChQuery,
        from: u32,
        e: u32,
        out: &mut Vec<u32>,
    ) -> u32 {
        let ChQuery { stack, memo, .. } = q;
        self.unpack((stack, memo), (from, e), out, &|r| r)
    }

    /// [`Self::chain`] as the cells of the grid (this hierarchy's nodes are its free cells).
    fn chain_cells(&self, q: &mut ChQuery, meet: u32) -> Vec<Cell> {
        // Row and column by a multiply, not a divide (one per cell not kept yet).
        let by_cols = crate::astar::DivBy::new(self.grid.cols() as usize, self.grid.len());
        let cell = |r: u32| {
            let (row, col) = by_cols.div_rem(self.cell_of_rank[r as usize] as usize);
            Cell::new(row as u32, col as u32)
        };
        let ChQuery {
            label,
            stack,
            cell_memo,
            ..
        } = q;
        self.chain_of(label, (stack, cell_memo), meet, &cell)
    }

    fn chain_of<T: Copy>(
        &self,
        label: &[Vec<Label>; 2],
        (stack, memo): (&mut Vec<Step>, &mut Memo<T>),
        meet: u32,
        item: &impl Fn(u32) -> T,
    ) -> Vec<T> {
        // Edges root → meet (a reversed walk from meet), then meet → root.
        let mut up: Vec<u32> = Vec::new();
        let mut v = meet;
        loop {
            let e = label[0][v as usize].parent;
            if e == NONE {
                break;
            }
            up.push(e);
            v = other(&self.edges[e as usize], v);
        }
        let mut out = Vec::with_capacity(256);
        out.push(item(v));
        let mut at = v;
        for &e in up.iter().rev() {
            at = self.unpack((&mut *stack, &mut *memo), (at, e), &mut out, item);
        }
        let mut v = meet;
        loop {
            let e = label[1][v as usize].parent;
            if e == NONE {
                break;
            }
            v = self.unpack((&mut *stack, &mut *memo), (v, e), &mut out, item);
        }
        out
    }

    /// Bidirectional upward Dijkstra from several `sources` and `targets` (ranks with their
    /// initial distances, as if a super-source and a super-target were joined to them): the
    /// meeting rank of a shortest path (if any) and the nodes settled.
    pub(crate) fn meet(
        &self,
        q: &mut ChQuery,
        sources: &[(u32, u64)],
        targets: &[(u32, u64)],
    ) -> (Option<u32>, u64) {
        let n = self.cell_of_rank.len();
        for d in 0..2 {
            if q.label[d].len() != n {
                q.label[d] = vec![Label::default(); n];
            }
            q.heap[d].clear();
        }
        if q.now == u32::MAX {
            q.label.iter_mut().flatten().for_each(|l| l.stamp = 0);
            q.now = 0;
        }
        q.now += 1;
        let now = q.now;
        for (d, roots) in [(0, sources), (1, targets)] {
            for &(root, d0) in roots {
                let l = &mut q.label[d][root as usize];
                if l.stamp != now || d0 < l.dist {
                    *l = Label {
                        dist: d0,
                        parent: NONE,
                        stamp: now,
                    };
                    q.heap[d].push(Reverse((d0, root)));
                }
            }
        }
        let mut best = u64::MAX;
        let mut meet = None;
        let mut settled = 0u64;
        loop {
            let top = |h: &BinaryHeap<Reverse<(u64, u32)>>| h.peek().map_or(u64::MAX, |r| r.0.0);
            let (f, b) = (top(&q.heap[0]), top(&q.heap[1]));
            if f >= best && b >= best {
                break;
            }
            let d = usize::from(b < f);
            let Some(Reverse((du, u))) = q.heap[d].pop() else {
                break;
            };
            let ui = u as usize;
            let [forward, backward] = &mut q.label;
            let (mine, theirs) = if d == 0 {
                (forward, &*backward)
            } else {
                (backward, &*forward)
            };
            if du > mine[ui].dist {
                continue; // stale entry
            }
            settled += 1;
            let there = theirs[ui];
            if there.stamp == now {
                let total = du.saturating_add(there.dist);
                if total < best {
                    best = total;
                    meet = Some(u);
                }
            }
            let range = self.first_out[ui] as usize..self.first_out[ui + 1] as usize;
            // Stall on demand: a higher node reached more cheaply proves u is not on a shortest
            // upward path of this direction.
            let arcs = &self.arcs[range];
            let stalled = arcs.iter().any(|a| {
                let l = mine[a.head as usize];
                l.stamp == now && l.dist.saturating_add(a.cost) < du
            });
            if stalled {
                continue;
            }
            for a in arcs {
                let v = a.head as usize;
                let dv = du.saturating_add(a.cost);
                let l = &mut mine[v];
                if l.stamp != now || dv < l.dist {
                    *l = Label {
                        dist: dv,
                        parent: a.edge,
                        stamp: now,
                    };
                    q.heap[d].push(Reverse((dv, v as u32)));
                }
            }
        }
        (meet, settled)
    }
}

#[inline]
fn other(e: &Edge, x: u32) -> u32 {
    if e.a == x { e.b } else { e.a }
}

/// The contraction: the remaining graph, the edges made so far, and the witness searches.
struct Builder {
    /// Remaining graph: neighbour node and edge id, per node (nodes are free cells, numbered in
    /// cell order).
    adj: Vec<Vec<(u32, u32)>>,
    edges: Vec<Edge>,
    cost: Vec<u64>,
    cell_of_node: Vec<u32>,
    node_of_cell: Vec<u32>,
    rank: Vec<u32>,
    deleted_neighbours: Vec<u32>,
    level: Vec<u32>,
    /// Upward edges of each contracted node: (higher node, edge id).
    up: Vec<Vec<(u32, u32)>>,
    witness: Witness,
    shortcuts: Vec<(u32, u32, u64, u32, u32)>,
}

#[derive(Default)]
struct Witness {
    dist: Vec<u64>,
    stamp: Vec<u32>,
    /// `target[x] == now`: x is a neighbour the search must reach.
    target: Vec<u32>,
    now: u32,
    heap: BinaryHeap<Reverse<(u64, u32)>>,
}

impl Builder {
    /// No edges yet: one node per entry of `cell_of_node` (grid cell indices, increasing).
    fn with_nodes(cells: usize, cell_of_node: Vec<u32>) -> Self {
        let mut node_of_cell = vec![NONE; cells];
        for (node, &i) in cell_of_node.iter().enumerate() {
            node_of_cell[i as usize] = node as u32;
        }
        let n = cell_of_node.len();
        Self {
            adj: vec![Vec::with_capacity(8); n],
            edges: Vec::with_capacity(n * 8),
            cost: Vec::with_capacity(n * 8),
            cell_of_node,
            node_of_cell,
            rank: vec![NONE; n],
            deleted_neighbours: vec![0; n],
            level: vec![0; n],
            up: vec![Vec::new(); n],
            witness: Witness {
                dist: vec![0; n],
                stamp: vec![0; n],
                target: vec![0; n],
                now: 0,
                heap: BinaryHeap::new(),
            },
            shortcuts: Vec::new(),
        }
    }

    fn new(grid: &Grid2, model: MoveModel) -> Self {
        let (rows, cols) = (i64::from(grid.rows()), i64::from(grid.cols()));
        let free = (0..grid.len()).filter(|&i| !grid.is_blocked(grid.cell(i)));
        let mut b = Self::with_nodes(grid.len(), free.map(|i| i as u32).collect());
        let n = b.cell_of_node.len();
        let moves: &[(i64, i64)] = if model.has_diagonals() {
            &[(0, 1), (1, 0), (1, 1), (1, -1)]
        } else {
            &[(0, 1), (1, 0)]
        };
        for u in 0..n {
            let i = b.cell_of_node[u] as usize;
            let from = grid.cell(i);
            let (r, c) = (i64::from(from.row), i64::from(from.col));
            for &(dr, dc) in moves {
                let (nr, nc) = (r + dr, c + dc);
                if nr < 0 || nr >= rows || nc < 0 || nc >= cols || !grid.is_free_at(nr, nc) {
                    continue;
                }
                let diagonal = dr != 0 && dc != 0;
                if diagonal && !model.corner_ok(grid, from, dr, dc) {
                    continue;
                }
                let w = b.node_of_cell[(nr * cols + nc) as usize];
                let cost = if diagonal { DIAGONAL } else { STRAIGHT };
                b.add_edge(u as u32, w, cost, NONE, NONE, NONE);
            }
        }
        b
    }

    fn add_edge(&mut self, a: u32, b: u32, cost: u64, mid: u32, first: u32, second: u32) -> u32 {
        let id = self.edges.len() as u32;
        self.edges.push(Edge {
            a,
            b,
            mid,
            first,
            second,
        });
        self.cost.push(cost);
        self.adj[a as usize].push((b, id));
        self.adj[b as usize].push((a, id));
        id
    }

    /// Shortcuts contracting `v` would add, into `self.shortcuts`.
    fn find_shortcuts(&mut self, v: u32) {
        self.shortcuts.clear();
        let nbrs = std::mem::take(&mut self.adj[v as usize]);
        for (i, &(u, eu)) in nbrs.iter().enumerate() {
            if i + 1 == nbrs.len() {
                break;
            }
            let cu = self.cost[eu as usize];
            let limit = nbrs[i + 1..]
                .iter()
                .map(|&(_, ew)| cu + self.cost[ew as usize])
                .max()
                .unwrap_or(0);
            self.witness_search(u, v, limit, &nbrs[i + 1..]);
            for &(w, ew) in &nbrs[i + 1..] {
                let via = cu + self.cost[ew as usize];
                let wi = w as usize;
                let witnessed =
                    self.witness.stamp[wi] == self.witness.now && self.witness.dist[wi] <= via;
                if !witnessed {
                    self.shortcuts.push((u, w, via, eu, ew));
                }
            }
        }
        self.adj[v as usize] = nbrs;
    }

    /// Dijkstra from `source` avoiding `v` (whose adjacency is taken out), up to `limit`.
    fn witness_search(&mut self, source: u32, v: u32, limit: u64, targets: &[(u32, u32)]) {
        let w = &mut self.witness;
        w.now = w.now.wrapping_add(1);
        if w.now == 0 {
            w.stamp.iter_mut().for_each(|x| *x = 0);
            w.target.iter_mut().for_each(|x| *x = 0);
            w.now = 1;
        }
        let now = w.now;
        for &(t, _) in targets {
            w.target[t as usize] = now;
        }
        w.heap.clear();
        w.dist[source as usize] = 0;
        w.stamp[source as usize] = now;
        w.heap.push(Reverse((0, source)));
        let mut settled = 0u32;
        let mut left = targets.len();
        while let Some(Reverse((d, x))) = w.heap.pop() {
            if d > w.dist[x as usize] {
                continue;
            }
            if d > limit || settled >= WITNESS_SETTLE_LIMIT {
                break;
            }
            settled += 1;
            if w.target[x as usize] == now {
                left -= 1;
                if left == 0 {
                    break;
                }
            }
            for &(y, e) in &self.adj[x as usize] {
                if y == v {
                    continue;
                }
                let dy = d + self.cost[e as usize];
                let yi = y as usize;
                if dy <= limit && (w.stamp[yi] != now || dy < w.dist[yi]) {
                    w.stamp[yi] = now;
                    w.dist[yi] = dy;
                    w.heap.push(Reverse((dy, y)));
                }
            }
        }
    }

    fn priority(&mut self, v: u32) -> i64 {
        self.find_shortcuts(v);
        let added = self.shortcuts.len() as i64;
        let degree = self.adj[v as usize].len() as i64;
        4 * (added - degree)
            + 2 * i64::from(self.deleted_neighbours[v as usize])
            + i64::from(self.level[v as usize])
    }

    /// Contracts `v` with the shortcuts [`Builder::priority`] just found for it.
    fn contract(&mut self, v: u32, rank: u32) {
        let shortcuts = std::mem::take(&mut self.shortcuts);
        for &(u, w, cost, eu, ew) in &shortcuts {
            // Keep only the cheaper of an existing edge u – w and the shortcut.
            let existing = self.adj[u as usize].iter().position(|&(x, _)| x == w);
            // Shortcut u – v – w: first is u – v, second is v – w.
            let (first, second) = (eu, ew);
            match existing {
                Some(k) => {
                    let old = self.adj[u as usize][k].1;
                    if cost < self.cost[old as usize] {
                        let id = self.edges.len() as u32;
                        self.edges.push(Edge {
                            a: u,
                            b: w,
                            mid: v,
                            first,
                            second,
                        });
                        self.cost.push(cost);
                        self.adj[u as usize][k].1 = id;
                        if let Some(slot) = self.adj[w as usize].iter_mut().find(|(x, _)| *x == u) {
                            slot.1 = id;
                        }
                    }
                }
                None => {
                    self.add_edge(u, w, cost, v, first, second);
                }
            }
        }
        self.shortcuts = shortcuts;
        let nbrs = std::mem::take(&mut self.adj[v as usize]);
        for &(u, _) in &nbrs {
            let list = &mut self.adj[u as usize];
            if let Some(k) = list.iter().position(|&(x, _)| x == v) {
                list.swap_remove(k);
            }
            self.deleted_neighbours[u as usize] += 1;
            let lv = self.level[v as usize] + 1;
            if self.level[u as usize] < lv {
                self.level[u as usize] = lv;
            }
        }
        self.rank[v as usize] = rank;
        self.up[v as usize] = nbrs;
    }

    fn contract_all(
        &mut self,
        core_degree: usize,
        deadline: Option<std::time::Instant>,
    ) -> Result<(), ContractionError> {
        let n = self.adj.len() as u32;
        let late = |contracted: u32| match deadline {
            Some(d) if std::time::Instant::now() >= d => Err(ContractionError::Deadline {
                contracted: contracted as usize,
                nodes: n as usize,
            }),
            _ => Ok(()),
        };
        let mut heap = BinaryHeap::with_capacity(n as usize);
        for v in 0..n {
            if v.is_multiple_of(1024) {
                late(0)?;
            }
            heap.push(Reverse((self.priority(v), v)));
        }
        let mut rank = 0u32;
        while let Some(Reverse((p, v))) = heap.pop() {
            if self.rank[v as usize] != NONE {
                continue;
            }
            // Lazy update: contract v only if it is still the cheapest.
            let now = self.priority(v);
            if now > p
                && let Some(&Reverse((next, _))) = heap.peek()
                && now > next
            {
                heap.push(Reverse((now, v)));
                continue;
            }
            if self.adj[v as usize].len() > core_degree {
                break;
            }
            late(rank)?;
            self.contract(v, rank);
            rank += 1;
        }
        // The core: ranked above every contracted node, searched in both directions (each core
        // node keeps all its core neighbours as "upward" edges).
        for v in 0..n {
            if self.rank[v as usize] == NONE {
                self.rank[v as usize] = rank;
                rank += 1;
                self.up[v as usize] = self.adj[v as usize].clone();
            }
        }
        Ok(())
    }

    fn finish(self, grid: Arc<Grid2>, model: MoveModel) -> ContractionHierarchy {
        let n = self.rank.len();
        let mut cell_of_rank = vec![0u32; n];
        let mut rank_of_cell = vec![NONE; grid.len()];
        for v in 0..n {
            let r = self.rank[v];
            cell_of_rank[r as usize] = self.cell_of_node[v];
            rank_of_cell[self.cell_of_node[v] as usize] = r;
        }
        let mut first_out = Vec::with_capacity(n + 1);
        let mut arcs = Vec::new();
        let mut node_of_rank = vec![0u32; n];
        for v in 0..n {
            node_of_rank[self.rank[v] as usize] = v as u32;
        }
        for &v in &node_of_rank {
            first_out.push(arcs.len() as u32);
            for &(w, e) in &self.up[v as usize] {
                arcs.push(UpArc {
                    cost: self.cost[e as usize],
                    head: self.rank[w as usize],
                    edge: e,
                });
            }
        }
        first_out.push(arcs.len() as u32);
        let rank = &self.rank;
        let edges = self
            .edges
            .iter()
            .map(|e| Edge {
                a: rank[e.a as usize],
                b: rank[e.b as usize],
                mid: if e.mid == NONE {
                    NONE
                } else {
                    rank[e.mid as usize]
                },
                first: e.first,
                second: e.second,
            })
            .collect();
        ContractionHierarchy {
            grid,
            model,
            rank_of_cell,
            cell_of_rank,
            first_out,
            arcs,
            edges,
            id: next_id(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::dijkstra_exact;
    use proptest::prelude::*;
    use skyplan_cspace::GridFrame;

    fn grid_strategy() -> impl Strategy<Value = Grid2> {
        (1u32..20, 1u32..20, 0.0f64..0.4).prop_flat_map(|(rows, cols, density)| {
            proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize)
                .prop_map(move |b| Grid2::new(rows, cols, b, GridFrame::default()).unwrap())
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(500))]

        /// Large cores (searched in every direction) are as exact as full contraction: core
        /// thresholds 0 (no contraction: bidirectional Dijkstra), 2, 5 and the default.
        #[test]
        fn any_core_threshold_gives_the_oracle_costs(
            grid in grid_strategy(),
            ends in proptest::collection::vec((0u32..20, 0u32..20, 0u32..20, 0u32..20), 1..5),
        ) {
            let grid = Arc::new(grid);
            for model in [MoveModel::FourConnected, MoveModel::Octile, MoveModel::OctileCornerCutting] {
                for core in [0, 2, 5, CORE_DEGREE] {
                    let ch = ContractionHierarchy::build_with_core(Arc::clone(&grid), model, core);
                    let mut q = ChQuery::default();
                    for &(a, b, c, d) in &ends {
                        let s = Cell::new(a % grid.rows(), b % grid.cols());
                        let t = Cell::new(c % grid.rows(), d % grid.cols());
                        let got = ch.search(&mut q, s, t).ok().map(|p| {
                            prop_assert_eq!(crate::check_path(&grid, &p.cells, model), Ok(()));
                            prop_assert_eq!((p.cells.first(), p.cells.last()), (Some(&s), Some(&t)));
                            Ok((p.straight_moves, p.diagonal_moves))
                        }).transpose()?;
                        let want = dijkstra_exact(&grid, s, t, model).map(|c| (c.straight, c.diagonal));
                        prop_assert_eq!(got, want, "{:?} core {}", model, core);
                    }
                }
            }
        }
    }

    /// Shortcuts kept from earlier queries give the same paths as unpacking afresh, also when
    /// one workspace serves two hierarchies in turn; the costs are the oracle's.
    #[test]
    fn kept_shortcuts_give_the_paths_of_a_fresh_unpacking() {
        // A 120 × 120 grid, 30 % blocked (SplitMix64), long winding paths.
        let mut state = 5u64;
        let mut next = || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        };
        let (rows, cols) = (120u32, 120u32);
        let blocked: Vec<bool> = (0..rows * cols).map(|_| next() % 100 < 30).collect();
        let grid = Arc::new(Grid2::new(rows, cols, blocked, GridFrame::default()).unwrap());
        let octile = ContractionHierarchy::build(Arc::clone(&grid), MoveModel::Octile).unwrap();
        let four =
            ContractionHierarchy::build(Arc::clone(&grid), MoveModel::FourConnected).unwrap();
        let free: Vec<Cell> = (0..rows * cols)
            .map(|i| Cell::new(i / cols, i % cols))
            .filter(|&c| !grid.is_blocked(c))
            .collect();
        let mut shared = ChQuery::default();
        let (mut compared, mut kept_max) = (0, 0);
        for pass in 0..4 {
            let ch = if pass % 2 == 0 { &octile } else { &four };
            for k in 0..100 {
                let s = free[(next() % free.len() as u64) as usize];
                let t = free[(next() % free.len() as u64) as usize];
                let fresh = ch.search(&mut ChQuery::default(), s, t).ok();
                let again = ch.search(&mut shared, s, t).ok();
                kept_max = kept_max.max(shared.cell_memo.spans.len());
                assert_eq!(
                    fresh.as_ref().map(|p| &p.cells),
                    again.as_ref().map(|p| &p.cells),
                    "pass {pass}, query {k}"
                );
                if let Some(p) = &again {
                    assert_eq!(crate::check_path(&grid, &p.cells, ch.model()), Ok(()));
                    if k % 10 == 0 {
                        let want = dijkstra_exact(&grid, s, t, ch.model())
                            .map(|c| (c.straight, c.diagonal));
                        assert_eq!(Some((p.straight_moves, p.diagonal_moves)), want);
                    }
                    compared += 1;
                }
            }
        }
        assert!(compared > 300, "{compared}");
        // Shortcuts were kept and served (the workspace switched hierarchies and back).
        assert!(kept_max > 50, "{kept_max}");
    }

    #[test]
    fn integer_costs_are_a_convergent_of_root_two() {
        let (p, q) = (i128::from(DIAGONAL), i128::from(STRAIGHT));
        assert_eq!((p * p - 2 * q * q).abs(), 1);
        // Sums of two path costs of at most MAX_CELLS moves each fit in u64.
        assert!((2 * MAX_CELLS as u128) * u128::from(DIAGONAL) < u128::from(u64::MAX));
    }

    #[test]
    fn integer_order_is_exact_order_near_the_limit() {
        use crate::oracle::OctileCost;
        // Counts up to twice MAX_CELLS (sums of two paths), including the pairs whose real
        // costs are closest (Pell numbers x ≈ y√2) and a deterministic scatter.
        let m = 2 * MAX_CELLS as u64;
        let mut pairs = Vec::new();
        for (x, y) in [
            (1u64, 1u64),
            (3, 2),
            (7, 5),
            (17, 12),
            (1393, 985),
            (665_857, 470_832),
        ] {
            let scale = m / x.max(y);
            for k in [1, 2, scale - 1, scale] {
                pairs.push(((x * k, 0), (0, y * k)));
                pairs.push(((x * k, 1), (1, y * k)));
            }
        }
        let mut z = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            z ^= z << 13;
            z ^= z >> 7;
            z ^= z << 17;
            z % m
        };
        for _ in 0..100_000 {
            let (a, b, c) = (next(), next() / 2, next());
            let d = (a as f64 + b as f64 * std::f64::consts::SQRT_2 - c as f64)
                / std::f64::consts::SQRT_2;
            pairs.push(((a, b), (c, d.max(0.0).round() as u64 % m)));
        }
        for ((s1, d1), (s2, d2)) in pairs {
            let exact = OctileCost {
                straight: s1,
                diagonal: d1,
            }
            .cmp(&OctileCost {
                straight: s2,
                diagonal: d2,
            });
            let int = (s1 * STRAIGHT + d1 * DIAGONAL).cmp(&(s2 * STRAIGHT + d2 * DIAGONAL));
            assert_eq!(int, exact, "{s1} + {d1}√2 vs {s2} + {d2}√2");
        }
    }
}
