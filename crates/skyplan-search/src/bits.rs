//! Block-based straight scans for JPS (Harabor & Grastien, "Improving Jump Point Search",
//! ICAPS 2014): the grid's free cells packed 64 to a word, row by row and, for vertical scans,
//! column by column (the transpose), so that a scan reads three lines 64 cells at a time and
//! finds its stop with one find-first-set.

use skyplan_cspace::Grid2;

/// Free cells of a grid packed one bit per cell along lines (rows, or columns for the
/// transpose). Bit `i % 64` of word `i / 64` of a line is cell `i` of that line, set iff free.
/// Each line has a zero word before it and one after it, and there is a zero line before the
/// first and after the last, so that the lines beside a scan and the 64 cells past either end
/// read as blocked without a bounds test.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub(crate) struct BitLines {
    /// Number of lines.
    lines: usize,
    /// Cells per line.
    len: usize,
    /// Words per line, padding included: `len.div_ceil(64) + 2`.
    stride: usize,
    /// `(lines + 2) × stride` words; line `l` starts at word `(l + 1) × stride`.
    words: Vec<u64>,
}

impl BitLines {
    /// An all-blocked set of `lines` lines of `len` cells.
    fn blocked(lines: usize, len: usize) -> Self {
        let stride = len.div_ceil(64) + 2;
        BitLines {
            lines,
            len,
            stride,
            words: vec![0; (lines + 2) * stride],
        }
    }

    #[inline(always)]
    fn set(&mut self, line: usize, pos: usize) {
        let w = (line + 1) * self.stride + 1 + pos / 64;
        self.words[w] |= 1 << (pos % 64);
    }

    /// The 64 cells `pos .. pos + 64` of `line` (bit `k` is cell `pos + k`), for `line` in
    /// `-1 ..= lines` and `pos` in `-64 ..= len`.
    #[inline(always)]
    fn ahead(&self, line: i64, pos: i64) -> u64 {
        debug_assert!((-1..=self.lines as i64).contains(&line));
        debug_assert!((-64..=self.len as i64).contains(&pos));
        let p = (pos + 64) as usize;
        let w = (line + 1) as usize * self.stride + p / 64;
        let s = p % 64;
        if s == 0 {
            self.words[w]
        } else {
            (self.words[w] >> s) | (self.words[w + 1] << (64 - s))
        }
    }

    /// The 64 cells `pos - 63 ..= pos` of `line`, nearest `pos` in the high bit (bit `63 - k`
    /// is cell `pos - k`), for `pos` in `-1 ..= len + 63`.
    #[inline(always)]
    fn behind(&self, line: i64, pos: i64) -> u64 {
        self.ahead(line, pos - 63)
    }

    /// The scan of straight JPS along `line` from `pos` (the first cell past the expanded
    /// node) in direction `dir` (±1): the first cell that is the goal (`goal`, its position if
    /// it lies on this line) or has a forced neighbour in a line beside, before the first
    /// blocked cell; `None` if a blocked cell or the grid's edge comes first. Forced means, for
    /// a cell `p` and a side line `s` (`line ± 1`): with corner cutting, `s` is free at
    /// `p + dir` and blocked at `p`; without, `s` is free at `p` and blocked at `p - dir` —
    /// exactly `View::forced_straight`.
    #[inline]
    pub(crate) fn scan(
        &self,
        line: i64,
        mut pos: i64,
        dir: i64,
        corner_cutting: bool,
        goal: Option<i64>,
    ) -> Option<i64> {
        debug_assert!((0..self.lines as i64).contains(&line));
        let (up, down) = (line - 1, line + 1);
        if dir > 0 {
            while pos >= 0 && pos < self.len as i64 {
                let here = self.ahead(line, pos);
                let forced = if corner_cutting {
                    (self.ahead(up, pos + 1) & !self.ahead(up, pos))
                        | (self.ahead(down, pos + 1) & !self.ahead(down, pos))
                } else {
                    (self.ahead(up, pos) & !self.ahead(up, pos - 1))
                        | (self.ahead(down, pos) & !self.ahead(down, pos - 1))
                };
                let stop = (!here).trailing_zeros();
                let mut hit = forced.trailing_zeros();
                if let Some(g) = goal
                    && g >= pos
                    && g - pos < 64
                {
                    hit = hit.min((g - pos) as u32);
                }
                if hit < stop {
                    return Some(pos + i64::from(hit));
                }
                if stop < 64 {
                    return None;
                }
                pos += 64;
            }
        } else {
            while pos >= 0 && pos < self.len as i64 {
                let here = self.behind(line, pos);
                let forced = if corner_cutting {
                    (self.behind(up, pos - 1) & !self.behind(up, pos))
                        | (self.behind(down, pos - 1) & !self.behind(down, pos))
                } else {
                    (self.behind(up, pos) & !self.behind(up, pos + 1))
                        | (self.behind(down, pos) & !self.behind(down, pos + 1))
                };
                let stop = (!here).leading_zeros();
                let mut hit = forced.leading_zeros();
                if let Some(g) = goal
                    && g <= pos
                    && pos - g < 64
                {
                    hit = hit.min((pos - g) as u32);
                }
                if hit < stop {
                    return Some(pos - i64::from(hit));
                }
                if stop < 64 {
                    return None;
                }
                pos -= 64;
            }
        }
        None
    }
}

/// 8 bytes that are each 0 or 1 as 8 bits, byte `k` in bit `k` (each byte's low bit is moved
/// to bit `56 + k` of the product without carries, then shifted down).
#[inline(always)]
fn pack8(bytes: u64) -> u64 {
    bytes.wrapping_mul(0x0102_0408_1020_4080) >> 56
}

/// The free cells of 64 (or fewer, at a row's end) cells given as blocked flags, packed.
#[inline(always)]
fn pack_free(blocked: &[bool]) -> u64 {
    let mut word = 0u64;
    let mut chunks = blocked.chunks_exact(8);
    for (k, chunk) in chunks.by_ref().enumerate() {
        let bytes = u64::from_le_bytes(std::array::from_fn(|i| u8::from(chunk[i])));
        word |= pack8(bytes) << (8 * k);
    }
    let done = blocked.len() - chunks.remainder().len();
    for (k, &b) in chunks.remainder().iter().enumerate() {
        word |= u64::from(b) << (done + k);
    }
    let valid = if blocked.len() == 64 {
        u64::MAX
    } else {
        (1u64 << blocked.len()) - 1
    };
    !word & valid
}

/// A grid's free cells as bit rows and bit columns, built once per grid and kept while the
/// queries use the same grid (checked by packing the grid's rows again and comparing, one read
/// of the grid per query and no copy of it).
#[derive(Debug, Default)]
pub(crate) struct BlockGrid {
    /// Row `r` is line `r`.
    pub(crate) rows: BitLines,
    /// Column `c` is line `c` (the transpose).
    pub(crate) cols: BitLines,
    /// `(rows, cols)` of the grid packed, `None` before the first.
    shape: Option<(u32, u32)>,
}

impl BlockGrid {
    /// Makes these the bits of `grid`, rebuilding them unless they already are.
    pub(crate) fn update(&mut self, grid: &Grid2) {
        if self.shape != Some((grid.rows(), grid.cols())) || !self.rows_match(grid) {
            self.build(grid);
        }
    }

    fn rows_match(&self, grid: &Grid2) -> bool {
        let cols = grid.cols() as usize;
        grid.blocked_cells()
            .chunks_exact(cols)
            .enumerate()
            .all(|(r, row)| {
                let at = (r + 1) * self.rows.stride + 1;
                row.chunks(64)
                    .zip(&self.rows.words[at..])
                    .all(|(cells, &w)| pack_free(cells) == w)
            })
    }

    #[cold]
    fn build(&mut self, grid: &Grid2) {
        let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
        self.rows = BitLines::blocked(rows, cols);
        for (r, row) in grid.blocked_cells().chunks_exact(cols).enumerate() {
            let at = (r + 1) * self.rows.stride + 1;
            for (w, cells) in row.chunks(64).enumerate() {
                self.rows.words[at + w] = pack_free(cells);
            }
        }
        self.cols = BitLines::blocked(cols, rows);
        // Row by row: the words written for 64 consecutive rows (one per column) stay in cache.
        for (r, row) in grid.blocked_cells().chunks_exact(cols).enumerate() {
            for (c, &b) in row.iter().enumerate() {
                if !b {
                    self.cols.set(c, r);
                }
            }
        }
        self.shape = Some((grid.rows(), grid.cols()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MoveModel;
    use crate::jps::View;
    use proptest::prelude::*;
    use skyplan_cspace::{Cell, GridFrame};

    /// The cell-by-cell scan of `View` (the reference): `(r, c)` first, along `(dr, dc)`.
    fn cell_scan(view: &View<'_>, mut r: i64, mut c: i64, dr: i64, dc: i64) -> Option<(i64, i64)> {
        loop {
            if !view.free(r, c) {
                return None;
            }
            if (r, c) == view.goal || view.forced_straight(r, c, dr, dc) {
                return Some((r, c));
            }
            r += dr;
            c += dc;
        }
    }

    fn grid_strategy() -> impl Strategy<Value = Grid2> {
        // Sizes across word edges (63, 64, 65, 127, 128, 129 …), densities from open to cluttered.
        (1u32..140, 1u32..140, 0.0f64..0.6).prop_flat_map(|(rows, cols, density)| {
            proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize)
                .prop_map(move |blocked| {
                    Grid2::new(rows, cols, blocked, GridFrame::default()).unwrap()
                })
        })
    }

    #[test]
    fn pack8_gathers_low_bits() {
        for v in 0u32..256 {
            let bytes = u64::from_le_bytes(std::array::from_fn(|k| ((v >> k) & 1) as u8));
            assert_eq!(pack8(bytes), u64::from(v));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Every straight scan from every free cell, in all four directions and both corner
        /// rules, stops where the cell-by-cell scan stops.
        #[test]
        fn block_scans_stop_where_cell_scans_stop(
            grid in grid_strategy(),
            goal in (0u32..140, 0u32..140),
        ) {
            let goal = Cell::new(goal.0 % grid.rows(), goal.1 % grid.cols());
            let mut bits = BlockGrid::default();
            bits.update(&grid);
            for model in [MoveModel::Octile, MoveModel::OctileCornerCutting] {
                let view = View::new(&grid, goal, model);
                let cc = model == MoveModel::OctileCornerCutting;
                let (gr, gc) = view.goal;
                for r in 0..view.rows {
                    for c in 0..view.cols {
                        for (dr, dc) in [(0, 1), (0, -1), (1, 0), (-1, 0)] {
                            let want = cell_scan(&view, r, c, dr, dc);
                            let got = if dc != 0 {
                                bits.rows.scan(r, c, dc, cc, (gr == r).then_some(gc)).map(|p| (r, p))
                            } else {
                                bits.cols.scan(c, r, dr, cc, (gc == c).then_some(gr)).map(|p| (p, c))
                            };
                            prop_assert_eq!(got, want, "from ({}, {}) along ({}, {}), {:?}", r, c, dr, dc, model);
                        }
                    }
                }
            }
        }

        /// The bits are rebuilt when the grid changes (same shape, one cell flipped) and kept
        /// when it does not.
        #[test]
        fn bits_follow_the_grid(grid in grid_strategy(), flip in (0u32..140, 0u32..140)) {
            let mut bits = BlockGrid::default();
            bits.update(&grid);
            prop_assert!(bits.rows_match(&grid));
            let fresh = |g: &Grid2| {
                let mut b = BlockGrid::default();
                b.build(g);
                (b.rows, b.cols)
            };
            let cell = Cell::new(flip.0 % grid.rows(), flip.1 % grid.cols());
            let mut blocked = grid.blocked_cells().to_vec();
            let i = grid.index(cell);
            blocked[i] = !blocked[i];
            let edited = Grid2::new(grid.rows(), grid.cols(), blocked, GridFrame::default()).unwrap();
            prop_assert!(!bits.rows_match(&edited));
            bits.update(&edited);
            prop_assert_eq!((bits.rows.clone(), bits.cols.clone()), fresh(&edited));
        }
    }
}
