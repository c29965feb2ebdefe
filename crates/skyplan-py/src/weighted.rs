//! `astar_path` with pyastar2d's contract and pyastar2d's paths: a grid of cell weights (≥ 1,
//! `inf` for walls); entering a cell costs its weight, diagonal moves included, and the start's
//! weight is not paid. skyplan's grid planners are for occupancy grids, so this weighted search
//! lives here.
//!
//! The search is pyastar2d's, step for step, so that ties between equally good paths (and the
//! paths of its non-admissible `ORTHOGONAL_*` heuristics) come out as pyastar2d's: the same
//! heuristics ([`Heuristic`]), the neighbour order (top to bottom, left to right), costs summed
//! in the weights' own float type (float32 for pyastar2d's float32 weights), no closed set
//! (a node is relaxed whenever its cost strictly drops), and an open list ordered by priority
//! alone as libstdc++'s `std::priority_queue` orders it ([`OpenList`]).

use crate::arrays::{describe, int_pair, map2};
use crate::errors::bad_input;
use numpy::PyArray2;
use numpy::ndarray::Array2;
use pyo3::prelude::*;
use std::ops::Add;

/// The weights' float type: costs are summed in it (pyastar2d sums float32 weights in float32).
trait Weight: Copy + PartialOrd + Add<Output = Self> + Send + Sync {
    const ZERO: Self;
    const INFINITY: Self;
    /// A heuristic's whole number of cells as this type (C++'s `int` to `float` conversion).
    fn from_cells(cells: i64) -> Self;
    /// A weight read from numpy (exact for the array's own dtype).
    fn from_f64(v: f64) -> Self;
}

impl Weight for f32 {
    const ZERO: Self = 0.0;
    const INFINITY: Self = f32::INFINITY;
    #[allow(clippy::cast_precision_loss)]
    fn from_cells(cells: i64) -> Self {
        cells as f32
    }
    #[allow(clippy::cast_possible_truncation)]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
}

impl Weight for f64 {
    const ZERO: Self = 0.0;
    const INFINITY: Self = f64::INFINITY;
    #[allow(clippy::cast_precision_loss)]
    fn from_cells(cells: i64) -> Self {
        cells as f64
    }
    fn from_f64(v: f64) -> Self {
        v
    }
}

/// pyastar2d's `Heuristic` values (`heuristic_override=`), with pyastar2d's numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Heuristic {
    /// 0: L∞ distance with diagonal moves, L1 without (admissible: weights are ≥ 1).
    Default,
    /// 1: pyastar2d's "orthogonal x": along rows first, then along the columns (not admissible:
    /// straight lines, not always the cheapest path).
    OrthogonalX,
    /// 2: pyastar2d's "orthogonal y": along columns first, then along the rows.
    OrthogonalY,
}

impl Heuristic {
    /// pyastar2d's number for the heuristic (`Heuristic.ORTHOGONAL_X == 1`), or `None`.
    fn from_number(n: i64) -> Option<Self> {
        match n {
            0 => Some(Self::Default),
            1 => Some(Self::OrthogonalX),
            2 => Some(Self::OrthogonalY),
            _ => None,
        }
    }

    /// The estimate at `cell` (row, col) for a search from `start` to `goal`, in cells, as
    /// pyastar2d's `astar.cpp` and `experimental_heuristics.cpp` compute it.
    fn cells(self, cell: (i64, i64), goal: (i64, i64), start: (i64, i64), diagonal: bool) -> i64 {
        let (di, dj) = ((cell.0 - goal.0).abs(), (cell.1 - goal.1).abs());
        // The goal's distance from the start, per axis (the orthogonal heuristics' switch).
        let (span_i, span_j) = ((goal.0 - start.0).abs(), (goal.1 - start.1).abs());
        match self {
            Self::Default if diagonal => di.max(dj),
            Self::Default => di + dj,
            // pyastar2d: `di > dim * 0.5` in doubles, the same as `2 di > dim` in integers.
            Self::OrthogonalX if 2 * di > span_i => di + span_j,
            Self::OrthogonalX => dj,
            Self::OrthogonalY if 2 * dj > span_j => dj + span_i,
            Self::OrthogonalY => di,
        }
    }
}

/// A binary heap of `(priority, cell)` ordered by priority alone, smallest on top, whose ties
/// come out as libstdc++'s `std::priority_queue` (`push_heap`, `pop_heap`) lets them: pyastar2d's
/// open list, so that equally good paths are chosen as pyastar2d chooses them.
struct OpenList<W> {
    heap: Vec<(W, usize)>,
}

impl<W: Weight> OpenList<W> {
    /// libstdc++'s `__push_heap`: `value` goes up from `hole` while its parent is worse.
    fn sift_up(&mut self, mut hole: usize, top: usize, value: (W, usize)) {
        while hole > top {
            let parent = (hole - 1) / 2;
            if self.heap[parent].0 <= value.0 {
                break;
            }
            self.heap[hole] = self.heap[parent];
            hole = parent;
        }
        self.heap[hole] = value;
    }

    fn push(&mut self, priority: W, cell: usize) {
        self.heap.push((priority, cell));
        let last = self.heap.len() - 1;
        self.sift_up(last, 0, (priority, cell));
    }

    fn top(&self) -> Option<usize> {
        self.heap.first().map(|&(_, cell)| cell)
    }

    /// libstdc++'s `pop_heap`: the last entry fills the hole the top leaves, through
    /// `__adjust_heap` (down to the bottom along the better child, the right one on ties, then
    /// up again).
    fn pop(&mut self) {
        let len = self.heap.len();
        if len > 1 {
            let value = self.heap[len - 1];
            self.heap[len - 1] = self.heap[0];
            // The heap is now heap[..len - 1]; its hole is at 0.
            let n = len - 1;
            let (mut hole, mut child) = (0, 0);
            while child < (n - 1) / 2 {
                child = 2 * (child + 1);
                if self.heap[child].0 > self.heap[child - 1].0 {
                    child -= 1;
                }
                self.heap[hole] = self.heap[child];
                hole = child;
            }
            if n.is_multiple_of(2) && child == (n - 2) / 2 {
                child = 2 * (child + 1);
                self.heap[hole] = self.heap[child - 1];
                hole = child - 1;
            }
            self.sift_up(hole, 0, value);
        }
        self.heap.pop();
    }
}

/// What a search is asked: the grid, its two cells (row-major indices), the move model.
struct Query<'a, W> {
    weights: &'a [W],
    rows: usize,
    cols: usize,
    start: usize,
    goal: usize,
    diagonal: bool,
    heuristic: Heuristic,
}

/// The row-major indices of `cell`'s neighbours in pyastar2d's order (top to bottom, left to
/// right), `None` where the grid ends or the move is diagonal and diagonals are off.
fn neighbours(cell: usize, rows: usize, cols: usize, diagonal: bool) -> [Option<usize>; 8] {
    let (r, c) = (cell / cols, cell % cols);
    let (up, down, left, right) = (r > 0, r + 1 < rows, c > 0, c + 1 < cols);
    let at = |ok: bool, index: fn(usize, usize) -> usize| ok.then(|| index(cell, cols));
    [
        at(diagonal && up && left, |i, w| i - w - 1),
        at(up, |i, w| i - w),
        at(diagonal && up && right, |i, w| i - w + 1),
        at(left, |i, _| i - 1),
        at(right, |i, _| i + 1),
        at(diagonal && down && left, |i, w| i + w - 1),
        at(down, |i, w| i + w),
        at(diagonal && down && right, |i, w| i + w + 1),
    ]
}

/// The path from `start` to `goal` (row-major indices) as pyastar2d finds it, `None` when the
/// goal cannot be reached. With the default heuristic the path is optimal (in the weights' float
/// arithmetic); with the orthogonal ones it is a path, as pyastar2d's.
fn search<W: Weight>(q: &Query<'_, W>) -> Option<Vec<usize>> {
    let cols = q.cols;
    let as_cell = |i: usize| ((i / cols) as i64, (i % cols) as i64);
    let (goal, start) = (as_cell(q.goal), as_cell(q.start));
    let mut cost = vec![W::INFINITY; q.weights.len()];
    let mut parent = vec![usize::MAX; q.weights.len()];
    let mut open = OpenList { heap: Vec::new() };
    cost[q.start] = W::ZERO;
    open.push(W::ZERO, q.start);
    loop {
        let cur = open.top()?;
        if cur == q.goal {
            break;
        }
        open.pop();
        for next in neighbours(cur, q.rows, cols, q.diagonal)
            .into_iter()
            .flatten()
        {
            let g = cost[cur] + q.weights[next];
            if g < cost[next] {
                let h = q.heuristic.cells(as_cell(next), goal, start, q.diagonal);
                open.push(g + W::from_cells(h), next);
                cost[next] = g;
                parent[next] = cur;
            }
        }
    }
    // Costs strictly fall along parent links (every weight is ≥ 1), so they end at the start.
    let mut path = vec![q.goal];
    let mut at = q.goal;
    while at != q.start {
        at = parent[at];
        path.push(at);
    }
    path.reverse();
    Some(path)
}

/// The weights' dtype name (`float32`), or a description of what was passed instead.
fn dtype_name(weights: &Bound<'_, PyAny>) -> Result<String, String> {
    weights
        .getattr("dtype")
        .and_then(|d| d.getattr("name"))
        .and_then(|n| n.extract::<String>())
        .map_err(|_| describe(weights))
}

/// `heuristic_override` as a [`Heuristic`]: pyastar2d's `Heuristic` members (or skyplan's), or
/// their numbers 0, 1, 2.
fn heuristic_arg(obj: &Bound<'_, PyAny>) -> PyResult<Heuristic> {
    let refused = || {
        bad_input(format!(
            "heuristic_override: expected skyplan.Heuristic.DEFAULT, ORTHOGONAL_X or ORTHOGONAL_Y (0, 1, 2), got {}",
            describe(obj)
        ))
    };
    if !obj.hasattr("__index__").unwrap_or(false) {
        return Err(refused());
    }
    let number: i64 = obj.extract().map_err(|_| refused())?;
    Heuristic::from_number(number).ok_or_else(refused)
}

/// The path as pyastar2d returns it: an (N, 2) int32 array of `(row, col)`.
fn path_array<'py>(
    py: Python<'py>,
    path: &[usize],
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<i32>>> {
    let flat: Vec<i32> = path
        .iter()
        .flat_map(|&i| [(i / cols) as i32, (i % cols) as i32])
        .collect();
    let array = Array2::from_shape_vec((path.len(), 2), flat)
        .map_err(|e| bad_input(format!("path: {e}")))?;
    Ok(numpy::IntoPyArray::into_pyarray(array, py))
}

/// Reads the weights in their own float type and searches with the GIL released.
fn read_and_search<'py, W: Weight>(
    py: Python<'py>,
    weights: &Bound<'py, PyAny>,
    cells: impl Fn(usize, usize) -> PyResult<(usize, usize)>,
    diagonal: bool,
    heuristic: Heuristic,
) -> PyResult<Option<Bound<'py, PyArray2<i32>>>> {
    let (rows, cols, values) = map2(weights, "weights", |v| v)?;
    if let Some(bad) = values.iter().find(|w| w.is_nan() || **w < 1.0) {
        return Err(bad_input(format!(
            "weights: minimum cost to move must be 1, got {bad}"
        )));
    }
    let (start, goal) = cells(rows, cols)?;
    let values: Vec<W> = values.into_iter().map(W::from_f64).collect();
    let query = Query {
        weights: &values,
        rows,
        cols,
        start,
        goal,
        diagonal,
        heuristic,
    };
    match py.detach(|| search(&query)) {
        Some(path) => path_array(py, &path, cols).map(Some),
        None => Ok(None),
    }
}

/// A\* on a grid of cell weights: pyastar2d's `astar_path`, with pyastar2d's paths.
///
/// `weights`: 2-D float32 array (as pyastar2d requires) or float64 array (skyplan accepts it
/// too, and sums its costs in float64), every weight ≥ 1, `np.inf` for walls; entering a cell
/// costs its weight (diagonal moves too, as in pyastar2d). `start`, `goal`: `(row, col)` inside
/// the grid. `allow_diagonal` (default False, as pyastar2d's): 8-connected moves.
/// `heuristic_override`: a `skyplan.Heuristic` (or pyastar2d's, or its number): `DEFAULT`
/// (L∞ distance with diagonals, L1 without: optimal paths), `ORTHOGONAL_X` or `ORTHOGONAL_Y`
/// (pyastar2d's experimental straight-line heuristics: not always the cheapest path).
///
/// Returns the path as an (N, 2) int32 array of `(row, col)` from start to goal, or `None` when
/// the goal cannot be reached; the same path as pyastar2d's, ties included. Raises
/// `skyplan.BadInput` (a `ValueError`) for a dtype other than float32 or float64 (pyastar2d
/// raises AssertionError, for float64 too), weights below 1 or NaN (pyastar2d lets NaN
/// through), a start or goal outside the grid, an unknown heuristic.
#[pyfunction]
#[pyo3(signature = (weights, start, goal, allow_diagonal = false, heuristic_override = None))]
pub fn astar_path<'py>(
    py: Python<'py>,
    weights: &Bound<'py, PyAny>,
    start: &Bound<'py, PyAny>,
    goal: &Bound<'py, PyAny>,
    allow_diagonal: bool,
    heuristic_override: Option<&Bound<'py, PyAny>>,
) -> PyResult<Option<Bound<'py, PyArray2<i32>>>> {
    let heuristic = match heuristic_override {
        Some(h) => heuristic_arg(h)?,
        None => Heuristic::Default,
    };
    let cells = |rows: usize, cols: usize| -> PyResult<(usize, usize)> {
        let cell = |obj: &Bound<'py, PyAny>, which: &str| -> PyResult<usize> {
            let [r, c] = int_pair(obj, which)?;
            if r < 0 || c < 0 || r >= rows as i64 || c >= cols as i64 {
                return Err(bad_input(format!(
                    "{which} of ({r}, {c}) lies outside the {rows} × {cols} grid"
                )));
            }
            Ok(r as usize * cols + c as usize)
        };
        Ok((cell(start, "start")?, cell(goal, "goal")?))
    };
    match dtype_name(weights).as_deref() {
        Ok("float32") => read_and_search::<f32>(py, weights, cells, allow_diagonal, heuristic),
        Ok("float64") => read_and_search::<f64>(py, weights, cells, allow_diagonal, heuristic),
        Ok(other) => Err(bad_input(format!(
            "weights: must have np.float32 data type (as pyastar2d requires; skyplan also takes np.float64), got {other}"
        ))),
        Err(what) => Err(bad_input(format!(
            "weights: must be a numpy array of np.float32 (or np.float64), got {what}"
        ))),
    }
}
