//! Connected free regions of a grid under a move model.

use crate::MoveModel;
use skyplan_cspace::{Cell, Grid2};
use std::collections::VecDeque;

/// Labels of the connected free regions: two free cells are mutually reachable iff they share
/// a label. Without corner cutting, 8-connected reachability equals 4-connected reachability
/// (a diagonal move needs both orthogonal cells free, so it can be replaced by two moves).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Components {
    labels: Vec<u32>,
    sizes: Vec<u64>,
    rows: u32,
    cols: u32,
}

const BLOCKED: u32 = u32::MAX;

impl Components {
    /// Labels every free cell of `grid` (linear time, breadth-first).
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_search::{Components, MoveModel};
    /// let grid = Grid2::from_ascii(".#\n#.")?;
    /// let strict = Components::new(&grid, MoveModel::Octile);
    /// assert!(!strict.connected(Cell::new(0, 0), Cell::new(1, 1)));
    /// assert_eq!(strict.count(), 2);
    /// let loose = Components::new(&grid, MoveModel::OctileCornerCutting);
    /// assert!(loose.connected(Cell::new(0, 0), Cell::new(1, 1)));
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn new(grid: &Grid2, model: MoveModel) -> Self {
        let mut labels = vec![BLOCKED; grid.len()];
        let mut sizes = Vec::new();
        let eight = model == MoveModel::OctileCornerCutting;
        let mut queue = VecDeque::new();
        for seed in 0..grid.len() {
            if labels[seed] != BLOCKED || grid.blocked_cells()[seed] {
                continue;
            }
            let label = sizes.len() as u32;
            labels[seed] = label;
            queue.push_back(seed);
            let mut size = 0u64;
            while let Some(i) = queue.pop_front() {
                size += 1;
                let c = grid.cell(i);
                let (r, col) = (i64::from(c.row), i64::from(c.col));
                for dr in -1..=1i64 {
                    for dc in -1..=1i64 {
                        if (dr == 0 && dc == 0) || (!eight && dr != 0 && dc != 0) {
                            continue;
                        }
                        if let Some(n) = grid.checked_cell(r + dr, col + dc) {
                            let ni = grid.index(n);
                            if labels[ni] == BLOCKED && !grid.blocked_cells()[ni] {
                                labels[ni] = label;
                                queue.push_back(ni);
                            }
                        }
                    }
                }
            }
            sizes.push(size);
        }
        Self {
            labels,
            sizes,
            rows: grid.rows(),
            cols: grid.cols(),
        }
    }

    /// Number of free regions.
    pub fn count(&self) -> usize {
        self.sizes.len()
    }

    /// The region label of a free cell (`None` if blocked or off the grid).
    pub fn label(&self, cell: Cell) -> Option<u32> {
        if cell.row >= self.rows || cell.col >= self.cols {
            return None;
        }
        let l = self.labels[cell.row as usize * self.cols as usize + cell.col as usize];
        (l != BLOCKED).then_some(l)
    }

    /// Number of cells in a region.
    pub fn size(&self, label: u32) -> u64 {
        self.sizes.get(label as usize).copied().unwrap_or(0)
    }

    /// True if both cells are free and mutually reachable.
    pub fn connected(&self, a: Cell, b: Cell) -> bool {
        matches!((self.label(a), self.label(b)), (Some(x), Some(y)) if x == y)
    }
}
