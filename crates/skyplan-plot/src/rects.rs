//! Blocked cells merged into rectangles, so that a city grid draws as a few hundred shapes.

use skyplan_cspace::Grid2;

/// A rectangle of grid cells: rows `row..row + rows`, columns `col..col + cols`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CellRect {
    /// First (southernmost) row.
    pub row: u32,
    /// First (westernmost) column.
    pub col: u32,
    /// Number of rows (≥ 1).
    pub rows: u32,
    /// Number of columns (≥ 1).
    pub cols: u32,
}

/// The blocked cells of a grid as disjoint rectangles that cover them exactly.
///
/// Each row is cut into maximal runs of blocked cells, and a run is stacked with the identical
/// runs of the rows above it, so buildings grown by a margin come out as a few rectangles each.
///
/// ```
/// use skyplan_cspace::Grid2;
/// use skyplan_plot::{CellRect, blocked_rects};
/// let grid = Grid2::from_ascii("##..\n##.#\n...#")?;
/// assert_eq!(
///     blocked_rects(&grid),
///     vec![CellRect { row: 0, col: 0, rows: 2, cols: 2 }, CellRect { row: 1, col: 3, rows: 2, cols: 1 }]
/// );
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn blocked_rects(grid: &Grid2) -> Vec<CellRect> {
    let cols = grid.cols() as usize;
    let mut out = Vec::new();
    if cols == 0 {
        return out;
    }
    // Runs of the previous row, (start col, end col exclusive, first row), sorted by start.
    let mut open: Vec<(u32, u32, u32)> = Vec::new();
    let mut next: Vec<(u32, u32, u32)> = Vec::new();
    for (r, line) in grid.blocked_cells().chunks_exact(cols).enumerate() {
        let r = r as u32;
        next.clear();
        let mut prev = open.iter().peekable();
        let mut c = 0;
        while c < cols {
            if !line[c] {
                c += 1;
                continue;
            }
            let start = c;
            while c < cols && line[c] {
                c += 1;
            }
            let (c0, c1) = (start as u32, c as u32);
            // Close the previous row's runs that end before this one starts or differ from it.
            let mut first_row = r;
            while let Some(&&(p0, p1, pr)) = prev.peek() {
                if p0 > c0 {
                    break;
                }
                prev.next();
                if (p0, p1) == (c0, c1) {
                    first_row = pr;
                } else {
                    out.push(CellRect {
                        row: pr,
                        col: p0,
                        rows: r - pr,
                        cols: p1 - p0,
                    });
                }
            }
            next.push((c0, c1, first_row));
        }
        for &(p0, p1, pr) in prev {
            out.push(CellRect {
                row: pr,
                col: p0,
                rows: r - pr,
                cols: p1 - p0,
            });
        }
        std::mem::swap(&mut open, &mut next);
    }
    let end = grid.rows();
    out.extend(open.iter().map(|&(p0, p1, pr)| CellRect {
        row: pr,
        col: p0,
        rows: end - pr,
        cols: p1 - p0,
    }));
    out.sort_unstable();
    out
}
