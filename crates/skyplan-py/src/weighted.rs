//! `astar_path` with pyastar2d's contract: a float32 grid of cell weights (≥ 1, `inf` for
//! walls); entering a cell costs its weight, diagonal moves included, and the start's weight
//! is not paid. skyplan's grid planners are for occupancy grids, so this weighted search lives
//! here: A\* with the admissible, consistent heuristic `min weight × (L∞ or L1 distance)`.

use crate::arrays::{describe, int_pair, map2};
use crate::errors::bad_input;
use numpy::PyArray2;
use numpy::ndarray::Array2;
use pyo3::prelude::*;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The cheapest path from `start` to `goal` (row-major indices), `None` when the goal cannot
/// be reached. Costs are summed in f64.
fn search(
    weights: &[f32],
    rows: usize,
    cols: usize,
    start: usize,
    goal: usize,
    diagonal: bool,
) -> Option<Vec<usize>> {
    let min_weight = f64::from(
        weights
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min)
            .max(1.0),
    );
    let (gr, gc) = ((goal / cols) as i64, (goal % cols) as i64);
    let h = |i: usize| -> f64 {
        let dr = ((i / cols) as i64 - gr).abs();
        let dc = ((i % cols) as i64 - gc).abs();
        let d = if diagonal { dr.max(dc) } else { dr + dc };
        d as f64 * min_weight
    };
    let mut cost = vec![f64::INFINITY; weights.len()];
    let mut parent = vec![usize::MAX; weights.len()];
    let mut closed = vec![false; weights.len()];
    // Priorities are non-negative finite floats: their bit patterns order as the numbers do.
    let mut open = BinaryHeap::new();
    cost[start] = 0.0;
    open.push(Reverse((h(start).to_bits(), start)));
    const STEPS: [(i64, i64, bool); 8] = [
        (-1, 0, false),
        (1, 0, false),
        (0, -1, false),
        (0, 1, false),
        (-1, -1, true),
        (-1, 1, true),
        (1, -1, true),
        (1, 1, true),
    ];
    while let Some(Reverse((_, cur))) = open.pop() {
        if closed[cur] {
            continue;
        }
        if cur == goal {
            let mut path = vec![goal];
            let mut at = goal;
            while at != start {
                at = parent[at];
                path.push(at);
            }
            path.reverse();
            return Some(path);
        }
        closed[cur] = true;
        let (r, c) = ((cur / cols) as i64, (cur % cols) as i64);
        for &(dr, dc, diag) in &STEPS {
            if diag && !diagonal {
                continue;
            }
            let (nr, nc) = (r + dr, c + dc);
            if nr < 0 || nc < 0 || nr >= rows as i64 || nc >= cols as i64 {
                continue;
            }
            let next = nr as usize * cols + nc as usize;
            let w = f64::from(weights[next]);
            if closed[next] || !w.is_finite() {
                continue;
            }
            let g = cost[cur] + w;
            if g < cost[next] {
                cost[next] = g;
                parent[next] = cur;
                open.push(Reverse(((g + h(next)).to_bits(), next)));
            }
        }
    }
    None
}

/// A\* on a grid of cell weights, with pyastar2d's `astar_path` contract.
///
/// `weights`: 2-D float32 array, every weight ≥ 1, `np.inf` for walls; entering a cell costs
/// its weight (diagonal moves too, as in pyastar2d). `start`, `goal`: `(row, col)` inside the
/// grid. `allow_diagonal` (default False, as pyastar2d's): 8-connected moves.
///
/// Returns the path as an (N, 2) int32 array of `(row, col)` from start to goal, or `None` when
/// the goal cannot be reached. The path is optimal (costs summed in float64). Raises
/// `skyplan.BadInput` (a `ValueError`) for a dtype other than float32, weights below 1 or NaN,
/// a start or goal outside the grid — where pyastar2d raises AssertionError or ValueError.
#[pyfunction]
#[pyo3(signature = (weights, start, goal, allow_diagonal = false))]
pub fn astar_path<'py>(
    py: Python<'py>,
    weights: &Bound<'py, PyAny>,
    start: &Bound<'py, PyAny>,
    goal: &Bound<'py, PyAny>,
    allow_diagonal: bool,
) -> PyResult<Option<Bound<'py, PyArray2<i32>>>> {
    let dtype_ok = weights
        .getattr("dtype")
        .and_then(|d| d.getattr("name"))
        .and_then(|n| n.extract::<String>())
        .is_ok_and(|n| n == "float32");
    if !dtype_ok {
        let got = weights
            .getattr("dtype")
            .map(|d| describe(&d))
            .unwrap_or_else(|_| describe(weights));
        return Err(bad_input(format!(
            "weights: must have np.float32 data type (as pyastar2d requires), got {got}"
        )));
    }
    let (rows, cols, values) = map2(weights, "weights", |v| v as f32)?;
    if let Some(bad) = values.iter().find(|w| w.is_nan() || **w < 1.0) {
        return Err(bad_input(format!(
            "weights: minimum cost to move must be 1, got {bad}"
        )));
    }
    let cell = |obj: &Bound<'py, PyAny>, which: &str| -> PyResult<usize> {
        let [r, c] = int_pair(obj, which)?;
        if r < 0 || c < 0 || r >= rows as i64 || c >= cols as i64 {
            return Err(bad_input(format!(
                "{which} of ({r}, {c}) lies outside the {rows} × {cols} grid"
            )));
        }
        Ok(r as usize * cols + c as usize)
    };
    let (s, g) = (cell(start, "start")?, cell(goal, "goal")?);
    let found = py.detach(|| search(&values, rows, cols, s, g, allow_diagonal));
    let Some(path) = found else {
        return Ok(None);
    };
    let flat: Vec<i32> = path
        .iter()
        .flat_map(|&i| [(i / cols) as i32, (i % cols) as i32])
        .collect();
    let array = Array2::from_shape_vec((path.len(), 2), flat)
        .map_err(|e| bad_input(format!("path: {e}")))?;
    Ok(Some(numpy::IntoPyArray::into_pyarray(array, py)))
}
