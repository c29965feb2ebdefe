//! Exact any-angle (Euclidean) shortest paths on a [`Grid2`].
//!
//! The rule (Anya's, Harabor et al., JAIR 2016): a path is a polyline that never enters a blocked
//! cell's interior, may run along the boundary of blocked cells and turn at their corners, and
//! never passes between two blocked cells that touch only at a corner. Cells off the grid count
//! as blocked. [`segment_is_free_any_angle`] decides one segment exactly (integer arithmetic).
//!
//! Under this rule a shortest path turns only at *convex corners*: grid vertices with exactly one
//! blocked cell among their four. [`AnyAngle::new`] builds the reduced visibility graph over them
//! once per grid (an edge only where the segment is free and tangent to the blocked cell at both
//! ends); [`AnyAngle::plan`] runs A\* with the Euclidean heuristic on it. The start's edges are
//! tested lazily, in order of `|start, corner| + |corner, goal|`, and a corner's edge to the goal
//! only when the corner is expanded, so a query tests few segments.
//!
//! Cost: the graph build tests `O(corners²)` candidate segments (the city at 1 m: 909 corners,
//! 6,963 edges, 0.1–0.3 s, 0.2 MB); a query then takes a fraction of a millisecond there. The
//! path touches obstacles (the safety margin must already be in the grid); re-check it with
//! [`segment_is_free_any_angle`], not with the grid planners' closed line-of-sight rule, under
//! which a path touching a corner is refused.
//!
//! Points are fractional cell coordinates ([`GridPoint`]: `row` north, `col` east; cell
//! `(r, c)` covers `[r, r + 1) × [c, c + 1)`, its centre is `(r + 0.5, c + 0.5)`), held exactly
//! as multiples of 1/4096 cell (other inputs are rounded to the nearest such point). Any point of
//! the closed grid rectangle that touches a free cell may be a start or goal: cell centres of free
//! cells, corners, edges. [`GridPoint::from_ne`] converts local north/east metres.
//!
//! ```
//! use skyplan_anyangle::{AnyAngle, GridPoint};
//! use skyplan_cspace::{Cell, Grid2};
//! // Row 0 is the first line (the southern edge).
//! let grid = Grid2::from_ascii("....\n.##.\n....")?;
//! let planner = AnyAngle::new(&grid);
//! let path = planner.plan(GridPoint::center(Cell::new(0, 0)), GridPoint::center(Cell::new(2, 3)))?;
//! // The block covers rows 1..2, columns 1..3. One turn, at its corner (1, 3) or, equally
//! // short, at (2, 1): √(0.5² + 2.5²) + √(1.5² + 0.5²) cells.
//! let want = 0.5f64.hypot(2.5) + 1.5f64.hypot(0.5);
//! assert!((path.length_cells - want).abs() < 1e-12);
//! assert_eq!(path.points.len(), 3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod segment;

use segment::{Fixed, GridView, Occupancy, Padded, SCALE};
use skyplan_cspace::{Cell, Grid2, GridFrame};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A point in fractional cell coordinates: `row` counts north, `col` east, from the grid's
/// south-west corner. Cell `(r, c)` covers `[r, r + 1) × [c, c + 1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridPoint {
    /// Rows north of the grid's southern edge.
    pub row: f64,
    /// Columns east of the grid's western edge.
    pub col: f64,
}

impl GridPoint {
    /// The centre of a cell.
    ///
    /// ```
    /// use skyplan_anyangle::GridPoint;
    /// use skyplan_cspace::Cell;
    /// assert_eq!(GridPoint::center(Cell::new(2, 3)), GridPoint { row: 2.5, col: 3.5 });
    /// ```
    pub fn center(cell: Cell) -> Self {
        Self {
            row: f64::from(cell.row) + 0.5,
            col: f64::from(cell.col) + 0.5,
        }
    }

    /// The point at local north/east metres in a grid frame.
    ///
    /// ```
    /// use skyplan_anyangle::GridPoint;
    /// use skyplan_cspace::GridFrame;
    /// let frame = GridFrame { origin_north_m: -10.0, origin_east_m: 4.0, cell_m: 2.0 };
    /// assert_eq!(GridPoint::from_ne(frame, -5.0, 5.0), GridPoint { row: 2.5, col: 0.5 });
    /// ```
    pub fn from_ne(frame: GridFrame, north_m: f64, east_m: f64) -> Self {
        Self {
            row: (north_m - frame.origin_north_m) / frame.cell_m,
            col: (east_m - frame.origin_east_m) / frame.cell_m,
        }
    }

    /// Local (north, east) metres of the point in a grid frame.
    ///
    /// ```
    /// use skyplan_anyangle::GridPoint;
    /// use skyplan_cspace::GridFrame;
    /// let frame = GridFrame { origin_north_m: -10.0, origin_east_m: 4.0, cell_m: 2.0 };
    /// assert_eq!(GridPoint { row: 2.5, col: 0.5 }.to_ne(frame), (-5.0, 5.0));
    /// ```
    pub fn to_ne(self, frame: GridFrame) -> (f64, f64) {
        (
            frame.origin_north_m + self.row * frame.cell_m,
            frame.origin_east_m + self.col * frame.cell_m,
        )
    }

    /// The exact fixed-point point (nearest multiple of 1/4096 cell), if finite and not huge.
    fn fixed(self) -> Option<Fixed> {
        let q = |x: f64| {
            let v = (x * SCALE as f64).round();
            (v.is_finite() && v.abs() < 1e15).then_some(v as i64)
        };
        Some(Fixed {
            r: q(self.row)?,
            c: q(self.col)?,
        })
    }
}

/// Which end of a query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// The start point.
    Start,
    /// The goal point.
    Goal,
}

impl std::fmt::Display for End {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            End::Start => "start",
            End::Goal => "goal",
        })
    }
}

/// Why [`AnyAngle::plan`] returned no path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnyAngleError {
    /// The point is not finite or lies outside the closed grid rectangle.
    #[error("{end} (row {row}, col {col}) is outside the {rows} × {cols} grid")]
    OffGrid {
        /// Which end.
        end: End,
        /// Fractional row given.
        row: f64,
        /// Fractional column given.
        col: f64,
        /// Grid rows.
        rows: u32,
        /// Grid columns.
        cols: u32,
    },
    /// The point touches no free cell (it is inside or enclosed by blocked cells).
    #[error("{end} (row {row}, col {col}) is blocked")]
    Blocked {
        /// Which end.
        end: End,
        /// Fractional row given.
        row: f64,
        /// Fractional column given.
        col: f64,
    },
    /// The search exhausted every reachable corner without meeting the goal.
    #[error(
        "goal is unreachable from start: the search expanded all {expansions} reachable corners"
    )]
    NoPath {
        /// Corners expanded before giving up.
        expansions: u64,
    },
    /// The final re-check of the route with [`segment_is_free_any_angle`] failed (a bug).
    #[error("internal error: segment {index} of the route failed the final re-check")]
    Recheck {
        /// Index of the failing segment.
        index: usize,
    },
}

/// A Euclidean-shortest path.
#[derive(Debug, Clone, PartialEq)]
pub struct AnyAnglePath {
    /// Waypoints in fractional cell coordinates: start, convex corners, goal (start and goal
    /// rounded to 1/4096 cell); always at least two points.
    pub points: Vec<GridPoint>,
    /// The same waypoints in local (north, east) metres of the grid's frame.
    pub points_ne: Vec<(f64, f64)>,
    /// Euclidean length in cells.
    pub length_cells: f64,
    /// Euclidean length in metres (`length_cells × cell_m`).
    pub length_m: f64,
    /// Number of search nodes (start and corners) expanded.
    pub expansions: u64,
    /// Number of segments tested during the search (start, goal and direct edges).
    pub segment_tests: u64,
}

/// True if the straight segment between two points obeys the any-angle rule on `grid`: it meets no
/// blocked cell's interior, runs along a grid edge only where a free cell lies on one side, and
/// passes through no vertex whose two diagonally opposite cells are both blocked. Both points must
/// lie on the closed grid rectangle (else `false`); a zero-length segment is free if its point
/// touches a free cell. Exact: the points are rounded to 1/4096 cell, then integer arithmetic.
///
/// ```
/// use skyplan_anyangle::{segment_is_free_any_angle, GridPoint};
/// use skyplan_cspace::Grid2;
/// let grid = Grid2::from_ascii(".#\n#.")?; // two blocked cells touching at the vertex (1, 1)
/// let p = |row, col| GridPoint { row, col };
/// assert!(!segment_is_free_any_angle(&grid, p(0.5, 0.5), p(1.5, 1.5))); // between them
/// assert!(segment_is_free_any_angle(&grid, p(0.0, 0.0), p(1.0, 1.0))); // to the vertex
/// assert!(segment_is_free_any_angle(&grid, p(0.0, 1.0), p(0.5, 1.0))); // along an edge
/// assert!(!segment_is_free_any_angle(&grid, p(0.5, 0.5), p(0.5, 1.5))); // into a blocked cell
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn segment_is_free_any_angle(grid: &Grid2, a: GridPoint, b: GridPoint) -> bool {
    let view = GridView(grid);
    match (a.fixed(), b.fixed()) {
        (Some(fa), Some(fb)) => view.on_grid(fa) && view.on_grid(fb) && view.segment_free(fa, fb),
        _ => false,
    }
}

/// A convex corner: a grid vertex with exactly one blocked cell, in quadrant (`sr`, `sc`).
#[derive(Debug, Clone, Copy)]
struct Corner {
    at: Fixed,
    sr: i64,
    sc: i64,
}

impl Corner {
    /// True if a straight path through this corner along direction `d` (arriving) may be part of
    /// a taut path turning here: the line does not cut into the blocked cell.
    #[inline]
    fn tangent(self, dr: i64, dc: i64) -> bool {
        !(dr * self.sr > 0 && dc * self.sc > 0)
    }
}

/// The exact any-angle planner for one grid: the reduced visibility graph of its convex corners.
///
/// Build once per grid ([`AnyAngle::new`], `O(corners²)` segment tests), then answer any number of
/// queries with [`AnyAngle::plan`] (`&self`: one planner may serve several threads).
#[derive(Debug, Clone)]
pub struct AnyAngle {
    padded: Padded,
    frame: GridFrame,
    rows: u32,
    cols: u32,
    corners: Vec<Corner>,
    /// CSR adjacency: the edges of corner `i` are `first[i]..first[i + 1]`.
    first: Vec<u32>,
    target: Vec<u32>,
    length_cells: Vec<f64>,
}

impl AnyAngle {
    /// Finds the convex corners of `grid` and the free, doubly tangent segments between them.
    ///
    /// ```
    /// use skyplan_anyangle::AnyAngle;
    /// use skyplan_cspace::Grid2;
    /// let planner = AnyAngle::new(&Grid2::from_ascii("...\n.#.\n...")?);
    /// assert_eq!(planner.corner_count(), 4); // the four corners of the blocked cell
    /// assert_eq!(planner.edge_count(), 4); // its four sides
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn new(grid: &Grid2) -> Self {
        let padded = Padded::new(grid);
        let (rows, cols) = (padded.rows, padded.cols);
        let mut corners = Vec::new();
        for r in 1..rows {
            for c in 1..cols {
                let cells = [
                    (padded.blocked(r - 1, c - 1), -1, -1),
                    (padded.blocked(r - 1, c), -1, 1),
                    (padded.blocked(r, c - 1), 1, -1),
                    (padded.blocked(r, c), 1, 1),
                ];
                let mut blocked = cells.iter().filter(|x| x.0);
                if let (Some(&(_, sr, sc)), None) = (blocked.next(), blocked.next()) {
                    corners.push(Corner {
                        at: Fixed::vertex(r, c),
                        sr,
                        sc,
                    });
                }
            }
        }
        let mut adjacency: Vec<Vec<(u32, f64)>> = vec![Vec::new(); corners.len()];
        for i in 0..corners.len() {
            let u = corners[i];
            for (j, &v) in corners.iter().enumerate().skip(i + 1) {
                let (dr, dc) = (v.at.r - u.at.r, v.at.c - u.at.c);
                if v.tangent(dr, dc) && u.tangent(-dr, -dc) && padded.segment_free(u.at, v.at) {
                    let len = u.at.dist_cells(v.at);
                    adjacency[i].push((j as u32, len));
                    adjacency[j].push((i as u32, len));
                }
            }
        }
        let mut first = Vec::with_capacity(corners.len() + 1);
        let mut target = Vec::new();
        let mut length_cells = Vec::new();
        first.push(0);
        for list in adjacency {
            for (t, len) in list {
                target.push(t);
                length_cells.push(len);
            }
            first.push(target.len() as u32);
        }
        Self {
            padded,
            frame: grid.frame(),
            rows: grid.rows(),
            cols: grid.cols(),
            corners,
            first,
            target,
            length_cells,
        }
    }

    /// Number of convex corners (graph nodes).
    pub fn corner_count(&self) -> usize {
        self.corners.len()
    }

    /// Number of undirected edges between corners.
    pub fn edge_count(&self) -> usize {
        self.target.len() / 2
    }

    /// Heap memory of the graph, in bytes.
    pub fn graph_bytes(&self) -> usize {
        self.corners.len() * std::mem::size_of::<Corner>()
            + self.first.len() * 4
            + self.target.len() * (4 + 8)
    }

    fn check_end(&self, end: End, p: GridPoint) -> Result<Fixed, AnyAngleError> {
        let fixed = p.fixed().filter(|&f| self.padded.on_grid(f));
        let Some(fixed) = fixed else {
            return Err(AnyAngleError::OffGrid {
                end,
                row: p.row,
                col: p.col,
                rows: self.rows,
                cols: self.cols,
            });
        };
        if !self.padded.point_free(fixed) {
            return Err(AnyAngleError::Blocked {
                end,
                row: p.row,
                col: p.col,
            });
        }
        Ok(fixed)
    }

    /// The Euclidean-shortest path from `start` to `goal` under the any-angle rule (crate docs).
    ///
    /// Errors: an end off the grid or touching no free cell; no path.
    ///
    /// ```
    /// use skyplan_anyangle::{AnyAngle, AnyAngleError, GridPoint};
    /// use skyplan_cspace::Grid2;
    /// let grid = Grid2::from_ascii("..#..\n..#..")?;
    /// let planner = AnyAngle::new(&grid);
    /// let err = planner.plan(GridPoint { row: 0.5, col: 0.5 }, GridPoint { row: 1.5, col: 4.5 });
    /// assert_eq!(err, Err(AnyAngleError::NoPath { expansions: 1 }));
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn plan(&self, start: GridPoint, goal: GridPoint) -> Result<AnyAnglePath, AnyAngleError> {
        let s = self.check_end(End::Start, start)?;
        let g = self.check_end(End::Goal, goal)?;
        let mut tests = 1u64;
        if self.padded.segment_free(s, g) {
            return self.finish(vec![s, g], 1, tests);
        }
        let n = self.corners.len();
        let (start_node, goal_node) = (n as u32, n as u32 + 1);
        let mut cost = vec![f64::INFINITY; n + 2];
        let mut parent = vec![u32::MAX; n + 2];
        let mut closed = vec![false; n + 2];
        let h = |i: usize| self.corners[i].at.dist_cells(g);
        // The start's edges, tested lazily in order of the f they would give.
        let mut pending: Vec<(f64, u32)> = self
            .corners
            .iter()
            .enumerate()
            .filter(|(_, k)| k.tangent(k.at.r - s.r, k.at.c - s.c))
            .map(|(i, k)| (s.dist_cells(k.at) + h(i), i as u32))
            .collect();
        pending.sort_unstable_by(|a, b| b.0.total_cmp(&a.0)); // popped from the back
        cost[start_node as usize] = 0.0;
        closed[start_node as usize] = true;
        let mut heap: BinaryHeap<Reverse<(u64, u32)>> = BinaryHeap::new();
        let mut expansions = 1u64;
        loop {
            let heap_f = heap.peek().map(|Reverse((f, _))| f64::from_bits(*f));
            if let Some(&(f, i)) = pending.last()
                && heap_f.is_none_or(|hf| f <= hf)
            {
                pending.pop();
                let k = self.corners[i as usize].at;
                let gs = s.dist_cells(k);
                if !closed[i as usize] && gs < cost[i as usize] {
                    tests += 1;
                    if self.padded.segment_free(s, k) {
                        cost[i as usize] = gs;
                        parent[i as usize] = start_node;
                        heap.push(Reverse((f.to_bits(), i)));
                    }
                }
                continue;
            }
            let Some(Reverse((_, u))) = heap.pop() else {
                return Err(AnyAngleError::NoPath { expansions });
            };
            let ui = u as usize;
            if closed[ui] {
                continue;
            }
            closed[ui] = true;
            if u == goal_node {
                let mut points = vec![g];
                let mut at = parent[ui];
                while at != start_node {
                    points.push(self.corners[at as usize].at);
                    at = parent[at as usize];
                }
                points.push(s);
                points.reverse();
                return self.finish(points, expansions, tests);
            }
            expansions += 1;
            let gu = cost[ui];
            let cu = self.corners[ui];
            // The edge to the goal, tested when the corner is expanded.
            if cu.tangent(cu.at.r - g.r, cu.at.c - g.c) {
                let gg = gu + cu.at.dist_cells(g);
                if gg < cost[goal_node as usize] {
                    tests += 1;
                    if self.padded.segment_free(cu.at, g) {
                        cost[goal_node as usize] = gg;
                        parent[goal_node as usize] = u;
                        heap.push(Reverse((gg.to_bits(), goal_node)));
                    }
                }
            }
            let (lo, hi) = (self.first[ui] as usize, self.first[ui + 1] as usize);
            for e in lo..hi {
                let v = self.target[e] as usize;
                if closed[v] {
                    continue;
                }
                let gv = gu + self.length_cells[e];
                if gv < cost[v] {
                    cost[v] = gv;
                    parent[v] = u;
                    heap.push(Reverse(((gv + h(v)).to_bits(), v as u32)));
                }
            }
        }
    }

    /// [`AnyAngle::plan`] between local north/east metres of the grid's frame.
    ///
    /// ```
    /// use skyplan_anyangle::AnyAngle;
    /// use skyplan_cspace::{Grid2, GridFrame};
    /// let frame = GridFrame { origin_north_m: -2.0, origin_east_m: -2.0, cell_m: 2.0 };
    /// // Row 0: free, blocked; row 1: blocked, free. The diagonal between the two free cells
    /// // passes between two blocked cells that touch at a corner: no path.
    /// let pinched = Grid2::new(2, 2, vec![false, true, true, false], frame)?;
    /// assert!(AnyAngle::new(&pinched).plan_ne((-1.0, -1.0), (1.0, 1.0)).is_err());
    /// // With one of them free the diagonal only touches the other's corner: allowed.
    /// let grid = Grid2::new(2, 2, vec![false, true, false, false], frame)?;
    /// let path = AnyAngle::new(&grid).plan_ne((-1.0, -1.0), (1.0, 1.0))?;
    /// assert_eq!(path.points_ne, vec![(-1.0, -1.0), (1.0, 1.0)]);
    /// assert!((path.length_m - 8f64.sqrt()).abs() < 1e-12);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn plan_ne(
        &self,
        start_ne: (f64, f64),
        goal_ne: (f64, f64),
    ) -> Result<AnyAnglePath, AnyAngleError> {
        self.plan(
            GridPoint::from_ne(self.frame, start_ne.0, start_ne.1),
            GridPoint::from_ne(self.frame, goal_ne.0, goal_ne.1),
        )
    }

    /// Re-checks every segment and builds the result.
    fn finish(
        &self,
        points: Vec<Fixed>,
        expansions: u64,
        segment_tests: u64,
    ) -> Result<AnyAnglePath, AnyAngleError> {
        if let Some(index) = points
            .windows(2)
            .position(|w| !self.padded.segment_free(w[0], w[1]))
        {
            return Err(AnyAngleError::Recheck { index });
        }
        let length_cells: f64 = points.windows(2).map(|w| w[0].dist_cells(w[1])).sum();
        let points: Vec<GridPoint> = points.into_iter().map(Fixed::to_point).collect();
        Ok(AnyAnglePath {
            points_ne: points.iter().map(|p| p.to_ne(self.frame)).collect(),
            points,
            length_cells,
            length_m: length_cells * self.frame.cell_m,
            expansions,
            segment_tests,
        })
    }
}

/// One query without keeping the planner: builds [`AnyAngle`] for `grid` and plans. For several
/// queries on one grid, build the planner once.
///
/// ```
/// use skyplan_anyangle::{shortest_path, GridPoint};
/// use skyplan_cspace::Grid2;
/// let grid = Grid2::from_ascii("...\n...")?;
/// let path = shortest_path(&grid, GridPoint { row: 0.5, col: 0.5 }, GridPoint { row: 1.5, col: 2.5 })?;
/// assert_eq!(path.points.len(), 2);
/// assert!((path.length_cells - 5f64.sqrt()).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn shortest_path(
    grid: &Grid2,
    start: GridPoint,
    goal: GridPoint,
) -> Result<AnyAnglePath, AnyAngleError> {
    AnyAngle::new(grid).plan(start, goal)
}
