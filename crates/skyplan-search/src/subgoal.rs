//! Simple subgoal graphs (Uras, Koenig and Hernández, "Subgoal Graphs for Optimal Pathfinding
//! in Eight-Neighbor Grids", ICAPS 2013): exact shortest paths under [`MoveModel::Octile`] over
//! a graph of a grid's convex corners, for many queries on one grid.
//!
//! * A **subgoal** is a free cell at a convex corner of the obstacles: for some diagonal
//!   direction its two orthogonal neighbours are free and the diagonal neighbour is blocked.
//!   Shortest paths bend only at such cells.
//! * Two cells are **h-reachable** when a free path between them is as short as the octile
//!   distance, and **direct**-h-reachable when such a path passes no other subgoal. A shortest
//!   path with no subgoal inside it is as short as the octile distance (it never bends), so a
//!   shortest path is a chain of direct-h-reachable hops between subgoals.
//! * Preprocessing finds, for every subgoal, the subgoals direct-h-reachable from it: a flood
//!   from it that takes only moves that add their cost to the octile distance from it (so every
//!   cell reached is reached by an octile-length path) and stops at subgoals. Those pairs are
//!   the graph's edges, weighted by the exact integer octile distance
//!   ([`crate::CH_STRAIGHT_COST`], [`crate::CH_DIAGONAL_COST`]).
//! * A contraction hierarchy is built over that graph, and from it **hub labels**
//!   ([`crate::hub_labels`]): each subgoal's list of hubs with exact upward distances.
//! * The same floods tell, for every free cell, the subgoals direct-h-reachable from it (the
//!   relation is symmetric): its **roots**, kept per cell when they average at most
//!   [`ROOTS_PER_FREE_CELL`].
//! * A query takes the start's roots as sources and the goal's as targets, each with its octile
//!   distance (a subgoal end is its own root), and reads their labels: the cheapest
//!   source–hub–target sum is the shortest path through subgoals, walked up the labels to the
//!   hub and its shortcuts unpacked. When that is longer than the octile line, or there is none,
//!   a depth-first walk by the two moves an octile-length path takes tells whether the line is
//!   free without subgoals (then it is the path). Each hop is then walked into cells: the
//!   diagonal-first or straight-first shape when free, else a depth-first walk inside the hop's
//!   octile diamond.
//! * Without kept roots a query floods from both ends for them (reaching the start from the
//!   goal means the line is free); without labels (a hierarchy with a core, or more than
//!   [`LABEL_MAX_ENTRIES`] entries) it searches the hierarchy from both sets of roots.
//!
//! On mazes with corridors a few cells wide the graph keeps a few percent of the free cells
//! (7,234 of 209,242 on the generated 4-cell 512 × 512 maze), so its queries touch far fewer
//! nodes than a cell search; on rooms a query reads a few hundred to a few thousand label
//! entries. On open maps the floods cover large areas, so building costs more.

use crate::astar::check_endpoints;
use crate::contraction::{DIAGONAL, NONE, STRAIGHT};
use crate::first_move::MOVES;
use crate::hub_labels::{HubLabels, LabelQuery, LabelRefusal};
use crate::{ChQuery, ContractionError, ContractionHierarchy, GridPath, MoveModel, SearchError};
use skyplan_cspace::{Cell, Grid2};
use std::sync::Arc;

/// Why a subgoal graph was not built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SubgoalError {
    /// Subgoal graphs here cover the 8-connected model without corner cutting only.
    #[error("subgoal graphs need the 8-connected move model without corner cutting")]
    MoveModel,
    /// The grid is too large for exact integer costs.
    #[error("the grid has {cells} cells; a subgoal graph takes at most {max} cells")]
    TooLarge {
        /// Cells of the grid.
        cells: usize,
        /// [`crate::CH_MAX_CELLS`].
        max: usize,
    },
    /// The deadline passed during preprocessing.
    #[error("subgoal graph preprocessing passed its deadline after {done} of {subgoals} subgoals")]
    Deadline {
        /// Subgoals whose edges were found.
        done: usize,
        /// Subgoals in all.
        subgoals: usize,
    },
}

/// Every cell's roots less those another of its roots reaches at no extra cost (`c_u + d(u, v)
/// ≤ c_v`): a path through `v` is then never shorter than one through `u`, so the cheapest
/// source–target sum is unchanged (the relation has no cycles, distances between distinct
/// subgoals being positive, so dropping every dominated root at once keeps one that dominates
/// it). As `d(u, v) ≥ octile(u, v)` and `c_v ≤ c_u + octile(u, v)`, `u` dominates `v` exactly
/// when `c_u + octile(u, v) = c_v` (a cheap test of the cells) and `d(u, v) = octile(u, v)`
/// (by the labels, each pair once). On 16-cell rooms it keeps a third of the roots. `None`
/// once `deadline` has passed.
fn prune_dominated(
    labels: &HubLabels,
    ch: &ContractionHierarchy,
    cols: usize,
    (first, roots): (&[u32], &[u32]),
    deadline: Option<std::time::Instant>,
) -> Option<(Vec<u32>, Vec<u32>)> {
    let cells = first.len() - 1;
    let mut kept_first = Vec::with_capacity(first.len());
    let mut kept = Vec::with_capacity(roots.len() / 2);
    let mut straight: std::collections::HashMap<u64, bool, BuildWordHasher> =
        std::collections::HashMap::default();
    let mut at: Vec<(i32, i32, u64)> = Vec::new();
    for i in 0..cells {
        if i % 4096 == 0
            && let Some(d) = deadline
            && std::time::Instant::now() >= d
        {
            return None;
        }
        kept_first.push(kept.len() as u32);
        let set = &roots[first[i] as usize..first[i + 1] as usize];
        if set.len() < 2 {
            kept.extend_from_slice(set);
            continue;
        }
        let (r, c) = ((i / cols) as i32, (i % cols) as i32);
        at.clear();
        at.extend(set.iter().map(|&u| {
            let cell = ch.cell_of(u) as usize;
            let (ur, uc) = ((cell / cols) as i32, (cell % cols) as i32);
            (ur, uc, octile(ur - r, uc - c))
        }));
        for (j, &v) in set.iter().enumerate() {
            let (vr, vc, cv) = at[j];
            let dominated = set.iter().zip(&at).any(|(&u, &(ur, uc, cu))| {
                let line = octile(vr - ur, vc - uc);
                u != v
                    && cu + line == cv
                    && *straight
                        .entry(u64::from(u.min(v)) << 32 | u64::from(u.max(v)))
                        .or_insert_with(|| labels.distance(u, v) == Some(line))
            });
            if !dominated {
                kept.push(v);
            }
        }
    }
    kept_first.push(kept.len() as u32);
    kept.shrink_to_fit();
    Some((kept_first, kept))
}

/// A multiply-rotate hasher for [`prune_dominated`]'s pairs of roots (the standard hasher is
/// built against adversaries this map-local table does not face, and cost a third of the
/// pruning on 16-cell rooms).
#[derive(Default)]
struct WordHasher(u64);

impl std::hash::Hasher for WordHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(w));
        }
    }

    fn write_u64(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

type BuildWordHasher = std::hash::BuildHasherDefault<WordHasher>;

/// The moves an octile-length path from `a` to `b` is made of: the diagonal towards `b` and
/// the straight move along the longer side (one is useless, filtered by the octile test, when
/// `b` is on a line or a diagonal from `a`).
#[inline]
fn toward(a: (i32, i32), b: (i32, i32)) -> [(i32, i32); 2] {
    let (dr, dc) = ((b.0 - a.0).signum(), (b.1 - a.1).signum());
    let straight = if (b.0 - a.0).abs() > (b.1 - a.1).abs() {
        (dr, 0)
    } else {
        (0, dc)
    };
    [(dr, dc), straight]
}

/// Exact integer octile distance of a displacement.
#[inline]
fn octile(dr: i32, dc: i32) -> u64 {
    let (a, b) = (dr.unsigned_abs() as u64, dc.unsigned_abs() as u64);
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (hi - lo) * STRAIGHT + lo * DIAGONAL
}

/// A simple subgoal graph of one grid (module docs), owning its grid so a session can keep it.
#[derive(Debug)]
pub struct SubgoalGraph {
    grid: Arc<Grid2>,
    board: Board,
    /// Row and column of each node.
    rc_of_node: Vec<(i32, i32)>,
    /// Directed edges (both ways of each pair).
    edges: usize,
    /// The contraction hierarchy over the graph: queries run on it, or on its hub labels.
    ch: ContractionHierarchy,
    /// Hub labels of the hierarchy, when it has no core and they fit [`LABEL_MAX_ENTRIES`].
    labels: Option<HubLabels>,
    /// Per grid cell index, the ranks of the subgoals direct-h-reachable from it
    /// (`roots[roots_first[i]..roots_first[i + 1]]`; empty for subgoals, which are their own),
    /// when they fit [`ROOTS_PER_FREE_CELL`]; else (empty vectors) queries flood.
    roots_first: Vec<u32>,
    roots: Vec<u32>,
}

/// What a subgoal graph keeps besides its hierarchy.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Keep {
    /// The hierarchy's hub labels.
    labels: bool,
    /// Each cell's direct-h-reachable subgoals.
    roots: bool,
}

pub(crate) const KEEP_ALL: Keep = Keep {
    labels: true,
    roots: true,
};

/// Hub label entries (16 bytes each) a subgoal graph keeps at most: 256 MiB.
pub const LABEL_MAX_ENTRIES: usize = 1 << 24;

/// Direct-h-reachable subgoals kept per free cell on average, at most (4 bytes each); on open
/// ground each cell sees many corners, and queries flood instead.
pub const ROOTS_PER_FREE_CELL: usize = 48;

/// The grid with a blocked ring round it, and the subgoals on it: what floods and hop walks
/// read.
#[derive(Debug)]
struct Board {
    /// Bordered width: the grid's columns + 2.
    width: usize,
    /// Free cells of the bordered grid.
    free: Vec<bool>,
    /// Node of each bordered cell, or `NONE`.
    node_of: Vec<u32>,
}

/// The flood's and the search's reusable buffers for one thread ([`SubgoalGraph::search`]).
#[derive(Debug, Default)]
pub struct SubgoalQuery {
    /// Per bordered cell: visited stamp and parent (bordered cell) of the hop walk.
    stamp: Vec<u32>,
    from: Vec<u32>,
    now: u32,
    stack: Vec<(u32, i32, i32)>,
    /// The hierarchy's workspace, and the roots of its two searches (ranks, costs).
    ch: ChQuery,
    sources: Vec<(u32, u64)>,
    targets: Vec<(u32, u64)>,
    /// The hub labels' workspace.
    labels: LabelQuery,
}

impl SubgoalQuery {
    /// An empty workspace; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    fn fit(&mut self, cells: usize) {
        if self.stamp.len() != cells {
            self.stamp = vec![0; cells];
            self.from = vec![NONE; cells];
            self.now = 0;
        }
    }

    fn next_stamp(&mut self) -> u32 {
        self.now = self.now.wrapping_add(1);
        if self.now == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.now = 1;
        }
        self.now
    }
}

/// A grid's subgoals and what the floods from them found: the graph's edges and (unless over
/// the budget or not asked for) every cell's roots.
#[derive(Debug)]
pub(crate) struct Floods {
    board: Board,
    rc_of_node: Vec<(i32, i32)>,
    /// Grid cell index of each node, increasing.
    pub(crate) node_cells: Vec<u32>,
    /// Direct-h-reachable pairs `(u, v, cost)` with `u < v`.
    pub(crate) pairs: Vec<(u32, u32, u64)>,
    /// (grid cell index, node) for every non-subgoal cell a subgoal's flood reaches.
    seen: Option<Vec<(u32, u32)>>,
}

impl Floods {
    /// The subgoals of `grid` and a flood from each (module docs), giving up at `deadline`.
    pub(crate) fn run(
        grid: &Grid2,
        deadline: Option<std::time::Instant>,
        keep: Keep,
    ) -> Result<Self, SubgoalError> {
        if grid.len() > crate::CH_MAX_CELLS {
            return Err(SubgoalError::TooLarge {
                cells: grid.len(),
                max: crate::CH_MAX_CELLS,
            });
        }
        let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
        let width = cols + 2;
        let mut free = vec![false; (rows + 2) * width];
        for (r, row) in grid
            .blocked_cells()
            .chunks(cols.max(1))
            .take(rows)
            .enumerate()
        {
            for (c, &b) in row.iter().enumerate() {
                free[(r + 1) * width + c + 1] = !b;
            }
        }
        let at = |r: usize, c: usize| (r + 1) * width + c + 1;
        let corner = |r: usize, c: usize| {
            MOVES[4..].iter().any(|&(dr, dc)| {
                let (r2, c2) = ((r as i32 + 1 + dr) as usize, (c as i32 + 1 + dc) as usize);
                free[r2 * width + c + 1] && free[(r + 1) * width + c2] && !free[r2 * width + c2]
            })
        };
        let mut node_of = vec![NONE; free.len()];
        let mut rc_of_node = Vec::new();
        let mut node_cells = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                if free[at(r, c)] && corner(r, c) {
                    node_of[at(r, c)] = rc_of_node.len() as u32;
                    rc_of_node.push((r as i32, c as i32));
                    node_cells.push((r * cols + c) as u32);
                }
            }
        }
        let n = rc_of_node.len();
        let board = Board {
            width,
            free,
            node_of,
        };
        let mut q = SubgoalQuery::new();
        q.fit(board.free.len());
        let mut pairs: Vec<(u32, u32, u64)> = Vec::new();
        let mut reached = Vec::new();
        // (grid cell index, node) for every non-subgoal cell a subgoal's flood reaches: the
        // subgoals direct-h-reachable from each cell (the relation is symmetric).
        let free_cells = grid.blocked_cells().iter().filter(|&&b| !b).count();
        let roots_budget = free_cells.saturating_mul(ROOTS_PER_FREE_CELL);
        let mut seen: Option<Vec<(u32, u32)>> = keep.roots.then(Vec::new);
        for (u, &(r, c)) in rc_of_node.iter().enumerate() {
            if u % 64 == 0
                && let Some(d) = deadline
                && std::time::Instant::now() >= d
            {
                return Err(SubgoalError::Deadline {
                    done: u,
                    subgoals: n,
                });
            }
            reached.clear();
            board.flood(&mut q, r, c, |r2, c2, node, cost| {
                if node != NONE {
                    reached.push((node, cost));
                } else if let Some(seen) = seen.as_mut() {
                    seen.push(((r2 as usize * cols + c2 as usize) as u32, u as u32));
                }
            });
            if seen.as_ref().is_some_and(|s| s.len() > roots_budget) {
                seen = None;
            }
            pairs.extend(
                (reached.iter())
                    .filter(|&&(v, _)| v as usize > u)
                    .map(|&(v, cost)| (u as u32, v, cost)),
            );
        }
        Ok(Self {
            board,
            rc_of_node,
            node_cells,
            pairs,
            seen,
        })
    }
}

impl SubgoalGraph {
    /// Builds the graph of `grid` under `model` (only [`MoveModel::Octile`]).
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_search::{GridSearch, MoveModel, Planner, SubgoalGraph, SubgoalQuery};
    /// use std::sync::Arc;
    /// let grid = Arc::new(Grid2::from_ascii("......\n.####.\n......\n###...")?);
    /// let graph = SubgoalGraph::build(Arc::clone(&grid), MoveModel::Octile)?;
    /// assert_eq!(graph.subgoals(), 5); // the cells diagonal to the walls' convex corners
    /// let path = graph.search(&mut SubgoalQuery::new(), Cell::new(0, 2), Cell::new(3, 3))?;
    /// let reference = GridSearch::new().search(&grid, Cell::new(0, 2), Cell::new(3, 3), MoveModel::Octile, Planner::AStar)?;
    /// assert_eq!(path.cost_cells(), reference.cost_cells());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn build(grid: Arc<Grid2>, model: MoveModel) -> Result<Self, SubgoalError> {
        Self::build_until(grid, model, None)
    }

    /// [`SubgoalGraph::build`] that gives up with [`SubgoalError::Deadline`] once `deadline`
    /// has passed (checked every 64 subgoals).
    pub fn build_until(
        grid: Arc<Grid2>,
        model: MoveModel,
        deadline: Option<std::time::Instant>,
    ) -> Result<Self, SubgoalError> {
        Self::build_keeping(grid, model, deadline, KEEP_ALL)
    }

    /// [`Self::build_until`], keeping the hub labels and the cells' roots only where `keep`
    /// says (tests check the searches without them too).
    fn build_keeping(
        grid: Arc<Grid2>,
        model: MoveModel,
        deadline: Option<std::time::Instant>,
        keep: Keep,
    ) -> Result<Self, SubgoalError> {
        if model != MoveModel::Octile {
            return Err(SubgoalError::MoveModel);
        }
        let mut floods = Floods::run(&grid, deadline, keep)?;
        let n = floods.rc_of_node.len();
        // The hierarchy keeps the node cells (the graph needs them no more).
        let ch = ContractionHierarchy::build_graph(
            Arc::clone(&grid),
            model,
            std::mem::take(&mut floods.node_cells),
            &floods.pairs,
            deadline,
        )
        .map_err(|e| match e {
            ContractionError::Deadline { .. } => SubgoalError::Deadline {
                done: n,
                subgoals: n,
            },
            ContractionError::TooLarge { cells, max } => SubgoalError::TooLarge { cells, max },
        })?;
        Self::assemble(grid, floods, ch, deadline, keep)
    }

    /// The graph from its floods and the hierarchy over their pairs (built, or read from a
    /// file): hub labels and kept roots as `keep` says.
    pub(crate) fn assemble(
        grid: Arc<Grid2>,
        floods: Floods,
        ch: ContractionHierarchy,
        deadline: Option<std::time::Instant>,
        keep: Keep,
    ) -> Result<Self, SubgoalError> {
        let Floods {
            board,
            rc_of_node,
            node_cells: _,
            pairs,
            seen,
        } = floods;
        let n = rc_of_node.len();
        let cols = grid.cols() as usize;
        let labels = match HubLabels::build(&ch, LABEL_MAX_ENTRIES, deadline) {
            Ok(_) if !keep.labels => None,
            Ok(labels) => Some(labels),
            Err(LabelRefusal::Deadline) => {
                return Err(SubgoalError::Deadline {
                    done: n,
                    subgoals: n,
                });
            }
            Err(LabelRefusal::Core | LabelRefusal::TooLarge) => None,
        };
        let (roots_first, roots) = match seen {
            Some(seen) => {
                // Counting sort by cell; each cell's roots as ranks.
                let mut first = vec![0u32; grid.len() + 1];
                for &(cell, _) in &seen {
                    first[cell as usize + 1] += 1;
                }
                for i in 0..grid.len() {
                    first[i + 1] += first[i];
                }
                let mut at = first.clone();
                let mut roots = vec![0u32; seen.len()];
                for &(cell, node) in &seen {
                    let (r, c) = rc_of_node[node as usize];
                    roots[at[cell as usize] as usize] = ch.rank_of(r as usize * cols + c as usize);
                    at[cell as usize] += 1;
                }
                match &labels {
                    Some(labels) => prune_dominated(labels, &ch, cols, (&first, &roots), deadline)
                        .ok_or(SubgoalError::Deadline {
                            done: n,
                            subgoals: n,
                        })?,
                    None => (first, roots),
                }
            }
            None => (Vec::new(), Vec::new()),
        };
        Ok(Self {
            grid,
            board,
            rc_of_node,
            edges: 2 * pairs.len(),
            ch,
            labels,
            roots_first,
            roots,
        })
    }

    /// The grid this graph was built for.
    pub fn grid(&self) -> &Arc<Grid2> {
        &self.grid
    }

    /// The hierarchy over the graph (what its file holds).
    pub(crate) fn hierarchy(&self) -> &ContractionHierarchy {
        &self.ch
    }

    /// The number of subgoals (the graph's nodes).
    pub fn subgoals(&self) -> usize {
        self.rc_of_node.len()
    }

    /// The number of directed edges (both ways of each direct-h-reachable pair).
    pub fn edges(&self) -> usize {
        self.edges
    }

    /// Bytes held by the graph and its hierarchy (not counting the grid).
    pub fn table_bytes(&self) -> usize {
        self.board.free.len() * (1 + 4)
            + self.rc_of_node.len() * 8
            + self.ch.table_bytes()
            + self.labels.as_ref().map_or(0, HubLabels::bytes)
            + (self.roots_first.len() + self.roots.len()) * 4
    }

    /// Entries of the hub labels (0 when queries search the hierarchy instead).
    pub fn label_entries(&self) -> usize {
        self.labels.as_ref().map_or(0, HubLabels::entries)
    }

    /// True if queries read hub labels from kept roots (no search, no flood): the fast case.
    pub fn labelled(&self) -> bool {
        self.labels.is_some() && !self.roots_first.is_empty()
    }

    /// Direct-h-reachable subgoals kept for the grid's cells (0 when queries flood instead).
    pub fn kept_roots(&self) -> usize {
        self.roots.len()
    }

    /// An optimal path from `start` to `goal` under [`MoveModel::Octile`], with `query` as the
    /// workspace.
    pub fn search(
        &self,
        query: &mut SubgoalQuery,
        start: Cell,
        goal: Cell,
    ) -> Result<GridPath, SearchError> {
        check_endpoints(&self.grid, start, goal)?;
        query.fit(self.board.free.len());
        if self.roots_first.is_empty() {
            return self.search_flooding(query, start, goal);
        }
        let (s, t) = (
            (start.row as i32, start.col as i32),
            (goal.row as i32, goal.col as i32),
        );
        if s == t {
            return Ok(self.board.walk(query, &[s, t]));
        }
        let mut roots = std::mem::take(&mut query.sources);
        self.roots_of(s, &mut roots);
        query.sources = roots;
        let mut roots = std::mem::take(&mut query.targets);
        self.roots_of(t, &mut roots);
        query.targets = roots;
        let (ranks, work) = self.chain(query);
        let hops = ranks.map(|ranks| self.hops(s, &ranks, t));
        // A path through subgoals as short as the octile line is optimal; otherwise the line
        // may still be free (a path with no subgoal on it never bends).
        let line = octile(t.0 - s.0, t.1 - s.1);
        let longer = hops.as_ref().is_none_or(|h| {
            h.windows(2)
                .map(|w| octile(w[1].0 - w[0].0, w[1].1 - w[0].1))
                .sum::<u64>()
                > line
        });
        if longer && self.board.reaches(query, s, t) {
            let mut path = self.board.walk(query, &[s, t]);
            path.expansions = work;
            return Ok(path);
        }
        let Some(hops) = hops else {
            return Err(SearchError::Unreachable { expansions: work });
        };
        let mut path = self.board.walk(query, &hops);
        path.expansions = work;
        Ok(path)
    }

    /// The roots of free cell `(r, c)` from the kept lists: itself if a subgoal, else the
    /// subgoals direct-h-reachable from it, as ranks with their octile distance.
    fn roots_of(&self, (r, c): (i32, i32), out: &mut Vec<(u32, u64)>) {
        out.clear();
        let cols = self.grid.cols() as i32;
        let i = (r * cols + c) as usize;
        if self.board.node_of[self.board.at(r, c)] != NONE {
            out.push((self.ch.rank_of(i), 0));
            return;
        }
        let kept = &self.roots[self.roots_first[i] as usize..self.roots_first[i + 1] as usize];
        out.extend(kept.iter().map(|&k| {
            let cell = self.ch.cell_of(k) as i32;
            (k, octile(cell / cols - r, cell % cols - c))
        }));
    }

    /// The ranks of a cheapest chain of subgoals from one of the query's sources to one of its
    /// targets (by the hub labels, else by the hierarchy's search), and the work done (label
    /// entries read, or nodes settled).
    fn chain(&self, q: &mut SubgoalQuery) -> (Option<Vec<u32>>, u64) {
        if let Some(labels) = &self.labels {
            let (meet, read) = labels.meet(&mut q.labels, &q.sources, &q.targets);
            let Some(m) = meet else {
                return (None, read);
            };
            let mut up = vec![q.sources[m.source].0];
            let mut down = vec![q.targets[m.target].0];
            if labels
                .climb(&self.ch, &mut q.ch, up[0], m.hub, &mut up)
                .is_some()
                && labels
                    .climb(&self.ch, &mut q.ch, down[0], m.hub, &mut down)
                    .is_some()
            {
                down.pop();
                up.extend(down.iter().rev());
                return (Some(up), read);
            }
            // Labels always hold the paths to their hubs; the search below is a safety net.
            debug_assert!(false, "a hub label's path is broken");
        }
        let (meet, settled) = self.ch.meet(&mut q.ch, &q.sources, &q.targets);
        (meet.map(|m| self.ch.chain(&mut q.ch, m)), settled)
    }

    /// The hops start → the chain's subgoals → goal, as rows and columns.
    fn hops(&self, s: (i32, i32), ranks: &[u32], t: (i32, i32)) -> Vec<(i32, i32)> {
        let cols = self.grid.cols() as i32;
        let mut hops = Vec::with_capacity(ranks.len() + 2);
        hops.push(s);
        hops.extend(ranks.iter().map(|&k| {
            let i = self.ch.cell_of(k) as i32;
            (i / cols, i % cols)
        }));
        hops.push(t);
        hops.dedup();
        hops
    }

    /// [`Self::search`] on a graph without kept roots: the roots are found by floods from both
    /// ends.
    fn search_flooding(
        &self,
        query: &mut SubgoalQuery,
        start: Cell,
        goal: Cell,
    ) -> Result<GridPath, SearchError> {
        let cols = self.grid.cols() as i32;
        let (sr, sc) = (start.row as i32, start.col as i32);
        let (tr, tc) = (goal.row as i32, goal.col as i32);
        let (s, t) = (self.board.at(sr, sc), self.board.at(tr, tc));
        // Targets: the goal itself when it is a subgoal, and the subgoals it reaches, with
        // their octile distance to it. Reaching the start means the octile line is free.
        let mut direct = s == t;
        let mut roots = std::mem::take(&mut query.targets);
        roots.clear();
        if self.board.node_of[t] != NONE {
            roots.push((self.ch.rank_of((tr * cols + tc) as usize), 0));
        }
        self.board.flood(query, tr, tc, |r, c, node, cost| {
            direct |= (r, c) == (sr, sc);
            if node != NONE {
                roots.push((self.ch.rank_of((r * cols + c) as usize), cost));
            }
        });
        query.targets = roots;
        if direct {
            return Ok(self.board.walk(query, &[(sr, sc), (tr, tc)]));
        }
        let mut roots = std::mem::take(&mut query.sources);
        roots.clear();
        if self.board.node_of[s] != NONE {
            roots.push((self.ch.rank_of((sr * cols + sc) as usize), 0));
        } else {
            self.board.flood(query, sr, sc, |r, c, node, cost| {
                if node != NONE {
                    roots.push((self.ch.rank_of((r * cols + c) as usize), cost));
                }
            });
        }
        query.sources = roots;
        let (ranks, expansions) = self.chain(query);
        let Some(ranks) = ranks else {
            return Err(SearchError::Unreachable { expansions });
        };
        let hops = self.hops((sr, sc), &ranks, (tr, tc));
        let mut path = self.board.walk(query, &hops);
        path.expansions = expansions;
        Ok(path)
    }
}

impl Board {
    #[inline]
    fn at(&self, r: i32, c: i32) -> usize {
        (r + 1) as usize * self.width + (c + 1) as usize
    }

    #[inline]
    fn free_at(&self, r: i32, c: i32) -> bool {
        self.free[self.at(r, c)]
    }

    /// True if the move (dr, dc) from free (r, c) is allowed: the target free and, for a
    /// diagonal, both orthogonal neighbours free.
    #[inline]
    fn can_move(&self, r: i32, c: i32, dr: i32, dc: i32) -> bool {
        self.free_at(r + dr, c + dc)
            && (dr == 0 || dc == 0 || (self.free_at(r + dr, c) && self.free_at(r, c + dc)))
    }

    /// Floods from free (r0, c0) by moves that add their cost to the octile distance from it,
    /// not through subgoals; calls `visit(row, column, node or NONE, octile cost)` once for
    /// every cell reached (subgoals are reached, not passed).
    fn flood(
        &self,
        q: &mut SubgoalQuery,
        r0: i32,
        c0: i32,
        mut visit: impl FnMut(i32, i32, u32, u64),
    ) {
        let now = q.next_stamp();
        let origin = self.at(r0, c0);
        q.stamp[origin] = now;
        q.stack.clear();
        q.stack.push((origin as u32, r0, c0));
        while let Some((_, r, c)) = q.stack.pop() {
            let here = octile(r - r0, c - c0);
            for (k, &(dr, dc)) in MOVES.iter().enumerate() {
                let (nr, nc) = (r + dr, c + dc);
                let step = if k < 4 { STRAIGHT } else { DIAGONAL };
                let there = octile(nr - r0, nc - c0);
                if there != here + step || !self.can_move(r, c, dr, dc) {
                    continue;
                }
                let y = self.at(nr, nc);
                if q.stamp[y] == now {
                    continue;
                }
                q.stamp[y] = now;
                let node = self.node_of[y];
                visit(nr, nc, node, there);
                if node == NONE {
                    q.stack.push((y as u32, nr, nc));
                }
            }
        }
    }

    /// True if free `b` is h-reachable from free `a` through no subgoal (a depth-first walk
    /// by the only two moves an octile-length path from `a` to `b` takes: the diagonal and the
    /// straight move towards `b`).
    fn reaches(&self, q: &mut SubgoalQuery, a: (i32, i32), b: (i32, i32)) -> bool {
        let moves = toward(a, b);
        let total = octile(b.0 - a.0, b.1 - a.1);
        let now = q.next_stamp();
        let (origin, target) = (self.at(a.0, a.1), self.at(b.0, b.1));
        if origin == target {
            return true;
        }
        q.stamp[origin] = now;
        q.stack.clear();
        q.stack.push((origin as u32, a.0, a.1));
        while let Some((_, r, c)) = q.stack.pop() {
            let here = octile(r - a.0, c - a.1);
            for (mr, mc) in moves {
                let (nr, nc) = (r + mr, c + mc);
                let step = if mr != 0 && mc != 0 {
                    DIAGONAL
                } else {
                    STRAIGHT
                };
                let there = here + step;
                if octile(nr - a.0, nc - a.1) != there
                    || there + octile(b.0 - nr, b.1 - nc) != total
                    || !self.can_move(r, c, mr, mc)
                {
                    continue;
                }
                let y = self.at(nr, nc);
                if y == target {
                    return true;
                }
                if q.stamp[y] == now || self.node_of[y] != NONE {
                    continue;
                }
                q.stamp[y] = now;
                q.stack.push((y as u32, nr, nc));
            }
        }
        false
    }

    /// The cells of a chain of h-reachable hops. Every octile-length path of a hop has the
    /// same numbers of straight and diagonal moves, so they are counted per hop.
    fn walk(&self, q: &mut SubgoalQuery, hops: &[(i32, i32)]) -> GridPath {
        let mut cells = vec![Cell::new(hops[0].0 as u32, hops[0].1 as u32)];
        let (mut straight, mut diagonal) = (0u64, 0u64);
        for pair in hops.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let (adr, adc) = ((b.0 - a.0).unsigned_abs(), (b.1 - a.1).unsigned_abs());
            diagonal += u64::from(adr.min(adc));
            straight += u64::from(adr.max(adc) - adr.min(adc));
            self.hop(q, a, b, &mut cells);
        }
        GridPath {
            cells,
            straight_moves: straight,
            diagonal_moves: diagonal,
            expansions: 0,
            any_angle_cells: None,
        }
    }

    /// Appends the cells (without `a`) of an octile-length free path from `a` to h-reachable
    /// `b`.
    fn hop(&self, q: &mut SubgoalQuery, a: (i32, i32), b: (i32, i32), out: &mut Vec<Cell>) {
        let (dr, dc) = ((b.0 - a.0).signum(), (b.1 - a.1).signum());
        let (adr, adc) = ((b.0 - a.0).abs(), (b.1 - a.1).abs());
        let diagonals = adr.min(adc);
        let (sr, sc) = if adr > adc { (dr, 0) } else { (0, dc) };
        let straights = adr.max(adc) - diagonals;
        let width = self.width as isize;
        // Diagonal first, then straight; else straight first, then diagonal.
        for shape in [
            [(dr, dc, diagonals), (sr, sc, straights)],
            [(sr, sc, straights), (dr, dc, diagonals)],
        ] {
            let start = out.len();
            let (mut r, mut c) = a;
            let mut i = self.at(r, c) as isize;
            let mut ok = true;
            'legs: for (mr, mc, times) in shape {
                let (row_step, col_step) = (mr as isize * width, mc as isize);
                let diagonal = mr != 0 && mc != 0;
                for _ in 0..times {
                    let j = i + row_step + col_step;
                    if !self.free[j as usize]
                        || (diagonal
                            && !(self.free[(i + row_step) as usize]
                                && self.free[(i + col_step) as usize]))
                    {
                        ok = false;
                        break 'legs;
                    }
                    i = j;
                    r += mr;
                    c += mc;
                    out.push(Cell::new(r as u32, c as u32));
                }
            }
            if ok {
                return;
            }
            out.truncate(start);
        }
        // A depth-first walk inside the octile diamond of a and b.
        let total = octile(b.0 - a.0, b.1 - a.1);
        let now = q.next_stamp();
        let (origin, target) = (self.at(a.0, a.1), self.at(b.0, b.1));
        q.stamp[origin] = now;
        q.from[origin] = NONE;
        q.stack.clear();
        q.stack.push((origin as u32, a.0, a.1));
        while let Some((x, r, c)) = q.stack.pop() {
            if x as usize == target {
                break;
            }
            let here = octile(r - a.0, c - a.1);
            // Straight pushed first: the diagonal is tried first.
            for (mr, mc) in toward(a, b).into_iter().rev() {
                let (nr, nc) = (r + mr, c + mc);
                let there = here
                    + if mr != 0 && mc != 0 {
                        DIAGONAL
                    } else {
                        STRAIGHT
                    };
                if octile(nr - a.0, nc - a.1) != there
                    || there + octile(b.0 - nr, b.1 - nc) != total
                    || !self.can_move(r, c, mr, mc)
                {
                    continue;
                }
                let y = self.at(nr, nc);
                if q.stamp[y] == now {
                    continue;
                }
                q.stamp[y] = now;
                q.from[y] = x;
                q.stack.push((y as u32, nr, nc));
            }
        }
        let start = out.len();
        let mut y = target;
        // The walk reached `target` (the hop is h-reachable); the stamp guard only keeps a
        // broken invariant from looping.
        debug_assert_eq!(q.stamp[target], now, "hop not h-reachable");
        while y != origin && q.stamp[y] == now {
            let (r, c) = ((y / self.width) as u32 - 1, (y % self.width) as u32 - 1);
            out.push(Cell::new(r, c));
            y = q.from[y] as usize;
        }
        out[start..].reverse();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::dijkstra_exact;
    use proptest::prelude::*;
    use skyplan_cspace::GridFrame;

    fn grid_strategy() -> impl Strategy<Value = Grid2> {
        (1u32..24, 1u32..24, 0.0f64..0.45).prop_flat_map(|(rows, cols, density)| {
            proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize)
                .prop_map(move |b| Grid2::new(rows, cols, b, GridFrame::default()).unwrap())
        })
    }

    /// The graph of `grid` with and without hub labels and kept roots (searched by the
    /// hierarchy, and with floods from both ends, instead).
    fn every_kind(grid: &Arc<Grid2>) -> Vec<SubgoalGraph> {
        let kinds = [(true, true), (true, false), (false, true), (false, false)];
        kinds
            .into_iter()
            .map(|(labels, roots)| {
                let keep = Keep { labels, roots };
                let graph =
                    SubgoalGraph::build_keeping(Arc::clone(grid), MoveModel::Octile, None, keep)
                        .unwrap();
                assert_eq!(graph.labels.is_some(), labels);
                assert_eq!(graph.roots_first.is_empty(), !roots);
                graph
            })
            .collect()
    }

    /// The path's moves and ends against the exact Dijkstra oracle's, and the path re-checked
    /// cell by cell.
    fn agrees(
        graph: &SubgoalGraph,
        q: &mut SubgoalQuery,
        s: Cell,
        t: Cell,
    ) -> Result<(), TestCaseError> {
        let grid = graph.grid();
        let got = graph
            .search(q, s, t)
            .ok()
            .map(|p| {
                prop_assert_eq!(crate::check_path(grid, &p.cells, MoveModel::Octile), Ok(()));
                prop_assert_eq!((p.cells.first(), p.cells.last()), (Some(&s), Some(&t)));
                Ok((p.straight_moves, p.diagonal_moves))
            })
            .transpose()?;
        let want = dijkstra_exact(grid, s, t, MoveModel::Octile).map(|c| (c.straight, c.diagonal));
        prop_assert_eq!(got, want, "{:?} → {:?}", s, t);
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(if std::env::var_os("CI").is_some() { 1500 } else { 400 }))]

        /// Random grids (scattered blocks, 0–45 %), free and blocked ends alike: the oracle's
        /// moves, or no path (or the endpoint error) where it has none.
        #[test]
        fn random_grids_give_the_oracle_paths(
            grid in grid_strategy(),
            ends in proptest::collection::vec((0u32..24, 0u32..24, 0u32..24, 0u32..24), 1..8),
        ) {
            let grid = Arc::new(grid);
            for graph in every_kind(&grid) {
                let mut q = SubgoalQuery::new();
                for &(a, b, c, d) in &ends {
                    let s = Cell::new(a % grid.rows(), b % grid.cols());
                    let t = Cell::new(c % grid.rows(), d % grid.cols());
                    if grid.is_blocked(s) || grid.is_blocked(t) {
                        prop_assert!(graph.search(&mut q, s, t).is_err());
                        continue;
                    }
                    agrees(&graph, &mut q, s, t)?;
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(if std::env::var_os("CI").is_some() { 60 } else { 20 }))]

        /// Mazes with corridors 1–5 cells wide (the maps subgoal graphs are for): every query
        /// from a handful of starts to every 7th free cell.
        #[test]
        fn mazes_give_the_oracle_paths(corridor in 1usize..6, seed in 0u64..1000) {
            let maze = skyplan_map::maze::generate(&skyplan_map::maze::MazeSpec {
                width: 41,
                height: 37,
                corridor_cells: corridor,
                seed,
            })
            .unwrap();
            let blocked = maze.passable.iter().map(|&p| !p).collect();
            let grid = Grid2::new(37, 41, blocked, GridFrame::default()).unwrap();
            let free: Vec<Cell> = (0..grid.len()).map(|i| grid.cell(i)).filter(|&c| !grid.is_blocked(c)).collect();
            for graph in every_kind(&Arc::new(grid)) {
                let mut q = SubgoalQuery::new();
                for &s in free.iter().step_by(151) {
                    for &t in free.iter().step_by(11) {
                        agrees(&graph, &mut q, s, t)?;
                    }
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(if std::env::var_os("CI").is_some() { 8 } else { 3 }))]

        /// Rooms (8 or 12 cells, doors 2 or 3 wide), where a cell sees many corners through
        /// the doors and most of its roots are dominated: the searches with pruned roots, with
        /// all of them and with floods give the oracle's paths, and pruning drops roots.
        #[test]
        fn rooms_give_the_oracle_paths_with_pruned_roots(room in prop_oneof![Just(8usize), Just(12)], seed in 0u64..1000) {
            let map = skyplan_map::maze::generate_rooms(&skyplan_map::maze::RoomsSpec {
                width: 48,
                height: 45,
                room_cells: room,
                door_cells: room / 4,
                seed,
            })
            .unwrap();
            let blocked = map.passable.iter().map(|&p| !p).collect();
            let grid = Grid2::new(45, 48, blocked, GridFrame::default()).unwrap();
            let free: Vec<Cell> = (0..grid.len()).map(|i| grid.cell(i)).filter(|&c| !grid.is_blocked(c)).collect();
            let graphs = every_kind(&Arc::new(grid));
            // Labels and roots: pruned; roots without labels: all of them.
            prop_assert!(graphs[0].kept_roots() < graphs[2].kept_roots(), "{} of {}", graphs[0].kept_roots(), graphs[2].kept_roots());
            for graph in graphs {
                let mut q = SubgoalQuery::new();
                for &s in free.iter().step_by(97) {
                    for &t in free.iter().step_by(13) {
                        agrees(&graph, &mut q, s, t)?;
                    }
                }
            }
        }
    }

    #[test]
    fn subgoals_are_the_convex_corners() {
        // One block in the open: its four diagonal neighbours are the subgoals.
        let grid = Grid2::from_ascii(".....\n.....\n..#..\n.....\n.....").unwrap();
        let graph = SubgoalGraph::build(Arc::new(grid), MoveModel::Octile).unwrap();
        let mut cells: Vec<(i32, i32)> = graph.rc_of_node.clone();
        cells.sort_unstable();
        assert_eq!(cells, [(1, 1), (1, 3), (3, 1), (3, 3)]);
        // Each sees the two beside it directly; the one opposite only through them.
        assert_eq!(graph.edges(), 8);
        // An open grid has none, and its queries are the octile line.
        let open = SubgoalGraph::build(
            Arc::new(Grid2::new(6, 9, vec![false; 54], GridFrame::default()).unwrap()),
            MoveModel::Octile,
        )
        .unwrap();
        assert_eq!((open.subgoals(), open.edges()), (0, 0));
        let p = open
            .search(&mut SubgoalQuery::new(), Cell::new(5, 0), Cell::new(0, 8))
            .unwrap();
        assert_eq!(
            (p.straight_moves, p.diagonal_moves, p.cells.len()),
            (3, 5, 9)
        );
    }

    #[test]
    fn special_ends_and_refusals() {
        let grid = Arc::new(Grid2::from_ascii("..#..\n..#..\n###..\n.....").unwrap());
        let graph = SubgoalGraph::build(Arc::clone(&grid), MoveModel::Octile).unwrap();
        let mut q = SubgoalQuery::new();
        // The same cell: a one-cell path; the walled-in corner: no path.
        let same = graph
            .search(&mut q, Cell::new(3, 3), Cell::new(3, 3))
            .unwrap();
        assert_eq!(same.cells, [Cell::new(3, 3)]);
        assert!(matches!(
            graph.search(&mut q, Cell::new(0, 0), Cell::new(3, 4)),
            Err(SearchError::Unreachable { .. })
        ));
        assert!(matches!(
            graph.search(&mut q, Cell::new(0, 2), Cell::new(3, 4)),
            Err(SearchError::StartBlocked(_))
        ));
        assert!(
            graph
                .search(&mut q, Cell::new(9, 0), Cell::new(3, 4))
                .is_err()
        );
        for model in [MoveModel::FourConnected, MoveModel::OctileCornerCutting] {
            assert_eq!(
                SubgoalGraph::build(Arc::clone(&grid), model).err(),
                Some(SubgoalError::MoveModel)
            );
        }
        let past = std::time::Instant::now();
        assert!(matches!(
            SubgoalGraph::build_until(Arc::clone(&grid), MoveModel::Octile, Some(past)),
            Err(SubgoalError::Deadline { .. })
        ));
    }
}
