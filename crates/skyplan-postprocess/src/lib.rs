//! Path post-processing for skyplan: independent passes over a grid path, each of which keeps
//! the path valid (every segment re-checked against the grid) and never makes it longer.
//!
//! * [`prune_collinear`]: drops cells in the middle of straight runs (exact integer test).
//! * [`prune_collinear_eps`]: the FCND determinant test with a tolerance, accepting a removal
//!   only where the new segment has line of sight.
//! * [`shortcut`]: greedy line-of-sight shortcutting with a conservative supercover traversal.
//!
//! ```
//! use skyplan_cspace::{Cell, Grid2};
//! use skyplan_postprocess::{prune_collinear, shortcut, touch_for};
//! use skyplan_search::MoveModel;
//! let grid = Grid2::from_ascii("....\n....\n....")?;
//! let path: Vec<Cell> = [(0, 0), (0, 1), (0, 2), (1, 3), (2, 3)].iter().map(|&(r, c)| Cell::new(r, c)).collect();
//! assert_eq!(prune_collinear(&path).len(), 4);
//! assert_eq!(shortcut(&grid, &path, touch_for(MoveModel::Octile)), vec![Cell::new(0, 0), Cell::new(2, 3)]);
//! # Ok::<(), skyplan_cspace::GridError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use skyplan_cspace::{Cell, Grid2, Touch};
use skyplan_search::MoveModel;

/// The line-of-sight rule that respects a move model's corner rule: only the corner-cutting
/// model may pass between two diagonally adjacent blocked cells.
pub fn touch_for(model: MoveModel) -> Touch {
    model.touch()
}

fn delta(a: Cell, b: Cell) -> (i64, i64) {
    (
        i64::from(b.row) - i64::from(a.row),
        i64::from(b.col) - i64::from(a.col),
    )
}

/// Removes every cell that lies on the straight line between its neighbours, continuing in the
/// same direction (exact integer cross product). Endpoints are kept.
pub fn prune_collinear(cells: &[Cell]) -> Vec<Cell> {
    let mut out: Vec<Cell> = Vec::with_capacity(cells.len());
    for &cell in cells {
        if out.last() == Some(&cell) {
            continue;
        }
        if out.len() >= 2 {
            let (p, q) = (out[out.len() - 2], out[out.len() - 1]);
            let (d1, d2) = (delta(p, q), delta(q, cell));
            let cross = d1.0 * d2.1 - d1.1 * d2.0;
            let dot = d1.0 * d2.0 + d1.1 * d2.1;
            if cross == 0 && dot > 0 {
                out.pop();
            }
        }
        out.push(cell);
    }
    out
}

/// The FCND collinearity test: drops the middle of three points when
/// `|det [[r1, c1, 1], [r2, c2, 1], [r3, c3, 1]]| < epsilon` (in cells²), but only where the
/// grid has line of sight between the remaining neighbours, so the path stays valid.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2, Touch};
/// let grid = Grid2::from_ascii(".....\n.....")?;
/// let path = [Cell::new(0, 0), Cell::new(0, 1), Cell::new(1, 2), Cell::new(1, 3), Cell::new(1, 4)];
/// let pruned = skyplan_postprocess::prune_collinear_eps(&grid, &path, 1.5, Touch::Closed);
/// assert_eq!(pruned, vec![Cell::new(0, 0), Cell::new(1, 4)]);
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn prune_collinear_eps(grid: &Grid2, cells: &[Cell], epsilon: f64, touch: Touch) -> Vec<Cell> {
    let mut out: Vec<Cell> = Vec::with_capacity(cells.len());
    for &cell in cells {
        if out.len() >= 2 {
            let (p, q) = (out[out.len() - 2], out[out.len() - 1]);
            let (d1, d2) = (delta(p, cell), delta(p, q));
            let det = (d1.0 * d2.1 - d1.1 * d2.0) as f64;
            if det.abs() < epsilon && grid.line_of_sight(p, cell, touch) {
                out.pop();
            }
        }
        out.push(cell);
    }
    out
}

/// Greedy line-of-sight shortcutting: from each kept cell, jump to the farthest following cell
/// of the path that is still visible (scanning forward until sight is lost). Every new segment
/// meets only free cells under `touch`, and by the triangle inequality the result is never
/// longer than the input.
pub fn shortcut(grid: &Grid2, cells: &[Cell], touch: Touch) -> Vec<Cell> {
    let Some(&first) = cells.first() else {
        return Vec::new();
    };
    let mut out = vec![first];
    let mut i = 0;
    while i + 1 < cells.len() {
        let mut j = i + 1;
        while j + 1 < cells.len() && grid.line_of_sight(cells[i], cells[j + 1], touch) {
            j += 1;
        }
        out.push(cells[j]);
        i = j;
    }
    out
}

/// Euclidean length of a polyline through cell centres, in cells.
pub fn polyline_length_cells(cells: &[Cell]) -> f64 {
    cells
        .windows(2)
        .map(|w| {
            let (dr, dc) = delta(w[0], w[1]);
            (dr as f64).hypot(dc as f64)
        })
        .sum()
}
