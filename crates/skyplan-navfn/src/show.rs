//! Aligned text pictures of small grids: the workspace, the distance matrix and the path.
//!
//! North is up: the first line printed is the grid's top (northernmost) row, the last line row 0.
//! Row numbers stand at the left, column numbers (last digit) above.
//!
//! ```
//! use skyplan_cspace::{Cell, Grid2};
//! use skyplan_navfn::{distance_field, show, FieldMetric, MoveModel};
//! let grid = Grid2::from_ascii("...\n.#.\n...")?; // row 0 first
//! let field = distance_field(&grid, Cell::new(2, 2), MoveModel::FourConnected, FieldMetric::Steps)?;
//! let path = field.descend(Cell::new(0, 0))?.cells;
//! let text = show::workspace(&grid, Some(Cell::new(0, 0)), Some(Cell::new(2, 2)), &path, Some(&field));
//! assert_eq!(text, "   012\n 2 **D\n 1 *#.\n 0 S..\n");
//! let matrix = show::distance_matrix(&field, Some(Cell::new(0, 0)));
//! assert_eq!(matrix, "    0 1 2\n 2  2 1 D\n 1  3 # 1\n 0  S 3 2\n");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::{DistanceField, FieldMetric};
use skyplan_cspace::{Cell, Grid2};
use std::collections::HashSet;
use std::fmt::Write;

/// The legend of [`workspace`].
pub const WORKSPACE_LEGEND: &str =
    "# obstacle, . free, S source, D destination, * path, x unreachable from the destination";
/// The legend of [`distance_matrix`].
pub const MATRIX_LEGEND: &str =
    "distance to the destination; # obstacle, ∞ unreachable, S source, D destination";

/// Largest grid [`picture`] draws, rows.
pub const MAX_ROWS: u32 = 60;
/// Largest grid [`picture`] draws, columns.
pub const MAX_COLS: u32 = 80;

/// The whole text picture: the workspace (with the field's unreachable cells), the distance
/// matrix of the field grown from `destination` under `model` and `metric` (when it grows), and
/// the path as a list of cells. A grid over [`MAX_COLS`] × [`MAX_ROWS`] is refused with why.
pub fn picture(
    grid: &Grid2,
    source: Cell,
    destination: Cell,
    path: &[Cell],
    model: crate::MoveModel,
    metric: FieldMetric,
) -> Result<String, String> {
    if grid.rows() > MAX_ROWS || grid.cols() > MAX_COLS {
        return Err(format!(
            "the grid is {} × {} cells; text output is for grids up to {MAX_COLS} × {MAX_ROWS}",
            grid.rows(),
            grid.cols()
        ));
    }
    let field = crate::distance_field(grid, destination, model, metric).ok();
    let mut text = format!("workspace (north up; {WORKSPACE_LEGEND})\n");
    text += &workspace(grid, Some(source), Some(destination), path, field.as_ref());
    if let Some(field) = &field {
        text += &format!("\ndistance matrix (cells; {MATRIX_LEGEND})\n");
        text += &distance_matrix(field, Some(source));
    }
    if !path.is_empty() {
        let cells: Vec<String> = path
            .iter()
            .map(|c| format!("({},{})", c.row, c.col))
            .collect();
        text += &format!("\npath (row,col): {}\n", cells.join(" → "));
    }
    Ok(text)
}

fn row_label_width(grid: &Grid2) -> usize {
    grid.rows().saturating_sub(1).to_string().len() + 1
}

/// The workspace: one character per cell. With a field, free cells it cannot reach are `x`.
pub fn workspace(
    grid: &Grid2,
    source: Option<Cell>,
    destination: Option<Cell>,
    path: &[Cell],
    field: Option<&DistanceField>,
) -> String {
    let on_path: HashSet<Cell> = path.iter().copied().collect();
    let w = row_label_width(grid);
    let mut out = format!("{:w$} ", "");
    for col in 0..grid.cols() {
        let _ = write!(out, "{}", col % 10);
    }
    out.push('\n');
    for row in (0..grid.rows()).rev() {
        let _ = write!(out, "{row:>w$} ");
        for col in 0..grid.cols() {
            let cell = Cell::new(row, col);
            let ch = if Some(cell) == source {
                'S'
            } else if Some(cell) == destination {
                'D'
            } else if grid.is_blocked(cell) {
                '#'
            } else if on_path.contains(&cell) {
                '*'
            } else if field.is_some_and(|f| f.value(cell).is_none()) {
                'x'
            } else {
                '.'
            };
            out.push(ch);
        }
        out.push('\n');
    }
    out
}

/// The distance matrix: every cell's distance to the destination, right-aligned in columns
/// (whole moves for [`FieldMetric::Steps`], one decimal for lengths).
pub fn distance_matrix(field: &DistanceField, source: Option<Cell>) -> String {
    let grid = field.grid();
    let text = |cell: Cell| -> String {
        if Some(cell) == source {
            "S".into()
        } else if cell == field.goal() {
            "D".into()
        } else if grid.is_blocked(cell) {
            "#".into()
        } else {
            match (field.value(cell), field.metric()) {
                (None, _) => "∞".into(),
                (Some(v), FieldMetric::Steps) => format!("{v:.0}"),
                (Some(v), FieldMetric::Length) => format!("{v:.1}"),
            }
        }
    };
    let cells: Vec<Vec<String>> = (0..grid.rows())
        .rev()
        .map(|row| {
            (0..grid.cols())
                .map(|col| text(Cell::new(row, col)))
                .collect()
        })
        .collect();
    let width = cells
        .iter()
        .flatten()
        .map(|s| s.chars().count())
        .chain(std::iter::once(
            grid.cols().saturating_sub(1).to_string().len(),
        ))
        .max()
        .unwrap_or(1);
    let w = row_label_width(grid);
    let mut out = format!("{:w$} ", "");
    for col in 0..grid.cols() {
        let _ = write!(out, " {col:>width$}");
    }
    out.push('\n');
    for (k, line) in cells.iter().enumerate() {
        let row = grid.rows() as usize - 1 - k;
        let _ = write!(out, "{row:>w$} ");
        for s in line {
            let pad = width.saturating_sub(s.chars().count());
            let _ = write!(out, " {}{s}", " ".repeat(pad));
        }
        out.push('\n');
    }
    out
}
