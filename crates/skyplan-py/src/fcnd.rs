//! Drop-ins for FCND's `planning_utils.py`: a student replaces the import and nothing else.

use crate::arrays::{blocked2, describe, finite, int_pair, map2};
use crate::errors::{bad_input, fail, to_py};
use numpy::PyArray2;
use numpy::ndarray::Array2;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_plan::{CellSearch, FailureKind, PlanFailure, PlannerId};
use skyplan_search::{MoveModel, SearchError};

/// A finite number argument.
fn number(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<f64> {
    match obj.extract::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(bad_input(format!(
            "{what}: expected a finite number, got {v}"
        ))),
        Err(_) => Err(bad_input(format!(
            "{what}: expected a number, got {}",
            describe(obj)
        ))),
    }
}

/// FCND's grid bounds and size: `floor(min(centre − half))`, `ceil(max(centre + half))`,
/// `int(ceil(max − min))`, for one axis.
fn axis(boxes: &[[f64; 6]], centre: usize, half: usize) -> (f64, usize) {
    let lo = boxes
        .iter()
        .map(|b| b[centre] - b[half])
        .fold(f64::INFINITY, f64::min)
        .floor();
    let hi = boxes
        .iter()
        .map(|b| b[centre] + b[half])
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil();
    // Finite inputs (checked) and the caller's size check keep this in range.
    (lo, (hi - lo).ceil() as usize)
}

/// FCND's rows (or columns) of one grown box: `int(clip(x, 0, size − 1))` of both edges, with
/// the floating-point operations in FCND's order.
fn span(lo_edge_m: f64, hi_edge_m: f64, size: usize) -> std::ops::RangeInclusive<usize> {
    let top = (size - 1) as f64;
    let clip = |x: f64| x.clamp(0.0, top) as usize;
    clip(lo_edge_m)..=clip(hi_edge_m)
}

/// FCND's grid: the same float64 array (1 = blocked) and offsets for the same boxes.
fn fcnd_grid(
    boxes: &[[f64; 6]],
    drone_altitude: f64,
    safety_distance: f64,
) -> PyResult<(Array2<f64>, f64, f64)> {
    let (north_min, north_size) = axis(boxes, 0, 3);
    let (east_min, east_size) = axis(boxes, 1, 4);
    if north_size.saturating_mul(east_size) > skyplan_cspace::MAX_CELLS {
        return Err(bad_input(format!(
            "data: the boxes span a {north_size} × {east_size} grid, more than {} cells",
            skyplan_cspace::MAX_CELLS
        )));
    }
    let mut grid = Array2::<f64>::zeros((north_size, east_size));
    if north_size == 0 || east_size == 0 {
        return Ok((grid, north_min, east_min));
    }
    let s = safety_distance;
    for &[north, east, alt, d_north, d_east, d_alt] in boxes {
        if alt + d_alt + s > drone_altitude {
            let rows = span(
                north - d_north - s - north_min,
                north + d_north + s - north_min,
                north_size,
            );
            let cols = span(
                east - d_east - s - east_min,
                east + d_east + s - east_min,
                east_size,
            );
            for r in rows {
                for c in cols.clone() {
                    grid[[r, c]] = 1.0;
                }
            }
        }
    }
    Ok((grid, north_min, east_min))
}

/// Returns a grid representation of a 2D configuration space, exactly as FCND's
/// `planning_utils.create_grid`.
///
/// `data` is the (n, 6) array of `colliders.csv` (`north, east, alt, d_north, d_east, d_alt`:
/// box centres and half sizes, metres; `np.loadtxt(path, delimiter=',', dtype='float64',
/// skiprows=2)`). Returns `(grid, north_offset, east_offset)`: a float64 array of
/// `ceil(max(north + d_north)) - floor(min(north - d_north))` rows (north) by the same in east,
/// 1.0 where a box taller than `drone_altitude - safety_distance` lies within
/// `safety_distance`, and the integer offsets (`grid` row = north - north_offset).
/// Values, shape, dtype and offsets are FCND's, bit for bit.
///
/// Raises `skyplan.BadInput` for anything but a 2-D numeric array of 6 columns and at least one
/// row, or a NaN or infinite value.
#[pyfunction]
#[pyo3(signature = (data, drone_altitude, safety_distance))]
pub fn create_grid<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    drone_altitude: &Bound<'py, PyAny>,
    safety_distance: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyArray2<f64>>, i64, i64)> {
    let drone_altitude = number(drone_altitude, "drone_altitude")?;
    let safety_distance = number(safety_distance, "safety_distance")?;
    let (rows, cols, values) = map2(data, "data", |v| v)?;
    if cols != 6 || rows == 0 {
        return Err(bad_input(format!(
            "data: expected the (n, 6) array of colliders.csv (north, east, alt, d_north, d_east, d_alt per box), got shape ({rows}, {cols})"
        )));
    }
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        return Err(bad_input(format!(
            "data: row {}, column {}: {} is not a finite number",
            k / 6,
            k % 6,
            values[k]
        )));
    }
    let boxes: Vec<[f64; 6]> = values
        .chunks_exact(6)
        .map(|c| [c[0], c[1], c[2], c[3], c[4], c[5]])
        .collect();
    let (grid, north_min, east_min) =
        py.detach(|| fcnd_grid(&boxes, drone_altitude, safety_distance))?;
    Ok((
        numpy::IntoPyArray::into_pyarray(grid, py),
        north_min as i64,
        east_min as i64,
    ))
}

/// A 2-D numeric array as a skyplan grid: nonzero = blocked; NaN refused.
fn occupancy(grid: &Bound<'_, PyAny>) -> PyResult<Grid2> {
    let (rows, cols, blocked) = blocked2(grid, "grid")?;
    let too_large = || bad_input(format!("grid: {rows} × {cols} is too large"));
    let rows = u32::try_from(rows).map_err(|_| too_large())?;
    let cols = u32::try_from(cols).map_err(|_| too_large())?;
    Grid2::new(rows, cols, blocked, GridFrame::default())
        .map_err(|e| bad_input(format!("grid: {e}")))
}

/// A `(row, col)` on the grid, else `InvalidStart`/`InvalidGoal`.
fn cell_on(grid: &Grid2, obj: &Bound<'_, PyAny>, which: &str) -> PyResult<Cell> {
    let [row, col] = int_pair(obj, which)?;
    grid.checked_cell(row, col).ok_or_else(|| {
        let kind = if which == "start" {
            FailureKind::InvalidStart
        } else {
            FailureKind::InvalidGoal
        };
        fail(
            kind,
            format!(
                "{which} (row {row}, col {col}) is off the {} × {} grid",
                grid.rows(),
                grid.cols()
            ),
        )
    })
}

fn search_failure(e: SearchError) -> PlanFailure {
    let kind = match e {
        SearchError::StartOutside { .. } | SearchError::StartBlocked(_) => {
            FailureKind::InvalidStart
        }
        SearchError::GoalOutside { .. } | SearchError::GoalBlocked(_) => FailureKind::InvalidGoal,
        SearchError::Unreachable { .. } => FailureKind::NoPath,
        SearchError::Damaged(_) => FailureKind::Internal,
    };
    PlanFailure::new(kind, e.to_string())
}

/// An exactly optimal grid path, as FCND's `planning_utils.a_star` returns it.
///
/// Called as FCND calls it, `a_star(grid, heuristic, start, goal)`, or as
/// `a_star(grid, start, goal)`. **The heuristic is ignored**: skyplan searches with its own
/// (octile or Manhattan) heuristic and Jump Point Search, and the path is optimal whatever
/// function FCND code passes.
///
/// `grid`: 2-D array, row = north index (as `create_grid` makes it), nonzero = blocked.
/// `start`, `goal`: `(row, col)` integers. Moves: FCND's by default — 8-connected, diagonals
/// cost √2 and need only their target cell free (`corner_cutting=True`);
/// `corner_cutting=False` also needs both side cells free; `diagonal=False` is 4-connected.
///
/// Returns `(path, cost)`: `path` the list of `(row, col)` tuples from start to goal, both
/// included, `cost` its length in cells. FCND's version prints "Failed to find a path!" and
/// returns `([], 0)`; this one raises `skyplan.NoPath`, and `skyplan.InvalidStart` /
/// `skyplan.InvalidGoal` for a start or goal off the grid or on a blocked cell.
#[pyfunction]
#[pyo3(signature = (grid, *args, diagonal = true, corner_cutting = true))]
pub fn a_star(
    py: Python<'_>,
    grid: &Bound<'_, PyAny>,
    args: &Bound<'_, PyTuple>,
    diagonal: bool,
    corner_cutting: bool,
) -> PyResult<(Vec<(i64, i64)>, f64)> {
    let (start, goal) = match args.len() {
        2 => (args.get_item(0)?, args.get_item(1)?),
        3 => (args.get_item(1)?, args.get_item(2)?),
        n => {
            return Err(bad_input(format!(
                "a_star: expected (grid, start, goal) or FCND's (grid, heuristic, start, goal), got {} positional arguments",
                n + 1
            )));
        }
    };
    let grid = occupancy(grid)?;
    let start = cell_on(&grid, &start, "start")?;
    let goal = cell_on(&grid, &goal, "goal")?;
    let model = match (diagonal, corner_cutting) {
        (false, _) => MoveModel::FourConnected,
        (true, true) => MoveModel::OctileCornerCutting,
        (true, false) => MoveModel::Octile,
    };
    let found = py.detach(|| -> Result<_, PlanFailure> {
        let mut search = CellSearch::new(&grid, PlannerId::Jps, model)?;
        search.search(start, goal).map_err(search_failure)
    });
    let path = found.map_err(to_py)?;
    let cost = path.cost_cells();
    let cells = path
        .cells
        .iter()
        .map(|c| (i64::from(c.row), i64::from(c.col)))
        .collect();
    Ok((cells, cost))
}

/// The first two coordinates of every point of a path, finite.
fn points(path: &[Bound<'_, PyAny>]) -> PyResult<Vec<[f64; 2]>> {
    path.iter()
        .enumerate()
        .map(|(k, p)| {
            let coord = |i: usize| {
                finite(
                    p.get_item(i).and_then(|x| x.extract::<f64>()).ok(),
                    || {
                        format!(
                            "path[{k}]: expected a point (row, col), got {}",
                            describe(p)
                        )
                    },
                    || format!("path[{k}]: {} is not finite", describe(p)),
                )
            };
            Ok([coord(0)?, coord(1)?])
        })
        .collect()
}

/// FCND's collinearity test: `|det([[x1, y1, 1], [x2, y2, 1], [x3, y3, 1]])| < epsilon`.
fn collinear(a: [f64; 2], b: [f64; 2], c: [f64; 2], epsilon: f64) -> bool {
    let det = a[0] * (b[1] - c[1]) + b[0] * (c[1] - a[1]) + c[0] * (a[1] - b[1]);
    det.abs() < epsilon
}

/// FCND's `prune_path`: drops the middle of every three consecutive collinear points.
///
/// The same loop as FCND's (the determinant of the three points with a column of ones, below
/// `epsilon`, removes the middle point); returns a new list of the same point objects. The
/// determinant is computed directly (exact for integer cells) rather than through numpy's LU
/// factorisation: the two agree except for a determinant within rounding of `epsilon`.
#[pyfunction]
#[pyo3(signature = (path, epsilon = 1e-6))]
pub fn prune_path<'py>(path: &Bound<'py, PyAny>, epsilon: f64) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let mut items: Vec<Bound<'py, PyAny>> = path
        .try_iter()
        .map_err(|_| {
            bad_input(format!(
                "path: expected a sequence of points, got {}",
                describe(path)
            ))
        })?
        .collect::<PyResult<_>>()?;
    let mut pts = points(&items)?;
    if !epsilon.is_finite() || epsilon < 0.0 {
        return Err(bad_input(format!(
            "epsilon {epsilon}: expected a tolerance ≥ 0"
        )));
    }
    let mut i = 0;
    while i + 2 < pts.len() {
        if collinear(pts[i], pts[i + 1], pts[i + 2], epsilon) {
            pts.remove(i + 1);
            items.remove(i + 1);
        } else {
            i += 1;
        }
    }
    Ok(items)
}

/// The cells of the Bresenham line from `a` to `b` (both included), as the `bresenham` package
/// FCND's lessons use yields them, all free.
fn bresenham_clear(grid: &Grid2, a: [i64; 2], b: [i64; 2]) -> bool {
    let [x0, y0] = a;
    let (dx, dy) = (b[0] - x0, b[1] - y0);
    let xsign = if dx > 0 { 1 } else { -1 };
    let ysign = if dy > 0 { 1 } else { -1 };
    let (mut dx, mut dy) = (dx.abs(), dy.abs());
    let (xx, xy, yx, yy) = if dx > dy {
        (xsign, 0, 0, ysign)
    } else {
        std::mem::swap(&mut dx, &mut dy);
        (0, ysign, xsign, 0)
    };
    let mut d = 2 * dy - dx;
    let mut y = 0;
    for x in 0..=dx {
        if !grid.is_free_at(x0 + x * xx + y * yx, y0 + x * xy + y * yy) {
            return false;
        }
        if d >= 0 {
            y += 1;
            d -= 2 * dx;
        }
        d += 2 * dy;
    }
    true
}

/// Line-of-sight pruning with Bresenham lines (the FCND lessons' `bresenham` package).
///
/// From each kept point, skips ahead while every cell of the Bresenham line to the next point
/// is free (nonzero = blocked, off the grid = blocked); keeps the first and last points.
/// Bresenham lines may pass between two diagonally touching blocked cells: for a conservative
/// shortcut, plan with `skyplan.Planner`, whose routes are re-checked against every cell they
/// cross.
#[pyfunction]
pub fn bresenham_prune<'py>(
    grid: &Bound<'py, PyAny>,
    path: &Bound<'py, PyAny>,
) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let grid = occupancy(grid)?;
    let items: Vec<Bound<'py, PyAny>> = path
        .try_iter()
        .map_err(|_| {
            bad_input(format!(
                "path: expected a sequence of cells, got {}",
                describe(path)
            ))
        })?
        .collect::<PyResult<_>>()?;
    let cells = items
        .iter()
        .enumerate()
        .map(|(k, p)| int_pair(p, &format!("path[{k}]")))
        .collect::<PyResult<Vec<_>>>()?;
    let n = cells.len();
    if n < 3 {
        return Ok(items);
    }
    let mut keep = vec![0];
    let mut anchor = 0;
    for j in 2..n {
        if !bresenham_clear(&grid, cells[anchor], cells[j]) {
            anchor = j - 1;
            keep.push(anchor);
        }
    }
    keep.push(n - 1);
    Ok(keep.into_iter().map(|k| items[k].clone()).collect())
}
