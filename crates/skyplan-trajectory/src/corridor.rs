//! The safe flight corridor: free space as the trajectory sees it ([`FreeSpace`], for box worlds
//! and grids), and a chain of free axis-aligned boxes grown around the route.

use crate::TrajectoryError;
use skyplan_cspace::{Grid2, Touch};
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, Neu};

/// Free space, exactly: what a trajectory may fly through (obstacles already grown by the
/// margin). Implemented for the 3D box world and for a grid at one altitude.
pub trait FreeSpace {
    /// Whether every point of the closed box is free.
    fn box_is_free(&self, b: &Aabb) -> bool;
    /// Whether every point of the segment is free.
    fn segment_is_free(&self, a: Neu, b: Neu) -> bool;
    /// Whether the point is free.
    fn point_is_free(&self, p: Neu) -> bool {
        self.box_is_free(&Aabb { min: p, max: p })
    }
}

impl FreeSpace for BoxWorld3 {
    fn box_is_free(&self, b: &Aabb) -> bool {
        BoxWorld3::box_is_free(self, b)
    }

    fn segment_is_free(&self, a: Neu, b: Neu) -> bool {
        CollisionChecker::segment_is_free(self, a, b)
    }
}

/// A 2D grid flown at one altitude: a point is free iff it is at that altitude and every cell
/// whose closed square holds it is free (cells off the grid are blocked). Box tests are O(1)
/// through a summed-area table of blocked cells.
#[derive(Debug, Clone)]
pub struct GridLayer {
    grid: Grid2,
    alt_m: f64,
    /// `sum[(r)(cols+1) + c]`: blocked cells in rows `< r`, columns `< c`.
    sum: Vec<u32>,
}

impl GridLayer {
    /// The grid's free space at `alt_m`.
    ///
    /// ```
    /// use skyplan_cspace::Grid2;
    /// use skyplan_trajectory::{FreeSpace, GridLayer};
    /// use skyplan_world3::Aabb;
    /// let layer = GridLayer::new(Grid2::from_ascii("...\n.#.\n...")?, 10.0);
    /// assert!(layer.box_is_free(&Aabb { min: [0.1, 0.1, 10.0], max: [0.9, 2.9, 10.0] }));
    /// assert!(!layer.box_is_free(&Aabb { min: [0.1, 0.1, 10.0], max: [1.0, 2.9, 10.0] })); // touches the wall cell
    /// assert!(!layer.box_is_free(&Aabb { min: [0.0, 0.1, 10.0], max: [0.9, 2.9, 10.0] })); // the grid's edge
    /// assert!(!layer.box_is_free(&Aabb { min: [0.1, 0.1, 11.0], max: [0.9, 2.9, 11.0] })); // another altitude
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn new(grid: Grid2, alt_m: f64) -> Self {
        let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
        let blocked = grid.blocked_cells();
        let mut sum = vec![0u32; (rows + 1) * (cols + 1)];
        for r in 0..rows {
            let mut row_sum = 0u32;
            for c in 0..cols {
                row_sum += u32::from(blocked[r * cols + c]);
                sum[(r + 1) * (cols + 1) + c + 1] = sum[r * (cols + 1) + c + 1] + row_sum;
            }
        }
        Self { grid, alt_m, sum }
    }

    /// The altitude flown, metres.
    pub fn alt_m(&self) -> f64 {
        self.alt_m
    }

    /// The inclusive cell range whose closed squares meet `[lo, hi]` along one axis, or `None`
    /// if any of it is off the grid.
    fn range(lo: f64, hi: f64, origin: f64, cell_m: f64, n: u32) -> Option<(usize, usize)> {
        let a = ((lo - origin) / cell_m).ceil() - 1.0;
        let b = ((hi - origin) / cell_m).floor();
        // A point exactly on the grid's outer edge touches an off-grid cell: blocked.
        if !(a.is_finite() && b.is_finite()) || a < 0.0 || b > f64::from(n) - 1.0 {
            return None;
        }
        Some((a as usize, b as usize))
    }
}

impl FreeSpace for GridLayer {
    fn box_is_free(&self, b: &Aabb) -> bool {
        let tol = 1e-9;
        if (b.min[2] - self.alt_m).abs() > tol || (b.max[2] - self.alt_m).abs() > tol {
            return false;
        }
        let f = self.grid.frame();
        let Some((r0, r1)) = Self::range(
            b.min[0],
            b.max[0],
            f.origin_north_m,
            f.cell_m,
            self.grid.rows(),
        ) else {
            return false;
        };
        let Some((c0, c1)) = Self::range(
            b.min[1],
            b.max[1],
            f.origin_east_m,
            f.cell_m,
            self.grid.cols(),
        ) else {
            return false;
        };
        let w = self.grid.cols() as usize + 1;
        let s = |r: usize, c: usize| self.sum[r * w + c];
        s(r1 + 1, c1 + 1) + s(r0, c0) == s(r0, c1 + 1) + s(r1 + 1, c0)
    }

    fn segment_is_free(&self, a: Neu, b: Neu) -> bool {
        let tol = 1e-9;
        (a[2] - self.alt_m).abs() <= tol
            && (b[2] - self.alt_m).abs() <= tol
            && self
                .grid
                .segment_is_free_ne((a[0], a[1]), (b[0], b[1]), Touch::Closed)
    }
}

/// One stretch of the route with the free box its trajectory piece must stay in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorridorCell {
    /// Where the stretch of route starts.
    pub from: Neu,
    /// Where it ends.
    pub to: Neu,
    /// The free box around it.
    pub region: Aabb,
}

/// How the corridor is built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorridorOptions {
    /// Longest stretch of route per piece, metres.
    pub piece_m: f64,
    /// Farthest a box grows beyond its stretch on each side, metres.
    pub grow_m: f64,
}

fn seed(a: Neu, b: Neu) -> Aabb {
    Aabb {
        min: [0, 1, 2].map(|k| a[k].min(b[k])),
        max: [0, 1, 2].map(|k| a[k].max(b[k])),
    }
}

/// Grows `b` face by face while it stays free, by halving steps down to 1/128 of `grow_m`.
fn grow(free: &dyn FreeSpace, mut b: Aabb, axes: usize, grow_m: f64) -> Aabb {
    let steps = [0.5, 0.25, 0.125, 0.0625, 0.03125, 0.015625, 0.0078125].map(|f| f * grow_m);
    for axis in 0..axes {
        for upward in [false, true] {
            let mut grown = 0.0;
            for &step in &steps {
                while grown + step <= grow_m + 1e-12 {
                    let mut trial = b;
                    if upward {
                        trial.max[axis] += step;
                    } else {
                        trial.min[axis] -= step;
                    }
                    if !free.box_is_free(&trial) {
                        break;
                    }
                    b = trial;
                    grown += step;
                }
            }
        }
    }
    b
}

/// Splits a stretch until each part's bounding box is free, then grows each box.
fn cover(
    free: &dyn FreeSpace,
    a: Neu,
    b: Neu,
    axes: usize,
    opts: &CorridorOptions,
    depth: u32,
    out: &mut Vec<CorridorCell>,
) -> Result<(), TrajectoryError> {
    let s = seed(a, b);
    if free.box_is_free(&s) {
        out.push(CorridorCell {
            from: a,
            to: b,
            region: grow(free, s, axes, opts.grow_m),
        });
        return Ok(());
    }
    let len = skyplan_world3::distance_m(a, b);
    if depth == 0 || len < 1e-3 {
        return Err(TrajectoryError::Corridor {
            near_neu: skyplan_world3::lerp(a, b, 0.5),
            why: if free.segment_is_free(a, b) {
                "the route passes too close to an obstacle for a free box around it (a route that cuts a corner between obstacles, or grazes one)".into()
            } else {
                "the route itself is not in free space here".into()
            },
        });
    }
    let m = skyplan_world3::lerp(a, b, 0.5);
    cover(free, a, m, axes, opts, depth - 1, out)?;
    cover(free, m, b, axes, opts, depth - 1, out)
}

/// The corridor of a route: consecutive cells share their end points, so consecutive boxes
/// overlap (both hold the shared point). `planar` keeps the altitude fixed (boxes of zero
/// height).
pub fn build_corridor(
    route: &[Neu],
    free: &dyn FreeSpace,
    planar: bool,
    opts: &CorridorOptions,
) -> Result<Vec<CorridorCell>, TrajectoryError> {
    let axes = if planar { 2 } else { 3 };
    let mut out = Vec::new();
    for w in route.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = skyplan_world3::distance_m(a, b);
        if len <= 1e-9 {
            continue;
        }
        let parts = (len / opts.piece_m).ceil().max(1.0) as usize;
        for k in 0..parts {
            let p = skyplan_world3::lerp(a, b, k as f64 / parts as f64);
            let q = skyplan_world3::lerp(a, b, (k + 1) as f64 / parts as f64);
            let mut parts = Vec::new();
            cover(free, p, q, axes, opts, 24, &mut parts)?;
            out.extend(merge(parts));
        }
    }
    Ok(out)
}

/// Joins the parts of one split stretch while a part's box holds the next part (splitting near
/// obstacles leaves many short ones; the parts are collinear).
fn merge(cells: Vec<CorridorCell>) -> Vec<CorridorCell> {
    let mut out: Vec<CorridorCell> = Vec::with_capacity(cells.len());
    for c in cells {
        if let Some(last) = out.last_mut()
            && last.region.holds(&seed(c.from, c.to))
        {
            last.to = c.to;
            continue;
        }
        out.push(c);
    }
    out
}
