//! Line of sight on a [`Grid2`]: which cells a straight segment touches.
//!
//! Two traversals, written independently so that each checks the other in tests:
//! * [`Grid2::line_of_sight`] between cell centres, in integer arithmetic (a supercover
//!   Bresenham walk), the fast path for shortcutting;
//! * [`Grid2::segment_is_free_ne`] between arbitrary local points, row band by row band.

use crate::{Cell, Grid2};

/// Which cells a segment must keep free.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Touch {
    /// Every cell whose closed square the segment meets, including cells it only touches at a
    /// corner: the segment never squeezes between two diagonal blocked cells. Conservative; the
    /// rule for moves without corner cutting. The default.
    #[default]
    Closed,
    /// Only cells whose interior the segment crosses (corner cutting allowed).
    Open,
}

impl Grid2 {
    /// Calls `visit` for every cell the segment between the centres of `a` and `b` meets (in
    /// order from `a`), stopping early when `visit` returns `false`. Returns `false` iff stopped.
    /// Coordinates may lie off the grid.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2, Touch};
    /// let mut cells = vec![];
    /// Grid2::supercover(Cell::new(0, 0), Cell::new(1, 1), Touch::Closed, |r, c| { cells.push((r, c)); true });
    /// assert_eq!(cells, vec![(0, 0), (1, 0), (0, 1), (1, 1)]);
    /// ```
    pub fn supercover(
        a: Cell,
        b: Cell,
        touch: Touch,
        mut visit: impl FnMut(i64, i64) -> bool,
    ) -> bool {
        let (mut r, mut c) = (i64::from(a.row), i64::from(a.col));
        let (dr, dc) = (i64::from(b.row) - r, i64::from(b.col) - c);
        let (sr, sc) = (dr.signum(), dc.signum());
        let (nr, nc) = (dr.abs(), dc.abs());
        // error > 0: the next boundary crossed is a column boundary; < 0: a row boundary;
        // == 0: the segment passes exactly through a grid vertex.
        let mut error = nc - nr;
        let (two_nr, two_nc) = (2 * nr, 2 * nc);
        let mut steps = nr + nc;
        if !visit(r, c) {
            return false;
        }
        while steps > 0 {
            if error > 0 {
                c += sc;
                error -= two_nr;
                steps -= 1;
            } else if error < 0 {
                r += sr;
                error += two_nc;
                steps -= 1;
            } else {
                if touch == Touch::Closed && !(visit(r + sr, c) && visit(r, c + sc)) {
                    return false;
                }
                r += sr;
                c += sc;
                error += two_nc - two_nr;
                steps -= 2;
            }
            if !visit(r, c) {
                return false;
            }
        }
        true
    }

    /// True if the straight segment between the centres of `a` and `b` meets only free cells.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2, Touch};
    /// let grid = Grid2::from_ascii("...\n.#.\n...")?;
    /// assert!(grid.line_of_sight(Cell::new(0, 0), Cell::new(0, 2), Touch::Closed));
    /// assert!(!grid.line_of_sight(Cell::new(0, 0), Cell::new(2, 2), Touch::Closed));
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn line_of_sight(&self, a: Cell, b: Cell, touch: Touch) -> bool {
        Self::supercover(a, b, touch, |r, c| self.is_free_at(r, c))
    }

    /// True if the straight segment between two local (north, east) points meets only free cells
    /// of the grid (cells off the grid count as blocked). Floating-point ties are resolved
    /// conservatively for [`Touch::Closed`] (a segment within 1e-9 cell of a cell touches it).
    ///
    /// ```
    /// use skyplan_cspace::{Grid2, Touch};
    /// let grid = Grid2::from_ascii("..\n#.")?; // row 1, col 0 is blocked
    /// assert!(grid.segment_is_free_ne((0.2, 0.2), (1.9, 1.9), Touch::Open));
    /// assert!(!grid.segment_is_free_ne((0.2, 0.2), (1.9, 1.9), Touch::Closed));
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn segment_is_free_ne(&self, a_ne: (f64, f64), b_ne: (f64, f64), touch: Touch) -> bool {
        let f = self.frame();
        let to_rc = |(n, e): (f64, f64)| {
            (
                (n - f.origin_north_m) / f.cell_m,
                (e - f.origin_east_m) / f.cell_m,
            )
        };
        let ((u0, v0), (u1, v1)) = (to_rc(a_ne), to_rc(b_ne));
        if ![u0, v0, u1, v1].iter().all(|x| x.is_finite()) {
            return false;
        }
        // Grow (closed) or shrink (open) every cell by `eps` cell widths.
        let eps = match touch {
            Touch::Closed => 1e-9,
            Touch::Open => -1e-9,
        };
        let (umin, umax) = (u0.min(u1), u0.max(u1));
        let first_row = (umin - eps).ceil() as i64 - 1;
        let last_row = (umax + eps).floor() as i64;
        for r in first_row..=last_row {
            // Part of the segment inside the (grown) band r - eps ≤ u ≤ r + 1 + eps.
            let (lo, hi) = (r as f64 - eps, r as f64 + 1.0 + eps);
            let (t0, t1) = if u1 == u0 {
                if u0 < lo || u0 > hi {
                    continue;
                }
                (0.0, 1.0)
            } else {
                let (ta, tb) = ((lo - u0) / (u1 - u0), (hi - u0) / (u1 - u0));
                (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
            };
            if t0 > t1 {
                continue;
            }
            let (va, vb) = (v0 + (v1 - v0) * t0, v0 + (v1 - v0) * t1);
            let first_col = (va.min(vb) - eps).ceil() as i64 - 1;
            let last_col = (va.max(vb) + eps).floor() as i64;
            if (first_col..=last_col).any(|c| !self.is_free_at(r, c)) {
                return false;
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::GridFrame;
    use proptest::prelude::*;

    /// Exact brute force in doubled integer coordinates: does the segment between the centres
    /// of `a` and `b` meet the closed (or open) square of cell (r, c)?
    fn meets(a: Cell, b: Cell, r: i64, c: i64, touch: Touch) -> bool {
        let (pr, pc) = (2 * i64::from(a.row) + 1, 2 * i64::from(a.col) + 1);
        let (qr, qc) = (2 * i64::from(b.row) + 1, 2 * i64::from(b.col) + 1);
        let corners = [
            (2 * r, 2 * c),
            (2 * r + 2, 2 * c),
            (2 * r, 2 * c + 2),
            (2 * r + 2, 2 * c + 2),
        ];
        let side = |(x, y): (i64, i64)| ((qr - pr) * (y - pc) - (qc - pc) * (x - pr)).signum();
        let sides: Vec<i64> = corners.iter().map(|&k| side(k)).collect();
        let (rlo, rhi, clo, chi) = (pr.min(qr), pr.max(qr), pc.min(qc), pc.max(qc));
        match touch {
            Touch::Closed => {
                let bbox = rhi >= 2 * r && rlo <= 2 * r + 2 && chi >= 2 * c && clo <= 2 * c + 2;
                bbox && !(sides.iter().all(|&s| s > 0) || sides.iter().all(|&s| s < 0))
            }
            Touch::Open => {
                let bbox = rhi > 2 * r && rlo < 2 * r + 2 && chi > 2 * c && clo < 2 * c + 2;
                let line_through =
                    (sides.contains(&1) && sides.contains(&-1)) || (pr == qr || pc == qc);
                bbox && line_through
            }
        }
    }

    proptest! {
        #[test]
        fn supercover_visits_exactly_the_cells_the_segment_meets(
            ar in 0u32..12, ac in 0u32..12, br in 0u32..12, bc in 0u32..12, closed in any::<bool>()
        ) {
            let touch = if closed { Touch::Closed } else { Touch::Open };
            let (a, b) = (Cell::new(ar, ac), Cell::new(br, bc));
            let mut got = vec![];
            Grid2::supercover(a, b, touch, |r, c| { got.push((r, c)); true });
            let mut sorted = got.clone();
            sorted.sort_unstable();
            sorted.dedup();
            prop_assert_eq!(sorted.len(), got.len(), "a cell visited twice");
            let mut want = vec![];
            for r in -1..13 {
                for c in -1..13 {
                    if meets(a, b, r, c, touch) { want.push((r, c)); }
                }
            }
            prop_assert_eq!(sorted, want);
        }

        #[test]
        fn both_traversals_agree_between_cell_centres(
            cells in proptest::collection::vec(proptest::bool::weighted(0.15), 64), ar in 0u32..8, ac in 0u32..8, br in 0u32..8, bc in 0u32..8,
            closed in any::<bool>()
        ) {
            let touch = if closed { Touch::Closed } else { Touch::Open };
            let grid = Grid2::new(8, 8, cells, GridFrame { origin_north_m: -3.0, origin_east_m: 7.0, cell_m: 2.5 }).unwrap();
            let (a, b) = (Cell::new(ar, ac), Cell::new(br, bc));
            prop_assert_eq!(grid.line_of_sight(a, b, touch), grid.segment_is_free_ne(grid.center_ne(a), grid.center_ne(b), touch));
        }
    }
}
