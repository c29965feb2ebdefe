//! Landmarks (differential heuristics): exact grid distances from a few cells to every cell,
//! giving a lower bound on any distance that is much tighter than the octile one where walls
//! force detours (Goldberg & Harrelson's ALT; Sturtevant et al., "Memory-Efficient Abstractions
//! for Pathfinding" / differential heuristics on grids).
//!
//! For a landmark `L` and cells `n`, `g`, the triangle inequality gives
//! `d(n, g) ≥ |d(L, n) − d(L, g)|`. Distances are kept in fixed point, [`UNITS_PER_CELL`]
//! units per cell rounded to the nearest, so a stored difference can exceed the true one by up
//! to `Q = 1 / UNITS_PER_CELL`. The bound is scaled by `λ = 1 / (1 + Q)`:
//!
//! * admissible: `λ · (d(n, g) + Q) ≤ d(n, g)` whenever `d(n, g) ≥ 1`, true for `n ≠ g`;
//! * consistent on every move or jump `u → v` of cost `w ≥ 1`:
//!   `h(u) ≤ h(v) + λ · (w + Q) ≤ h(v) + w`.
//!
//! Both hold for *any* stored values whose differences across every single move are at most the
//! move's cost plus `Q` (along a path of `m` moves the difference at its ends is then at most
//! its cost plus `m · Q`, and every move costs at least 1), whether or not they are the true
//! distances: [`Landmarks::check`] verifies exactly that, so a table read from a file can make a
//! search slower but never its answer longer. The maximum of such bounds and
//! the octile distance is consistent too, so A\* and JPS stay exact without reopening cells.
//!
//! A cell a landmark cannot reach holds [`UNKNOWN`] for it, and that landmark gives no bound
//! there (nor anywhere in that cell's component: the check requires every move to join two
//! known or two unknown values). A landmark with a reachable cell farther than the fixed point
//! holds (a million cells of path) is not kept.

use crate::MoveModel;
use crate::queue::{BucketQueue, key, key_f, key_index};
use skyplan_cspace::{Cell, Grid2};
use std::f64::consts::SQRT_2;

/// Fixed-point units per cell of distance (`Q = 1 / 4096` cell).
pub const UNITS_PER_CELL: u32 = 4096;
/// The stored value of a cell its landmark does not reach (blocked or in another component).
pub const UNKNOWN: u32 = u32::MAX;
/// The most landmarks a table holds.
pub const MAX_LANDMARKS: usize = 32;
/// `λ / UNITS_PER_CELL`: one unit of stored difference as a bound in cells (module docs).
const CELLS_PER_UNIT: f64 = 1.0 / (UNITS_PER_CELL as f64 + 1.0);

/// Why landmarks cannot be built or used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LandmarkError {
    /// Stored distances that would make the bound inadmissible.
    #[error(
        "landmark {landmark} at row {row}, column {col}: its distances there and at a neighbour differ by more than the move between them (not distances on this grid)"
    )]
    Inconsistent {
        /// The landmark's number.
        landmark: usize,
        /// Row of the cell.
        row: u32,
        /// Column of the cell.
        col: u32,
    },
    /// A landmark cell off the grid or blocked, or too many landmarks.
    #[error("{0}")]
    Shape(String),
}

/// Exact distances from a few landmark cells to every cell of one grid, under one move model
/// (module docs).
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_search::{Landmarks, MoveModel};
/// // A wall with a gap at the right: the octile distance across it is 2, the true one 10.
/// let grid = Grid2::from_ascii(".....\n####.\n.....")?;
/// let landmarks = Landmarks::build(&grid, MoveModel::Octile, 2);
/// let (start, goal) = (Cell::new(0, 0), Cell::new(2, 0));
/// let bound = landmarks.to_goal(grid.index(start), grid.index(goal), 2);
/// let h = bound.at(grid.index(start));
/// assert!(h > 9.99 && h <= 10.0); // the true distance, 10, less 1 / 4097 of it
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Landmarks {
    rows: u32,
    cols: u32,
    model: MoveModel,
    cells: Vec<Cell>,
    /// `cells.len()` values per grid cell, interleaved (a cell's values share a cache line).
    units: Vec<u32>,
}

impl Landmarks {
    /// Picks up to `count` (at most [`MAX_LANDMARKS`]) landmarks by farthest selection — the
    /// first the free cell farthest from a cell of the largest connected region, each next the
    /// one farthest from all before — and keeps their exact distances to every cell. Fewer are
    /// kept when that region has fewer distinct cells to pick (none when it is one cell).
    ///
    /// Time: one Dijkstra over the component per landmark (plus one to start).
    pub fn build(grid: &Grid2, model: MoveModel, count: usize) -> Self {
        let count = count.min(MAX_LANDMARKS);
        let mut out = Self {
            rows: grid.rows(),
            cols: grid.cols(),
            model,
            cells: Vec::new(),
            units: Vec::new(),
        };
        if count == 0 {
            return out;
        }
        // The seed: a cell of the largest connected region, so that the landmarks serve most
        // of the map (a small pocket first in row order would hold them all).
        let components = crate::Components::new(grid, model);
        let biggest = (0..grid.len())
            .filter_map(|i| components.label(grid.cell(i)).map(|l| (l, i)))
            .max_by_key(|&(l, i)| (components.size(l), std::cmp::Reverse(i)));
        let Some((_, seed)) = biggest else {
            return out;
        };
        let n = grid.len();
        let mut field = Field::new(grid, model);
        field.run(seed);
        // Each cell's distance to the nearest landmark so far (to the seed before the first).
        let mut nearest: Vec<f32> = (0..n).map(|i| field.dist(i) as f32).collect();
        // Written straight into the interleaved layout (`count` per cell), compacted at the end
        // if fewer are kept.
        let mut units = vec![UNKNOWN; n * count];
        for j in 0..count {
            let mut best = (0.0f32, None);
            for (i, &m) in nearest.iter().enumerate() {
                if m.is_finite() && m > best.0 {
                    best = (m, Some(i));
                }
            }
            let Some(at) = best.1 else { break };
            field.run(at);
            // A distance the fixed point cannot hold would make the landmark's bound fall to
            // nothing inside a connected region (not consistent): keep only landmarks whose
            // every distance fits.
            if (0..n).any(|i| field.dist(i).is_finite() && to_units(field.dist(i)) == UNKNOWN) {
                break;
            }
            for (i, m) in nearest.iter_mut().enumerate() {
                let d = field.dist(i);
                *m = if j == 0 { d as f32 } else { m.min(d as f32) };
                units[i * count + j] = to_units(d);
            }
            out.cells.push(grid.cell(at));
        }
        let kept = out.cells.len();
        if kept < count {
            units = (0..n)
                .flat_map(|i| units[i * count..i * count + kept].to_vec())
                .collect();
        }
        out.units = units;
        out
    }

    /// Landmarks from stored parts (a file), checked against `grid` ([`Landmarks::check`]).
    pub(crate) fn from_parts(
        grid: &Grid2,
        model: MoveModel,
        cells: Vec<Cell>,
        units: Vec<u32>,
    ) -> Result<Self, LandmarkError> {
        if cells.len() > MAX_LANDMARKS || units.len() != cells.len() * grid.len() {
            return Err(LandmarkError::Shape(format!(
                "{} landmarks with {} values for {} cells (expected at most {MAX_LANDMARKS}, one value per cell each)",
                cells.len(),
                units.len(),
                grid.len()
            )));
        }
        let me = Self {
            rows: grid.rows(),
            cols: grid.cols(),
            model,
            cells,
            units,
        };
        me.check(grid)?;
        Ok(me)
    }

    /// The landmark cells.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// The move model the distances are for.
    pub fn model(&self) -> MoveModel {
        self.model
    }

    /// The stored values: `cells().len()` per grid cell, interleaved, in fixed point
    /// ([`UNITS_PER_CELL`] per cell; [`UNKNOWN`] where a landmark does not reach).
    pub fn units(&self) -> &[u32] {
        &self.units
    }

    /// Bytes of distances kept (4 per cell and landmark).
    pub fn bytes(&self) -> usize {
        self.units.len() * 4
    }

    /// The bound to the cell at index `goal` (module docs), using the `active` landmarks that
    /// bound the distance from the cell at index `start` best (fewer reads per cell; the bound
    /// stays admissible and consistent with any subset).
    pub fn to_goal(&self, start: usize, goal: usize, active: usize) -> GoalBound<'_> {
        let k = self.cells.len();
        let mut chosen: Vec<(u32, usize, u32)> = if k == 0 {
            Vec::new()
        } else {
            let g = &self.units[goal * k..goal * k + k];
            let s = &self.units[start * k..start * k + k];
            (0..k)
                .filter(|&j| g[j] != UNKNOWN && s[j] != UNKNOWN)
                .map(|j| (s[j].abs_diff(g[j]), j, g[j]))
                .collect()
        };
        chosen.sort_unstable_by(|a, b| b.cmp(a));
        chosen.truncate(active);
        GoalBound {
            units: &self.units,
            k,
            chosen: chosen.into_iter().map(|(_, j, y)| (j, y)).collect(),
        }
    }

    /// Checks that the stored values bound distances on `grid` (module docs): across every
    /// move of the model between free cells, both values unknown, or both known and differing
    /// by at most the move's cost plus `Q`; blocked cells unknown.
    pub fn check(&self, grid: &Grid2) -> Result<(), LandmarkError> {
        if (self.rows, self.cols) != (grid.rows(), grid.cols()) {
            return Err(LandmarkError::Shape(format!(
                "landmarks for a {} × {} grid, not {} × {}",
                self.rows,
                self.cols,
                grid.rows(),
                grid.cols()
            )));
        }
        let k = self.cells.len();
        let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
        let blocked = grid.blocked_cells();
        let straight = u64::from(UNITS_PER_CELL) + 1;
        let diagonal = (f64::from(UNITS_PER_CELL) * SQRT_2).floor() as u64 + 1;
        let bad = |j: usize, i: usize| LandmarkError::Inconsistent {
            landmark: j,
            row: (i / cols) as u32,
            col: (i % cols) as u32,
        };
        for (j, cell) in self.cells.iter().enumerate() {
            if cell.row >= grid.rows() || cell.col >= grid.cols() || grid.is_blocked(*cell) {
                return Err(LandmarkError::Shape(format!(
                    "landmark {j} at row {}, column {} is not a free cell of the grid",
                    cell.row, cell.col
                )));
            }
        }
        let value = |i: usize, j: usize| self.units[i * k + j];
        // Moves to the right, down, down-right and down-left cover every move once; a diagonal
        // one under the model's corner rule.
        let diagonal_ok = |r: usize, c: usize, dc: i64| {
            self.model
                .corner_ok(grid, Cell::new(r as u32, c as u32), 1, dc)
        };
        for r in 0..rows {
            for c in 0..cols {
                let i = r * cols + c;
                if blocked[i] {
                    if (0..k).any(|j| value(i, j) != UNKNOWN) {
                        return Err(bad(
                            (0..k).find(|&j| value(i, j) != UNKNOWN).unwrap_or(0),
                            i,
                        ));
                    }
                    continue;
                }
                let mut next: [(usize, u64); 4] = [(usize::MAX, 0); 4];
                if c + 1 < cols {
                    next[0] = (i + 1, straight);
                }
                if r + 1 < rows {
                    next[1] = (i + cols, straight);
                    if self.model.has_diagonals() {
                        if c + 1 < cols && diagonal_ok(r, c, 1) {
                            next[2] = (i + cols + 1, diagonal);
                        }
                        if c > 0 && diagonal_ok(r, c, -1) {
                            next[3] = (i + cols - 1, diagonal);
                        }
                    }
                }
                for (n, limit) in next {
                    if n == usize::MAX || blocked[n] {
                        continue;
                    }
                    for j in 0..k {
                        let (a, b) = (value(i, j), value(n, j));
                        let ok = if a == UNKNOWN || b == UNKNOWN {
                            a == b
                        } else {
                            u64::from(a.abs_diff(b)) <= limit
                        };
                        if !ok {
                            return Err(bad(j, i));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// The landmarks' bound to one goal ([`Landmarks::to_goal`]).
#[derive(Debug)]
pub struct GoalBound<'a> {
    units: &'a [u32],
    k: usize,
    /// (landmark, its value at the goal).
    chosen: Vec<(usize, u32)>,
}

impl GoalBound<'_> {
    /// A lower bound on the distance (cells) from the cell at index `i` to the goal:
    /// admissible and consistent (module docs).
    #[inline(always)]
    pub fn at(&self, i: usize) -> f64 {
        let row = &self.units[i * self.k..i * self.k + self.k];
        let mut best = 0u32;
        for &(j, y) in &self.chosen {
            let x = row[j];
            if x != UNKNOWN {
                best = best.max(x.abs_diff(y));
            }
        }
        f64::from(best) * CELLS_PER_UNIT
    }
}

/// A distance in cells as fixed point ([`UNKNOWN`] if unreachable or beyond the range).
fn to_units(d: f64) -> u32 {
    let u = (d * f64::from(UNITS_PER_CELL)).round();
    if u < f64::from(UNKNOWN) {
        u as u32
    } else {
        UNKNOWN
    }
}

/// One grid's Dijkstra workspace: the free cells with a blocked border (no edge tests) and
/// the distances of the last run, both on the padded grid.
struct Field {
    cols: usize,
    padded_cols: usize,
    free: Vec<bool>,
    dist: Vec<f64>,
    model: MoveModel,
    queue: BucketQueue,
}

impl Field {
    fn new(grid: &Grid2, model: MoveModel) -> Self {
        let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
        let w = cols + 2;
        let mut free = vec![false; (rows + 2) * w];
        for (r, row) in grid.blocked_cells().chunks(cols.max(1)).enumerate() {
            for (c, &b) in row.iter().enumerate() {
                free[(r + 1) * w + c + 1] = !b;
            }
        }
        Self {
            cols,
            padded_cols: w,
            dist: vec![f64::INFINITY; free.len()],
            free,
            model,
            queue: BucketQueue::default(),
        }
    }

    /// The distance from the last run's source to grid cell `i` (infinite if unreachable).
    fn dist(&self, i: usize) -> f64 {
        self.dist[(i / self.cols + 1) * self.padded_cols + i % self.cols + 1]
    }

    /// Dijkstra from grid cell `source` over the free cells.
    fn run(&mut self, source: usize) {
        let w = self.padded_cols as isize;
        let mut moves: Vec<(isize, f64, isize, isize)> = vec![(1, 1.0, 0, 0), (-1, 1.0, 0, 0)];
        moves.push((w, 1.0, 0, 0));
        moves.push((-w, 1.0, 0, 0));
        if self.model.has_diagonals() {
            let cut = self.model == MoveModel::OctileCornerCutting;
            for (dr, dc) in [(1isize, 1isize), (1, -1), (-1, 1), (-1, -1)] {
                // The two cells beside the diagonal (the move itself when cutting corners).
                let (a, b) = if cut { (0, 0) } else { (dr * w, dc) };
                moves.push((dr * w + dc, SQRT_2, a, b));
            }
        }
        self.dist.fill(f64::INFINITY);
        self.queue.clear(true);
        let s = (source / self.cols + 1) * self.padded_cols + source % self.cols + 1;
        self.dist[s] = 0.0;
        self.queue.push(key(0.0, 0.0, s as u32));
        while let Some(top) = self.queue.pop() {
            let p = key_index(top) as usize;
            let d = key_f(top);
            if d > self.dist[p] {
                continue;
            }
            for &(step, cost, a, b) in &moves {
                let q = (p as isize + step) as usize;
                if !self.free[q]
                    || !self.free[(p as isize + a) as usize]
                    || !self.free[(p as isize + b) as usize]
                {
                    continue;
                }
                let nd = d + cost;
                if nd < self.dist[q] {
                    self.dist[q] = nd;
                    self.queue.push(key(nd, nd, q as u32));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::dijkstra_exact;
    use proptest::prelude::*;

    const MODELS: [MoveModel; 3] = [
        MoveModel::Octile,
        MoveModel::OctileCornerCutting,
        MoveModel::FourConnected,
    ];

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Stored distances are the oracle's; bounds are at most the oracle's distance and
        /// consistent across every move.
        #[test]
        fn distances_are_exact_and_bounds_admissible_and_consistent(grid in skyplan_testkit::arb_grid(40, 0.0..0.5), k in 1usize..5, m in 0usize..3) {
            let model = MODELS[m];
            let lm = Landmarks::build(&grid, model, k);
            prop_assert!(lm.check(&grid).is_ok());
            let n = grid.len();
            let kk = lm.cells().len();
            let free: Vec<usize> = (0..n).filter(|&i| !grid.blocked_cells()[i]).collect();
            if free.is_empty() {
                prop_assert_eq!(kk, 0);
                return Ok(());
            }
            let sample = |step: usize| free.iter().copied().step_by((free.len() / step).max(1));
            for (j, &l) in lm.cells().iter().enumerate() {
                for i in sample(15) {
                    let truth = dijkstra_exact(&grid, l, grid.cell(i), model).map(|c| c.to_f64());
                    let stored = lm.units()[i * kk + j];
                    match truth {
                        None => prop_assert_eq!(stored, UNKNOWN),
                        Some(d) => prop_assert!((f64::from(stored) / f64::from(UNITS_PER_CELL) - d).abs() <= 0.5 / f64::from(UNITS_PER_CELL) + 1e-9),
                    }
                }
            }
            for g in sample(3) {
                let bound = lm.to_goal(free[0], g, 2);
                let goal = grid.cell(g);
                for i in sample(12) {
                    if let Some(d) = dijkstra_exact(&grid, grid.cell(i), goal, model) {
                        prop_assert!(bound.at(i) <= d.to_f64() + 1e-12, "bound {} > {}", bound.at(i), d.to_f64());
                    }
                }
                for &i in &free {
                    let cell = grid.cell(i);
                    for (dr, dc) in [(0i64, 1i64), (1, 0), (1, 1), (1, -1)] {
                        let (r, c) = (i64::from(cell.row) + dr, i64::from(cell.col) + dc);
                        let Some(next) = grid.checked_cell(r, c) else { continue };
                        let diagonal = dr != 0 && dc != 0;
                        if grid.is_blocked(next) || (diagonal && !model.has_diagonals())
                            || (diagonal && !model.corner_ok(&grid, cell, dr, dc)) {
                            continue;
                        }
                        let w = if diagonal { SQRT_2 } else { 1.0 };
                        prop_assert!((bound.at(i) - bound.at(grid.index(next))).abs() <= w + 1e-12);
                    }
                }
            }
        }
    }

    #[test]
    fn values_that_are_not_distances_are_refused() {
        let grid = Grid2::from_ascii("......\n.####.\n......").unwrap();
        let lm = Landmarks::build(&grid, MoveModel::Octile, 2);
        assert_eq!(lm.cells().len(), 2);
        let mut units = lm.units().to_vec();
        // Raise one cell's value by two cells: its moves no longer bound the difference.
        units[2 * 2] += 2 * UNITS_PER_CELL;
        let e = Landmarks::from_parts(&grid, MoveModel::Octile, lm.cells().to_vec(), units)
            .unwrap_err();
        assert!(
            matches!(e, LandmarkError::Inconsistent { landmark: 0, .. }),
            "{e}"
        );
        // A blocked landmark, a blocked cell with a value, too few values.
        let e = Landmarks::from_parts(
            &grid,
            MoveModel::Octile,
            vec![Cell::new(1, 1)],
            lm.units().iter().step_by(2).copied().collect(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("not a free cell"), "{e}");
        let mut units = lm.units().to_vec();
        units[grid.index(Cell::new(1, 2)) * 2] = 7;
        let e = Landmarks::from_parts(&grid, MoveModel::Octile, lm.cells().to_vec(), units)
            .unwrap_err();
        assert!(
            matches!(e, LandmarkError::Inconsistent { row: 1, col: 2, .. }),
            "{e}"
        );
        let e = Landmarks::from_parts(&grid, MoveModel::Octile, lm.cells().to_vec(), vec![0; 3])
            .unwrap_err();
        assert!(matches!(e, LandmarkError::Shape(_)), "{e}");
        // The unchanged values are accepted.
        assert!(
            Landmarks::from_parts(
                &grid,
                MoveModel::Octile,
                lm.cells().to_vec(),
                lm.units().to_vec()
            )
            .is_ok()
        );
    }

    /// The first free cell in row order is a pocket of one cell: the landmarks still go to the
    /// large region, where the queries are.
    #[test]
    fn landmarks_serve_the_largest_region() {
        let grid = Grid2::from_ascii(".#......\n##......\n........").unwrap();
        let lm = Landmarks::build(&grid, MoveModel::Octile, 2);
        assert_eq!(lm.cells().len(), 2);
        assert!(!lm.cells().contains(&Cell::new(0, 0)), "{:?}", lm.cells());
        assert!(lm.check(&grid).is_ok());
        // The pocket is unknown to both; the region's cells are known.
        assert_eq!(&lm.units()[..2], &[UNKNOWN, UNKNOWN]);
        assert!(lm.units()[2 * 2..2 * 3].iter().all(|&u| u != UNKNOWN));
    }

    #[test]
    fn farthest_selection_takes_the_far_corners_of_an_open_grid() {
        let grid = Grid2::from_ascii(&vec![".".repeat(30); 20].join("\n")).unwrap();
        let lm = Landmarks::build(&grid, MoveModel::Octile, 2);
        // From (0, 0) the farthest cell is the opposite corner, and from it, (0, 0).
        assert_eq!(lm.cells(), &[Cell::new(19, 29), Cell::new(0, 0)]);
        assert!(
            Landmarks::build(&Grid2::from_ascii("##").unwrap(), MoveModel::Octile, 4)
                .cells()
                .is_empty()
        );
    }
}
