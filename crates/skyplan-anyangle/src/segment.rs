//! The any-angle rule for one straight segment, in exact integer arithmetic.
//!
//! Points are fixed-point: [`SCALE`] units per cell. A segment is free when
//! * every cell whose open interior it meets is free,
//! * every grid edge it runs along (a positive length of it) has a free cell on at least one side,
//! * no grid vertex strictly inside it is a *pinch*: a vertex whose two diagonally opposite cells
//!   are both blocked (the segment would pass between two blocked cells that touch only at a
//!   corner).
//!
//! Cells off the grid count as blocked.

use crate::GridPoint;
use skyplan_cspace::Grid2;

/// Fixed-point units per cell: points are multiples of 1/4096 cell.
pub(crate) const SCALE: i64 = 4096;

/// A point in fixed-point cell units: `r` north, `c` east, [`SCALE`] per cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct Fixed {
    pub(crate) r: i64,
    pub(crate) c: i64,
}

impl Fixed {
    /// The grid vertex (corner) at integer row/column lines.
    pub(crate) fn vertex(r: i64, c: i64) -> Self {
        Self {
            r: r * SCALE,
            c: c * SCALE,
        }
    }

    /// Euclidean distance in cells.
    #[inline]
    pub(crate) fn dist_cells(self, o: Self) -> f64 {
        ((self.r - o.r) as f64).hypot((self.c - o.c) as f64) / SCALE as f64
    }

    pub(crate) fn to_point(self) -> GridPoint {
        GridPoint {
            row: self.r as f64 / SCALE as f64,
            col: self.c as f64 / SCALE as f64,
        }
    }
}

/// Occupancy with a one-cell blocked border, so that every cell a segment between points of the
/// closed grid rectangle can touch has an index.
#[derive(Debug, Clone)]
pub(crate) struct Padded {
    blocked: Vec<bool>,
    width: i64,
    pub(crate) rows: i64,
    pub(crate) cols: i64,
}

impl Padded {
    pub(crate) fn new(grid: &Grid2) -> Self {
        let (rows, cols) = (i64::from(grid.rows()), i64::from(grid.cols()));
        let width = cols + 2;
        let mut blocked = vec![true; ((rows + 2) * width) as usize];
        let src = grid.blocked_cells();
        for r in 0..rows {
            let dst = ((r + 1) * width + 1) as usize;
            let from = (r * cols) as usize;
            blocked[dst..dst + cols as usize].copy_from_slice(&src[from..from + cols as usize]);
        }
        Self {
            blocked,
            width,
            rows,
            cols,
        }
    }

    /// True if cell (r, c) is blocked; valid for -1 ≤ r ≤ rows, -1 ≤ c ≤ cols.
    #[inline(always)]
    pub(crate) fn blocked(&self, r: i64, c: i64) -> bool {
        self.blocked[((r + 1) * self.width + c + 1) as usize]
    }
}

/// Occupancy as the segment rule reads it: cells by signed row/column, off-grid cells blocked.
pub(crate) trait Occupancy {
    /// True if cell (r, c) is blocked or off the grid; called for -1 ≤ r ≤ rows, -1 ≤ c ≤ cols.
    fn blocked(&self, r: i64, c: i64) -> bool;
    /// Grid rows.
    fn rows(&self) -> i64;
    /// Grid columns.
    fn cols(&self) -> i64;

    /// True if the vertex at grid lines (r, c) has both cells of a diagonal pair blocked.
    #[inline]
    fn pinch(&self, r: i64, c: i64) -> bool {
        (self.blocked(r - 1, c - 1) && self.blocked(r, c))
            || (self.blocked(r - 1, c) && self.blocked(r, c - 1))
    }

    /// True if the fixed-point point lies on the closed grid rectangle.
    fn on_grid(&self, p: Fixed) -> bool {
        p.r >= 0 && p.c >= 0 && p.r <= self.rows() * SCALE && p.c <= self.cols() * SCALE
    }

    /// True if a path may stand at point `p` (on the grid): it touches a free cell.
    fn point_free(&self, p: Fixed) -> bool {
        let rows: &[i64] = if p.r % SCALE == 0 {
            &[p.r / SCALE - 1, p.r / SCALE]
        } else {
            &[p.r.div_euclid(SCALE)]
        };
        let cols: &[i64] = if p.c % SCALE == 0 {
            &[p.c / SCALE - 1, p.c / SCALE]
        } else {
            &[p.c.div_euclid(SCALE)]
        };
        rows.iter()
            .any(|&r| cols.iter().any(|&c| !self.blocked(r, c)))
    }

    /// The segment rule (module docs) for two points on the grid.
    fn segment_free(&self, a: Fixed, b: Fixed) -> bool {
        if a == b {
            return self.point_free(a);
        }
        if a.r == b.r {
            return self.axis_free(a.r, a.c.min(b.c), a.c.max(b.c), false);
        }
        if a.c == b.c {
            return self.axis_free(a.c, a.r.min(b.r), a.r.max(b.r), true);
        }
        let (p, q) = if a.r < b.r { (a, b) } else { (b, a) };
        let dy = q.r - p.r; // > 0
        let dx = q.c - p.c; // != 0
        let den = SCALE * dy;
        let k0 = p.r.div_euclid(SCALE);
        let k1 = ceil_div(q.r, SCALE) - 1;
        // x · dy at height y is an exact numerator over `dy`; its column is the numerator's
        // quotient by `den`, kept with the remainder and advanced band by band (no division in
        // the loop).
        let divmod = |n: i64| (n.div_euclid(den), n.rem_euclid(den));
        let (step_q, step_r) = divmod(SCALE * dx);
        let (mut qa, mut ra) = divmod(p.c * dy);
        for k in k0..=k1 {
            let (qb, rb) = if k == k1 {
                divmod(q.c * dy)
            } else if k == k0 {
                divmod(p.c * dy + ((k + 1) * SCALE - p.r) * dx)
            } else {
                let (mut qb, mut rb) = (qa + step_q, ra + step_r);
                if rb >= den {
                    rb -= den;
                    qb += 1;
                }
                (qb, rb)
            };
            // Columns whose open interval meets the open x-range of this band.
            let (c_min, c_max) = if dx > 0 {
                (qa, qb + i64::from(rb > 0) - 1)
            } else {
                (qb, qa + i64::from(ra > 0) - 1)
            };
            for c in c_min..=c_max {
                if self.blocked(k, c) {
                    return false;
                }
            }
            if k < k1 && rb == 0 && self.pinch(k + 1, qb) {
                return false;
            }
            (qa, ra) = (qb, rb);
        }
        true
    }

    /// A segment along one axis: `fixed` is its constant coordinate (a row if `vertical` is
    /// false, else a column), `lo < hi` the range of the other.
    fn axis_free(&self, fixed: i64, lo: i64, hi: i64, vertical: bool) -> bool {
        let blocked = |line: i64, along: i64| {
            if vertical {
                self.blocked(along, line)
            } else {
                self.blocked(line, along)
            }
        };
        let first = lo.div_euclid(SCALE);
        let last = ceil_div(hi, SCALE) - 1;
        if fixed % SCALE == 0 {
            let k = fixed / SCALE;
            for j in first..=last {
                if blocked(k - 1, j) && blocked(k, j) {
                    return false;
                }
            }
            for j in first + 1..=last {
                let pinch = if vertical {
                    self.pinch(j, k)
                } else {
                    self.pinch(k, j)
                };
                if pinch {
                    return false;
                }
            }
        } else {
            let k = fixed.div_euclid(SCALE);
            for j in first..=last {
                if blocked(k, j) {
                    return false;
                }
            }
        }
        true
    }
}

impl Occupancy for Padded {
    #[inline(always)]
    fn blocked(&self, r: i64, c: i64) -> bool {
        Padded::blocked(self, r, c)
    }
    fn rows(&self) -> i64 {
        self.rows
    }
    fn cols(&self) -> i64 {
        self.cols
    }
}

/// A [`Grid2`] read directly (bounds-checked), for one-off segment tests.
pub(crate) struct GridView<'a>(pub(crate) &'a Grid2);

impl Occupancy for GridView<'_> {
    #[inline]
    fn blocked(&self, r: i64, c: i64) -> bool {
        !self.0.is_free_at(r, c)
    }
    fn rows(&self) -> i64 {
        i64::from(self.0.rows())
    }
    fn cols(&self) -> i64 {
        i64::from(self.0.cols())
    }
}

#[inline]
fn ceil_div(a: i64, b: i64) -> i64 {
    -((-a).div_euclid(b))
}
