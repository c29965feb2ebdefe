//! The moves of a [`MoveModel`] in one fixed order, the tie-break every extraction uses.

use skyplan_cspace::{Cell, Grid2};
use skyplan_search::MoveModel;

/// Offsets `(d_row, d_col)`: [`skyplan_cspace::NEIGHBOURS_8`], straight moves first. Ties are
/// broken by this order.
pub(crate) const OFFSETS: [(i64, i64); 8] = skyplan_cspace::NEIGHBOURS_8;

/// Calls `visit(next, diagonal)` for every legal move from `from` on `grid` under `model`, in
/// [`OFFSETS`] order. A move is legal if its target is on the grid and free and, for a diagonal
/// without corner cutting, both orthogonally adjacent cells are free. Legality is symmetric, so
/// the same function serves fields grown from the goal.
#[inline]
pub(crate) fn for_each_move(
    grid: &Grid2,
    from: Cell,
    model: MoveModel,
    mut visit: impl FnMut(Cell, bool),
) {
    let count = if model.has_diagonals() { 8 } else { 4 };
    let (r, c) = (i64::from(from.row), i64::from(from.col));
    for &(dr, dc) in &OFFSETS[..count] {
        let Some(next) = grid.checked_cell(r + dr, c + dc) else {
            continue;
        };
        if grid.is_blocked(next) {
            continue;
        }
        let diagonal = dr != 0 && dc != 0;
        if diagonal && !model.corner_ok(grid, from, dr, dc) {
            continue;
        }
        visit(next, diagonal);
    }
}

/// Heap key of a non-negative finite float: its bits order like the number.
#[inline]
pub(crate) fn key(value: f64) -> u64 {
    value.to_bits()
}
