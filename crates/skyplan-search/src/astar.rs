//! A\* and Dijkstra on a 2D grid with flat arrays and reusable buffers.

use crate::{GridPath, MoveModel, Planner, SearchError};
use skyplan_cspace::{Cell, Grid2};
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::f64::consts::SQRT_2;

/// A heap entry: smallest `f` first; on equal `f`, largest `g` first (deepest first, which
/// expands fewer cells on open grids).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Entry {
    pub(crate) f: f64,
    pub(crate) g: f64,
    pub(crate) index: u32,
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
    /// `f` and `g` are never negative or NaN, and for such floats the IEEE-754 bit patterns,
    /// read as integers, are ordered exactly like the numbers: integer compares are cheaper.
    #[inline]
    fn cmp(&self, other: &Self) -> Ordering {
        debug_assert!(self.f >= 0.0 && self.g >= 0.0 && other.f >= 0.0 && other.g >= 0.0);
        other
            .f
            .to_bits()
            .cmp(&self.f.to_bits())
            .then(self.g.to_bits().cmp(&other.g.to_bits()))
            .then(other.index.cmp(&self.index))
    }
}

/// Reusable A\*/Dijkstra workspace: create once, run many queries on grids of any size.
#[derive(Debug, Default)]
pub struct GridSearch {
    /// Per-cell search state, one cache line for all of it.
    nodes: Vec<Node>,
    /// `2 × query number`: a node's `stamp` is `open_stamp` (reached) or `open_stamp + 1`
    /// (expanded) in the current query; anything older is stale and means "unseen".
    open_stamp: u32,
    pub(crate) heap: BinaryHeap<Entry>,
}

#[derive(Debug, Clone, Copy, Default)]
struct Node {
    g: f64,
    parent: u32,
    stamp: u32,
}

pub(crate) const NO_PARENT: u32 = u32::MAX;

/// The endpoint checks every planner makes first.
pub(crate) fn check_endpoints(grid: &Grid2, start: Cell, goal: Cell) -> Result<(), SearchError> {
    let (rows, cols) = (grid.rows(), grid.cols());
    if !grid.contains(start) {
        return Err(SearchError::StartOutside {
            cell: start,
            rows,
            cols,
        });
    }
    if !grid.contains(goal) {
        return Err(SearchError::GoalOutside {
            cell: goal,
            rows,
            cols,
        });
    }
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

    pub(crate) fn reset(&mut self, cells: usize) {
        if self.nodes.len() != cells {
            self.nodes = vec![Node::default(); cells];
            self.open_stamp = 0;
        }
        if self.open_stamp >= u32::MAX - 3 {
            self.nodes.fill(Node::default());
            self.open_stamp = 0;
        }
        self.open_stamp += 2;
        self.heap.clear();
    }

    /// True if cell `i` was expanded in the current query.
    #[inline(always)]
    pub(crate) fn is_closed(&self, i: usize) -> bool {
        self.nodes[i].stamp == self.open_stamp + 1
    }

    /// Marks cell `i` expanded.
    #[inline(always)]
    pub(crate) fn close(&mut self, i: usize) {
        self.nodes[i].stamp = self.open_stamp + 1;
    }

    /// The best cost found so far to cell `i` (infinite if unseen in this query).
    #[inline(always)]
    pub(crate) fn g(&self, i: usize) -> f64 {
        let n = self.nodes[i];
        if n.stamp >= self.open_stamp {
            n.g
        } else {
            f64::INFINITY
        }
    }

    /// The parent of cell `i` on its best path ([`NO_PARENT`] for the start).
    #[inline(always)]
    pub(crate) fn parent(&self, i: usize) -> u32 {
        self.nodes[i].parent
    }

    /// Offers a path of cost `g` to cell `i` through `parent`, with heuristic `h`: queued if the
    /// cell is not expanded yet and the path is better than any found before.
    #[inline(always)]
    pub(crate) fn offer(&mut self, i: usize, g: f64, h: f64, parent: u32) {
        if !self.is_closed(i) && self.relax(i, g, parent) {
            self.heap.push(Entry {
                f: g + h,
                g,
                index: i as u32,
            });
        }
    }

    /// Pops the best queued cell that is still current (skipping stale entries), marks it
    /// expanded and returns its cost and index.
    #[inline(always)]
    pub(crate) fn expand_next(&mut self) -> Option<(f64, u32)> {
        while let Some(Entry { g, index, .. }) = self.heap.pop() {
            let i = index as usize;
            if self.is_closed(i) || g > self.g(i) {
                continue;
            }
            self.close(i);
            return Some((g, index));
        }
        None
    }

    /// Records a better path to the not yet expanded cell `i`; returns false if it is not better.
    #[inline(always)]
    pub(crate) fn relax(&mut self, i: usize, g: f64, parent: u32) -> bool {
        let open_stamp = self.open_stamp;
        let n = &mut self.nodes[i];
        if n.stamp >= open_stamp && g >= n.g {
            return false;
        }
        *n = Node {
            g,
            parent,
            stamp: open_stamp,
        };
        true
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
        let (rows, cols) = (grid.rows(), grid.cols());
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
        self.reset(grid.len());
        let blocked = grid.blocked_cells();
        let cols_i = cols as i64;
        let h = |c: Cell| match planner {
            Planner::Dijkstra => 0.0,
            Planner::AStar | Planner::Jps | Planner::JpsPlus | Planner::ThetaStar => {
                model.heuristic(c, goal)
            }
        };
        let start_i = grid.index(start) as u32;
        let goal_i = grid.index(goal) as u32;
        self.offer(start_i as usize, 0.0, h(start), NO_PARENT);

        // (dr, dc, cost): orthogonal moves first.
        const MOVES: [(i64, i64, f64); 8] = [
            (1, 0, 1.0),
            (-1, 0, 1.0),
            (0, 1, 1.0),
            (0, -1, 1.0),
            (1, 1, SQRT_2),
            (1, -1, SQRT_2),
            (-1, 1, SQRT_2),
            (-1, -1, SQRT_2),
        ];
        let moves = if model.has_diagonals() {
            &MOVES[..]
        } else {
            &MOVES[..4]
        };
        let corner_cutting = model == MoveModel::OctileCornerCutting;
        let free = |r: i64, c: i64| -> bool {
            r >= 0
                && c >= 0
                && r < i64::from(rows)
                && c < cols_i
                && !blocked[(r * cols_i + c) as usize]
        };
        let mut expansions = 0u64;
        while let Some((g, index)) = self.expand_next() {
            let i = index as usize;
            expansions += 1;
            if index == goal_i {
                return Ok(self.reconstruct(grid, goal_i, expansions));
            }
            let (r, c) = ((i as i64) / cols_i, (i as i64) % cols_i);
            for &(dr, dc, step) in moves {
                let (nr, nc) = (r + dr, c + dc);
                if !free(nr, nc) {
                    continue;
                }
                if dr != 0 && dc != 0 && !corner_cutting && !(free(r + dr, c) && free(r, c + dc)) {
                    continue;
                }
                let ni = (nr * cols_i + nc) as usize;
                self.offer(ni, g + step, h(Cell::new(nr as u32, nc as u32)), index);
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
