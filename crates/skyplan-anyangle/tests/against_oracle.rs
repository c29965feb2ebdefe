//! The any-angle planner against an independent oracle on random grids.
//!
//! The oracle is written here from the rule alone: Dijkstra over the visibility graph of the start,
//! the goal and every corner of every blocked cell, each edge decided by a brute-force test of the
//! rule against every cell, edge and vertex near the segment (a separating-axis test per cell,
//! exact integers). It shares no code with the planner.

use proptest::prelude::*;
use proptest::sample::Index;
use skyplan_anyangle::{AnyAngle, AnyAngleError, GridPoint, segment_is_free_any_angle};
use skyplan_cspace::{Cell, Grid2, GridFrame, Touch};
use skyplan_search::{GridSearch, MoveModel, Planner, SearchError};
use std::ops::RangeInclusive;

/// Brute-force rule in integer coordinates with `s` units per cell; cells off the grid blocked.
struct Brute<'a> {
    grid: &'a Grid2,
    s: i64,
}

impl Brute<'_> {
    fn blocked(&self, r: i64, c: i64) -> bool {
        !self.grid.is_free_at(r, c)
    }

    fn pinch(&self, r: i64, c: i64) -> bool {
        (self.blocked(r - 1, c - 1) && self.blocked(r, c))
            || (self.blocked(r - 1, c) && self.blocked(r, c - 1))
    }

    /// Does the closed segment p–q meet the open square of cell (r, c)? Separating axes: the two
    /// grid axes and the segment's normal.
    fn meets_open_cell(&self, p: (i64, i64), q: (i64, i64), r: i64, c: i64) -> bool {
        let s = self.s;
        let (y0, y1, x0, x1) = (r * s, (r + 1) * s, c * s, (c + 1) * s);
        if p.0.max(q.0) <= y0 || p.0.min(q.0) >= y1 || p.1.max(q.1) <= x0 || p.1.min(q.1) >= x1 {
            return false;
        }
        let side = |(y, x): (i64, i64)| (q.0 - p.0) * (x - p.1) - (q.1 - p.1) * (y - p.0);
        let sides = [
            side((y0, x0)),
            side((y0, x1)),
            side((y1, x0)),
            side((y1, x1)),
        ];
        !(sides.iter().all(|&v| v >= 0) || sides.iter().all(|&v| v <= 0))
    }

    /// For a segment along a grid line from `a` to `b` (coordinates along the line): does it
    /// cover, with positive length, a unit edge `i` in `edges` that is `walled` (blocked on both
    /// sides)?
    fn walled_edge_covered(
        &self,
        (a, b): (i64, i64),
        edges: RangeInclusive<i64>,
        walled: impl Fn(i64) -> bool,
    ) -> bool {
        let s = self.s;
        let (lo, hi) = (a.min(b), a.max(b));
        edges
            .into_iter()
            .any(|i| lo.max(i * s) < hi.min((i + 1) * s) && walled(i))
    }

    fn segment_free(&self, p: (i64, i64), q: (i64, i64)) -> bool {
        let s = self.s;
        let (rows, cols) = (i64::from(self.grid.rows()), i64::from(self.grid.cols()));
        if p == q {
            // The point must touch a free cell.
            return (-1..=rows).any(|r| {
                (-1..=cols).any(|c| {
                    !self.blocked(r, c)
                        && (r * s..=(r + 1) * s).contains(&p.0)
                        && (c * s..=(c + 1) * s).contains(&p.1)
                })
            });
        }
        // Only cells and vertices near the segment's bounding box can matter.
        let (r_lo, r_hi) = (
            (p.0.min(q.0) / s - 1).max(-1),
            (p.0.max(q.0) / s + 1).min(rows),
        );
        let (c_lo, c_hi) = (
            (p.1.min(q.1) / s - 1).max(-1),
            (p.1.max(q.1) / s + 1).min(cols),
        );
        for r in r_lo..=r_hi {
            for c in c_lo..=c_hi {
                if self.blocked(r, c) && self.meets_open_cell(p, q, r, c) {
                    return false;
                }
            }
        }
        // Along a grid line: every unit edge covered with positive length needs a free side.
        if p.0 == q.0 && p.0 % s == 0 {
            let k = p.0 / s;
            let walled = |c| self.blocked(k - 1, c) && self.blocked(k, c);
            if self.walled_edge_covered((p.1, q.1), c_lo..=c_hi, walled) {
                return false;
            }
        }
        if p.1 == q.1 && p.1 % s == 0 {
            let k = p.1 / s;
            let walled = |r| self.blocked(r, k - 1) && self.blocked(r, k);
            if self.walled_edge_covered((p.0, q.0), r_lo..=r_hi, walled) {
                return false;
            }
        }
        // Vertices strictly inside the segment.
        for r in r_lo.max(0)..=r_hi {
            for c in c_lo.max(0)..=c_hi {
                let v = (r * s, c * s);
                let cross = (q.0 - p.0) * (v.1 - p.1) - (q.1 - p.1) * (v.0 - p.0);
                let dot_p = (v.0 - p.0) * (q.0 - p.0) + (v.1 - p.1) * (q.1 - p.1);
                let dot_q = (v.0 - q.0) * (p.0 - q.0) + (v.1 - q.1) * (p.1 - q.1);
                if cross == 0 && dot_p > 0 && dot_q > 0 && self.pinch(r, c) {
                    return false;
                }
            }
        }
        true
    }
}

fn dist(p: (i64, i64), q: (i64, i64), s: i64) -> f64 {
    ((p.0 - q.0) as f64).hypot((p.1 - q.1) as f64) / s as f64
}

/// Dijkstra over start, goal and every corner of a blocked cell (except pinch vertices, where a
/// path can neither pass nor usefully turn: leaving into the other free quadrant passes between
/// the blocked cells, leaving into the same one is never shorter). Doubled coordinates.
fn oracle(grid: &Grid2, start: Cell, goal: Cell) -> Option<f64> {
    let centre = |c: Cell| (2 * i64::from(c.row) + 1, 2 * i64::from(c.col) + 1);
    oracle_doubled(grid, centre(start), centre(goal))
}

/// [`oracle`] between any points of the half-cell lattice, in doubled coordinates.
fn oracle_doubled(grid: &Grid2, start: (i64, i64), goal: (i64, i64)) -> Option<f64> {
    let brute = Brute { grid, s: 2 };
    let mut nodes = vec![start, goal];
    for r in 0..=i64::from(grid.rows()) {
        for c in 0..=i64::from(grid.cols()) {
            let around = [(r - 1, c - 1), (r - 1, c), (r, c - 1), (r, c)];
            let touches_blocked_cell = around.iter().any(|&(y, x)| {
                grid.checked_cell(y, x)
                    .is_some_and(|cell| grid.is_blocked(cell))
            });
            let touches_free_cell = around.iter().any(|&(y, x)| grid.is_free_at(y, x));
            if touches_blocked_cell && touches_free_cell && !brute.pinch(r, c) {
                nodes.push((2 * r, 2 * c));
            }
        }
    }
    let n = nodes.len();
    let mut d = vec![f64::INFINITY; n];
    let mut done = vec![false; n];
    d[0] = 0.0;
    loop {
        let u = (0..n)
            .filter(|&i| !done[i] && d[i].is_finite())
            .min_by(|&a, &b| d[a].total_cmp(&d[b]))?;
        if u == 1 {
            return Some(d[1]);
        }
        done[u] = true;
        for w in 0..n {
            if done[w] {
                continue;
            }
            let nd = d[u] + dist(nodes[u], nodes[w], 2);
            if nd < d[w] && brute.segment_free(nodes[u], nodes[w]) {
                d[w] = nd;
            }
        }
    }
}

fn random_grid() -> impl Strategy<Value = (Grid2, Index, Index)> {
    (1u32..=24, 1u32..=24, 0.0f64..0.5)
        .prop_flat_map(|(rows, cols, density)| {
            (
                Just(rows),
                Just(cols),
                proptest::collection::vec(
                    proptest::bool::weighted(density),
                    (rows * cols) as usize,
                ),
                any::<Index>(),
                any::<Index>(),
            )
        })
        .prop_map(|(rows, cols, cells, a, b)| {
            (
                Grid2::new(rows, cols, cells, GridFrame::default()).expect("valid size"),
                a,
                b,
            )
        })
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b.abs().max(1.0)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn shortest_any_angle_paths_match_the_visibility_graph_oracle((grid, a, b) in random_grid()) {
        let free: Vec<Cell> = (0..grid.len()).map(|i| grid.cell(i)).filter(|&c| !grid.is_blocked(c)).collect();
        if free.is_empty() {
            return Ok(());
        }
        let (start, goal) = (free[a.index(free.len())], free[b.index(free.len())]);
        let planner = AnyAngle::new(&grid);
        let got = planner.plan(GridPoint::center(start), GridPoint::center(goal));
        let want = oracle(&grid, start, goal);
        let mut search = GridSearch::new();
        let theta = search.search(&grid, start, goal, MoveModel::Octile, Planner::ThetaStar);
        let octile = search.search(&grid, start, goal, MoveModel::Octile, Planner::AStar);
        match (got, want) {
            (Ok(path), Some(len)) => {
                prop_assert!(close(path.length_cells, len), "planner {} oracle {}", path.length_cells, len);
                prop_assert_eq!(path.points.first(), Some(&GridPoint::center(start)));
                prop_assert_eq!(path.points.last(), Some(&GridPoint::center(goal)));
                let brute = Brute { grid: &grid, s: 4 };
                let fixed = |p: &GridPoint| ((p.row * 4.0) as i64, (p.col * 4.0) as i64);
                let mut sum = 0.0;
                for w in path.points.windows(2) {
                    prop_assert_eq!((w[0].row * 4.0).fract(), 0.0, "waypoint off the lattice");
                    prop_assert!(brute.segment_free(fixed(&w[0]), fixed(&w[1])), "segment {:?}", w);
                    prop_assert!(segment_is_free_any_angle(&grid, w[0], w[1]));
                    // The grid crate's own traversal with corner cutting allowed is a weaker rule.
                    prop_assert!(grid.segment_is_free_ne(w[0].to_ne(grid.frame()), w[1].to_ne(grid.frame()), Touch::Open));
                    sum += (w[0].row - w[1].row).hypot(w[0].col - w[1].col);
                }
                prop_assert!(close(sum, path.length_cells));
                let theta = theta.expect("Theta* finds a path where one exists").cost_cells();
                let octile = octile.expect("A* finds a path where one exists").cost_cells();
                prop_assert!(path.length_cells <= theta * (1.0 + 1e-12), "longer than Theta*: {} > {}", path.length_cells, theta);
                prop_assert!(path.length_cells <= octile * (1.0 + 1e-12));
            }
            (Err(AnyAngleError::NoPath { .. }), None) => {
                prop_assert!(matches!(theta, Err(SearchError::Unreachable { .. })), "Theta* {:?}", theta);
                prop_assert!(matches!(octile, Err(SearchError::Unreachable { .. })), "A* {:?}", octile);
            }
            (got, want) => prop_assert!(false, "planner {:?}, oracle {:?}", got, want),
        }
    }

    #[test]
    fn segment_rule_matches_brute_force(
        (grid, _, _) in random_grid(),
        p in (0i64..=100, 0i64..=100),
        q in (0i64..=100, 0i64..=100),
        through_vertex in any::<bool>(),
    ) {
        // Points on a quarter-cell lattice of the closed grid rectangle: centres, corners, edges.
        let (rows4, cols4) = (4 * i64::from(grid.rows()), 4 * i64::from(grid.cols()));
        let (p, mut q) = ((p.0 % (rows4 + 1), p.1 % (cols4 + 1)), (q.0 % (rows4 + 1), q.1 % (cols4 + 1)));
        if through_vertex {
            // Half the cases: q mirrors p through a grid vertex, so the segment passes through it.
            let v = (4 * (q.0 / 4), 4 * (q.1 / 4));
            q = ((2 * v.0 - p.0).clamp(0, rows4), (2 * v.1 - p.1).clamp(0, cols4));
        }
        let point = |(r, c): (i64, i64)| GridPoint { row: r as f64 / 4.0, col: c as f64 / 4.0 };
        let brute = Brute { grid: &grid, s: 4 };
        prop_assert_eq!(segment_is_free_any_angle(&grid, point(p), point(q)), brute.segment_free(p, q));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    /// Starts and goals anywhere on the half-cell lattice: centres, edge midpoints, corners
    /// (convex corners, pinch vertices, points touching only blocked cells).
    #[test]
    fn any_lattice_endpoints_match_the_oracle(
        (grid, _, _) in random_grid(),
        a in (0i64..=48, 0i64..=48),
        b in (0i64..=48, 0i64..=48),
    ) {
        let (rows2, cols2) = (2 * i64::from(grid.rows()), 2 * i64::from(grid.cols()));
        let (a, b) = ((a.0 % (rows2 + 1), a.1 % (cols2 + 1)), (b.0 % (rows2 + 1), b.1 % (cols2 + 1)));
        let point = |(r, c): (i64, i64)| GridPoint { row: r as f64 / 2.0, col: c as f64 / 2.0 };
        let brute = Brute { grid: &grid, s: 2 };
        let got = AnyAngle::new(&grid).plan(point(a), point(b));
        if !brute.segment_free(a, a) {
            prop_assert!(matches!(got, Err(AnyAngleError::Blocked { end: skyplan_anyangle::End::Start, .. })), "{:?}", got);
            return Ok(());
        }
        if !brute.segment_free(b, b) {
            prop_assert!(matches!(got, Err(AnyAngleError::Blocked { end: skyplan_anyangle::End::Goal, .. })), "{:?}", got);
            return Ok(());
        }
        match (got, oracle_doubled(&grid, a, b)) {
            (Ok(path), Some(len)) => {
                prop_assert!(close(path.length_cells, len), "planner {} oracle {}", path.length_cells, len);
                for w in path.points.windows(2) {
                    let fixed = |p: &GridPoint| ((p.row * 2.0) as i64, (p.col * 2.0) as i64);
                    prop_assert!(brute.segment_free(fixed(&w[0]), fixed(&w[1])), "segment {:?}", w);
                }
            }
            (Err(AnyAngleError::NoPath { .. }), None) => {}
            (got, want) => prop_assert!(false, "planner {:?}, oracle {:?}", got, want),
        }
    }
}

#[test]
fn segment_rule_cases() {
    // Row 0 is the first line.
    let grid = Grid2::from_ascii("....\n.#..\n..#.\n....").expect("grid");
    let p = |row, col| GridPoint { row, col };
    // Through the pinch vertex (2, 2) between (1, 1) and (2, 2): diagonal and along both lines.
    assert!(!segment_is_free_any_angle(&grid, p(1.5, 2.5), p(2.5, 1.5)));
    assert!(!segment_is_free_any_angle(&grid, p(2.0, 1.5), p(2.0, 2.5)));
    assert!(!segment_is_free_any_angle(&grid, p(1.5, 2.0), p(2.5, 2.0)));
    // Ending at it is allowed.
    assert!(segment_is_free_any_angle(&grid, p(2.5, 1.5), p(2.0, 2.0)));
    // Along the bottom of (1, 1), past its corner.
    assert!(segment_is_free_any_angle(&grid, p(1.0, 0.0), p(1.0, 4.0)));
    // Along an edge with blocked cells on both sides: none here; off the grid counts as blocked.
    assert!(segment_is_free_any_angle(&grid, p(0.0, 0.0), p(0.0, 4.0)));
    assert!(!segment_is_free_any_angle(&grid, p(0.0, 0.0), p(-0.5, 4.0)));
    assert!(!segment_is_free_any_angle(&grid, p(1.5, 1.5), p(1.5, 1.5)));
    let wall = Grid2::from_ascii("##\n..").expect("grid");
    assert!(!segment_is_free_any_angle(&wall, p(0.0, 0.0), p(0.0, 2.0)));
    assert!(segment_is_free_any_angle(&wall, p(1.0, 0.0), p(1.0, 2.0)));
}

#[test]
fn errors_name_the_end() {
    let grid = Grid2::from_ascii("..\n.#").expect("grid");
    let planner = AnyAngle::new(&grid);
    let free = GridPoint { row: 0.5, col: 0.5 };
    assert!(matches!(
        planner.plan(
            GridPoint {
                row: -0.5,
                col: 0.5
            },
            free
        ),
        Err(AnyAngleError::OffGrid {
            end: skyplan_anyangle::End::Start,
            ..
        })
    ));
    assert!(matches!(
        planner.plan(
            free,
            GridPoint {
                row: f64::NAN,
                col: 0.5
            }
        ),
        Err(AnyAngleError::OffGrid {
            end: skyplan_anyangle::End::Goal,
            ..
        })
    ));
    assert!(matches!(
        planner.plan(free, GridPoint { row: 1.5, col: 1.5 }),
        Err(AnyAngleError::Blocked {
            end: skyplan_anyangle::End::Goal,
            ..
        })
    ));
    // The blocked cell's far corner (2, 2) touches only it and the outside.
    assert!(matches!(
        planner.plan(GridPoint { row: 2.0, col: 2.0 }, free),
        Err(AnyAngleError::Blocked {
            end: skyplan_anyangle::End::Start,
            ..
        })
    ));
    // Its near corner touches free cells: a valid goal.
    let path = planner
        .plan(free, GridPoint { row: 1.0, col: 1.0 })
        .expect("path");
    assert!((path.length_cells - 0.5f64.sqrt()).abs() < 1e-12);
}
