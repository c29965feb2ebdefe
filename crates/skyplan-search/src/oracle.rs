//! The reference oracle: Dijkstra in exact arithmetic, written independently of the fast search.
//!
//! Costs are [`OctileCost`]s `straight + √2 · diagonal` compared exactly with integers, so no
//! floating-point rounding can make the oracle disagree with the truth. It is simple and slow on
//! purpose; tests compare every planner against it.

use crate::MoveModel;
use skyplan_cspace::{Cell, Grid2};
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

/// An exact octile cost `straight + √2 · diagonal`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct OctileCost {
    /// Orthogonal moves.
    pub straight: u64,
    /// Diagonal moves.
    pub diagonal: u64,
}

impl OctileCost {
    /// The cost as a float (the same formula as [`crate::octile_cost`]).
    pub fn to_f64(self) -> f64 {
        crate::octile_cost(self.straight, self.diagonal)
    }
}

impl Ord for OctileCost {
    /// Exact comparison of `a + b√2` with `c + d√2`: the sign of `x − y√2` with `x = a − c`,
    /// `y = d − b`, decided by comparing `x²` with `2y²` when `x` and `y` share a sign.
    ///
    /// ```
    /// use skyplan_search::oracle::OctileCost;
    /// let three_straight = OctileCost { straight: 3, diagonal: 0 };
    /// let two_diagonal = OctileCost { straight: 0, diagonal: 2 }; // 2.828…
    /// assert!(two_diagonal < three_straight);
    /// ```
    fn cmp(&self, other: &Self) -> Ordering {
        let x = i128::from(self.straight) - i128::from(other.straight);
        let y = i128::from(other.diagonal) - i128::from(self.diagonal);
        match (x.signum(), y.signum()) {
            (0, 0) => Ordering::Equal,
            (sx, sy) if sx >= 0 && sy <= 0 => Ordering::Greater,
            (sx, sy) if sx <= 0 && sy >= 0 => Ordering::Less,
            (1, 1) => (x * x).cmp(&(2 * y * y)),
            _ => (2 * y * y).cmp(&(x * x)),
        }
    }
}

impl PartialOrd for OctileCost {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Exact optimal cost from `start` to `goal` under `model`, or `None` if either endpoint is
/// blocked or off the grid, or the goal is unreachable.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_search::{MoveModel, oracle::{dijkstra_exact, OctileCost}};
/// let grid = Grid2::from_ascii("...\n.#.\n...")?;
/// let cost = dijkstra_exact(&grid, Cell::new(0, 0), Cell::new(2, 2), MoveModel::Octile);
/// assert_eq!(cost, Some(OctileCost { straight: 4, diagonal: 0 }));
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn dijkstra_exact(
    grid: &Grid2,
    start: Cell,
    goal: Cell,
    model: MoveModel,
) -> Option<OctileCost> {
    if grid.is_blocked(start) || grid.is_blocked(goal) {
        return None;
    }
    let mut best: Vec<Option<OctileCost>> = vec![None; grid.len()];
    let mut heap = BinaryHeap::new();
    best[grid.index(start)] = Some(OctileCost::default());
    heap.push(Reverse((OctileCost::default(), start)));
    while let Some(Reverse((cost, cell))) = heap.pop() {
        if cell == goal {
            return Some(cost);
        }
        if best[grid.index(cell)].is_some_and(|b| b < cost) {
            continue;
        }
        for dr in -1..=1i64 {
            for dc in -1..=1i64 {
                let diagonal = dr != 0 && dc != 0;
                if (dr == 0 && dc == 0) || (diagonal && !model.has_diagonals()) {
                    continue;
                }
                let (r, c) = (i64::from(cell.row), i64::from(cell.col));
                let Some(next) = grid.checked_cell(r + dr, c + dc) else {
                    continue;
                };
                if grid.is_blocked(next) {
                    continue;
                }
                if diagonal
                    && model != MoveModel::OctileCornerCutting
                    && (!grid.is_free_at(r + dr, c) || !grid.is_free_at(r, c + dc))
                {
                    continue;
                }
                let mut next_cost = cost;
                if diagonal {
                    next_cost.diagonal += 1;
                } else {
                    next_cost.straight += 1;
                }
                let slot = &mut best[grid.index(next)];
                if slot.is_none_or(|b| next_cost < b) {
                    *slot = Some(next_cost);
                    heap.push(Reverse((next_cost, next)));
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn exact_order_agrees_with_floats_when_they_are_far_apart(a in 0u64..10_000, b in 0u64..10_000, c in 0u64..10_000, d in 0u64..10_000) {
            let (p, q) = (OctileCost { straight: a, diagonal: b }, OctileCost { straight: c, diagonal: d });
            let (fp, fq) = (p.to_f64(), q.to_f64());
            if (fp - fq).abs() > 1e-6 {
                prop_assert_eq!(p.cmp(&q), fp.total_cmp(&fq));
            }
            prop_assert_eq!(p.cmp(&q), q.cmp(&p).reverse());
            prop_assert_eq!(p.cmp(&q) == Ordering::Equal, a == c && b == d);
        }
    }
}
