//! [`bidirectional_astar`]: A\* from both ends at once (Pohl's symmetric bidirectional A\*):
//! a forward search towards the goal and a backward search towards the start, each with the
//! move model's consistent heuristic, the side with the smaller open list expanded next. The
//! best meeting cost `μ` is updated whenever an edge reaches a cell the other side has seen;
//! the search stops as soon as either side's smallest `f` is at least `μ`, which proves `μ`
//! optimal: every path not yet found costs at least that side's smallest `f`.
//!
//! The grid graph is undirected (a diagonal move needs the same two orthogonal cells free in
//! both directions), so the backward search uses the same moves as the forward one.

use crate::astar::check_endpoints;
use crate::jps::DIRS;
use crate::{GridPath, MoveModel, OpenEntry, SearchError};
use skyplan_cspace::{Cell, Grid2};
use std::collections::BinaryHeap;
use std::f64::consts::SQRT_2;

const NONE: u32 = u32::MAX;

/// One direction of the search: costs so far, parents, closed cells and its open list.
struct Side {
    g: Vec<f64>,
    parent: Vec<u32>,
    closed: Vec<bool>,
    open: BinaryHeap<OpenEntry>,
    /// The cell its heuristic aims at (the goal going forward, the start going backward).
    target: Cell,
    expansions: u64,
}

impl Side {
    fn new(cells: usize, from: u32, from_cell: Cell, target: Cell, model: MoveModel) -> Self {
        let mut side = Side {
            g: vec![f64::INFINITY; cells],
            parent: vec![NONE; cells],
            closed: vec![false; cells],
            open: BinaryHeap::new(),
            target,
            expansions: 0,
        };
        side.g[from as usize] = 0.0;
        let f = model.heuristic(from_cell, target);
        side.open.push(OpenEntry {
            f,
            g: 0.0,
            node: from,
        });
        side
    }

    /// The smallest `f` of a cell not closed yet (stale entries are dropped on the way).
    fn top_f(&mut self) -> Option<f64> {
        while let Some(top) = self.open.peek() {
            if self.closed[top.node as usize] || top.g > self.g[top.node as usize] {
                self.open.pop();
            } else {
                return Some(top.f);
            }
        }
        None
    }

    /// The cells from this side's root to `node`, root first.
    fn chain(&self, node: u32) -> Vec<u32> {
        let mut cells = vec![node];
        let mut at = node;
        while self.parent[at as usize] != NONE {
            at = self.parent[at as usize];
            cells.push(at);
        }
        cells.reverse();
        cells
    }
}

/// The best meeting found so far: its cost and the two cells joined (equal, or neighbours with
/// `forward` on the start's side).
#[derive(Clone, Copy)]
struct Meeting {
    cost: f64,
    forward: u32,
    backward: u32,
}

/// The moves out of `cell` under `model`: each neighbour's index and the move's cost.
#[inline]
fn moves(grid: &Grid2, cell: Cell, model: MoveModel, out: &mut Vec<(u32, f64)>) {
    out.clear();
    let (r, c) = (i64::from(cell.row), i64::from(cell.col));
    for (dr, dc) in DIRS {
        let diagonal = dr != 0 && dc != 0;
        if diagonal && !model.has_diagonals() {
            continue;
        }
        if !grid.is_free_at(r + dr, c + dc) || (diagonal && !model.corner_ok(grid, cell, dr, dc)) {
            continue;
        }
        if let Some(next) = grid.checked_cell(r + dr, c + dc) {
            let cost = if diagonal { SQRT_2 } else { 1.0 };
            out.push((grid.index(next) as u32, cost));
        }
    }
}

/// Expands the best open cell of `this` (the other side is `other`); updates `best`.
fn expand(
    grid: &Grid2,
    model: MoveModel,
    this: &mut Side,
    other: &Side,
    forward: bool,
    best: &mut Option<Meeting>,
    scratch: &mut Vec<(u32, f64)>,
) {
    let Some(entry) = this.open.pop() else {
        return;
    };
    let u = entry.node;
    this.closed[u as usize] = true;
    this.expansions += 1;
    let meet = |a: u32, b: u32, cost: f64, best: &mut Option<Meeting>| {
        if best.is_none_or(|m| cost < m.cost) {
            let (forward_cell, backward_cell) = if forward { (a, b) } else { (b, a) };
            *best = Some(Meeting {
                cost,
                forward: forward_cell,
                backward: backward_cell,
            });
        }
    };
    let g_u = this.g[u as usize];
    if other.g[u as usize].is_finite() {
        meet(u, u, g_u + other.g[u as usize], best);
    }
    moves(grid, grid.cell(u as usize), model, scratch);
    for &(v, w) in scratch.iter() {
        let g_v = g_u + w;
        if other.g[v as usize].is_finite() {
            meet(u, v, g_v + other.g[v as usize], best);
        }
        if this.closed[v as usize] || g_v >= this.g[v as usize] {
            continue;
        }
        this.g[v as usize] = g_v;
        this.parent[v as usize] = u;
        let f = g_v + model.heuristic(grid.cell(v as usize), this.target);
        this.open.push(OpenEntry { f, g: g_v, node: v });
    }
}

/// The shortest path from `start` to `goal` under `model`, searched from both ends at once.
/// Its cost equals A\*'s (checked against the exact oracle in the tests); its cells may be
/// another of the equally short paths.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_search::{bidirectional_astar, MoveModel};
/// let grid = Grid2::from_ascii("....\n.##.\n....")?;
/// let path = bidirectional_astar(&grid, Cell::new(0, 0), Cell::new(2, 3), MoveModel::Octile)?;
/// assert_eq!(path.cells.first(), Some(&Cell::new(0, 0)));
/// assert_eq!(path.cells.last(), Some(&Cell::new(2, 3)));
/// assert_eq!(path.cost_cells(), 5.0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn bidirectional_astar(
    grid: &Grid2,
    start: Cell,
    goal: Cell,
    model: MoveModel,
) -> Result<GridPath, SearchError> {
    check_endpoints(grid, start, goal)?;
    let (s, t) = (grid.index(start) as u32, grid.index(goal) as u32);
    let mut sides = [
        Side::new(grid.len(), s, start, goal, model),
        Side::new(grid.len(), t, goal, start, model),
    ];
    let mut best: Option<Meeting> = (s == t).then_some(Meeting {
        cost: 0.0,
        forward: s,
        backward: t,
    });
    let mut scratch = Vec::with_capacity(8);
    // Until one side has closed its whole region (then every meeting has been seen) or
    // neither side can improve the best meeting.
    while let (Some(f0), Some(f1)) = (sides[0].top_f(), sides[1].top_f()) {
        if best.is_some_and(|m| f0 >= m.cost || f1 >= m.cost) {
            break;
        }
        let forward = sides[0].open.len() <= sides[1].open.len();
        let [a, b] = &mut sides;
        let (this, other) = if forward { (a, &*b) } else { (b, &*a) };
        expand(grid, model, this, other, forward, &mut best, &mut scratch);
    }
    let expansions = sides[0].expansions + sides[1].expansions;
    let Some(m) = best else {
        return Err(SearchError::Unreachable { expansions });
    };
    let mut nodes = sides[0].chain(m.forward);
    let mut back = sides[1].chain(m.backward);
    back.reverse();
    if m.forward == m.backward {
        back.remove(0);
    }
    nodes.extend(back);
    let cells: Vec<Cell> = nodes.iter().map(|&i| grid.cell(i as usize)).collect();
    let diagonal_moves = cells
        .windows(2)
        .filter(|w| w[0].row != w[1].row && w[0].col != w[1].col)
        .count() as u64;
    Ok(GridPath {
        straight_moves: (cells.len() as u64 - 1) - diagonal_moves,
        diagonal_moves,
        cells,
        expansions,
        any_angle_cells: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::dijkstra_exact;
    use crate::{check_path, octile_cost};

    /// A grid from a seed: a xorshift stream blocks about `percent` % of the cells.
    fn random_grid(rows: usize, cols: usize, percent: u64, seed: u64) -> Grid2 {
        let mut x = seed | 1;
        let text: Vec<String> = (0..rows)
            .map(|_| {
                (0..cols)
                    .map(|_| {
                        x ^= x << 13;
                        x ^= x >> 7;
                        x ^= x << 17;
                        if x % 100 < percent { '#' } else { '.' }
                    })
                    .collect()
            })
            .collect();
        Grid2::from_ascii(&text.join("\n")).expect("a rectangular grid")
    }

    #[test]
    fn costs_equal_the_exact_oracle_for_every_move_model() {
        let models = [
            MoveModel::FourConnected,
            MoveModel::Octile,
            MoveModel::OctileCornerCutting,
        ];
        let mut compared = 0;
        for seed in 1..=300u64 {
            let grid = random_grid(3 + (seed % 17) as usize, 3 + (seed % 23) as usize, 30, seed);
            let free: Vec<Cell> = (0..grid.len())
                .map(|i| grid.cell(i))
                .filter(|&c| !grid.is_blocked(c))
                .collect();
            if free.len() < 2 {
                continue;
            }
            let (a, b) = (free[0], free[(seed as usize * 7) % free.len()]);
            for model in models {
                let truth = dijkstra_exact(&grid, a, b, model);
                let found = bidirectional_astar(&grid, a, b, model);
                match (truth, found) {
                    (Some(t), Ok(p)) => {
                        assert_eq!(check_path(&grid, &p.cells, model), Ok(()));
                        assert_eq!((p.cells[0], *p.cells.last().unwrap()), (a, b));
                        assert_eq!(
                            p.cost_cells(),
                            octile_cost(t.straight, t.diagonal),
                            "seed {seed}, {model:?}"
                        );
                        compared += 1;
                    }
                    (None, Err(SearchError::Unreachable { .. })) => {}
                    (t, f) => panic!("seed {seed}, {model:?}: oracle {t:?}, bidirectional {f:?}"),
                }
            }
        }
        assert!(compared > 300, "only {compared} reachable queries compared");
    }

    #[test]
    fn blocked_or_outside_ends_are_refused_and_start_equal_goal_is_one_cell() {
        let grid = Grid2::from_ascii("..#\n...").unwrap();
        let m = MoveModel::Octile;
        assert!(matches!(
            bidirectional_astar(&grid, Cell::new(0, 0), Cell::new(0, 2), m),
            Err(SearchError::GoalBlocked(_))
        ));
        assert!(matches!(
            bidirectional_astar(&grid, Cell::new(5, 0), Cell::new(0, 0), m),
            Err(SearchError::StartOutside(_))
        ));
        let p = bidirectional_astar(&grid, Cell::new(0, 1), Cell::new(0, 1), m).unwrap();
        assert_eq!((p.cells.len(), p.cost_cells()), (1, 0.0));
        let walled = Grid2::from_ascii(".#.\n.#.").unwrap();
        assert!(matches!(
            bidirectional_astar(&walled, Cell::new(0, 0), Cell::new(0, 2), m),
            Err(SearchError::Unreachable { .. })
        ));
    }
}
