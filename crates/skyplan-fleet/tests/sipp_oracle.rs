//! The safe-interval search against an independent oracle: a time-expanded reachability sweep
//! on a lattice of milliseconds (every cell at every millisecond), on random small grids with
//! random blocked times. With 4-connected moves of one second and blocked intervals whose ends
//! are whole seconds, every optimal departure and wait of the continuous problem lies on that
//! lattice, so the earliest arrivals must be equal.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_fleet::sipp::{Interval, SippError, SippPath, SippQuery, sipp};

/// Blocked `[a, b]` (ms) per cell.
type Blocked = Vec<Vec<(i64, i64)>>;

const MS: i64 = 1000;

/// Earliest arrival (ms) by sweeping time: `at[c]` = the flight can be in `c` at time `t`.
/// A wait or move over `[t, t + d]` needs the cells it occupies free over all of it.
fn oracle(
    grid: &Grid2,
    blocked: &Blocked,
    start: usize,
    goal: usize,
    latest_ms: i64,
    horizon_ms: i64,
) -> Option<i64> {
    let n = grid.len();
    let free_over = |c: usize, t0: i64, t1: i64| blocked[c].iter().all(|&(a, b)| t1 < a || t0 > b);
    let cols = grid.cols() as usize;
    // reach[t % (MS + 1)][c]: a ring of the last MS + 1 instants.
    let ring = (MS + 1) as usize;
    let mut reach = vec![vec![false; n]; ring];
    for t in 0..=horizon_ms {
        let slot = (t as usize) % ring;
        let mut now = vec![false; n];
        if t <= latest_ms && free_over(start, t, t) {
            now[start] = true;
        }
        // Waited one millisecond.
        if t >= 1 {
            let prev = &reach[((t - 1) as usize) % ring];
            for (c, _) in prev.iter().enumerate().filter(|(_, r)| **r) {
                if free_over(c, t - 1, t) {
                    now[c] = true;
                }
            }
        }
        // Arrived by a move that left one second ago.
        if t >= MS {
            let from = &reach[((t - MS) as usize) % ring];
            for (c, _) in from.iter().enumerate().filter(|(_, r)| **r) {
                let (r, k) = ((c / cols) as i64, (c % cols) as i64);
                for (dr, dk) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                    if !grid.is_free_at(r + dr, k + dk) {
                        continue;
                    }
                    let m = ((r + dr) as usize) * cols + (k + dk) as usize;
                    if free_over(c, t - MS, t) && free_over(m, t - MS, t) {
                        now[m] = true;
                    }
                }
            }
        }
        if now[goal] {
            return Some(t);
        }
        reach[slot] = now;
    }
    None
}

/// The route moves between 4-neighbours in one second each and keeps out of every blocked
/// time, moving and waiting.
fn keeps_out(grid: &Grid2, blocked: &Blocked, path: &SippPath, case: usize) {
    let blocked_s = |c: Cell| {
        blocked[grid.index(c)]
            .iter()
            .map(|&(x, y)| (x as f64 / 1000.0, y as f64 / 1000.0))
    };
    for w in path.cells.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (t0, t1) = (a.leave_s, b.arrive_s);
        assert!(
            (t1 - t0 - 1.0).abs() < 1e-9,
            "case {case}: a move takes 1 s"
        );
        assert_eq!(
            a.cell.row.abs_diff(b.cell.row) + a.cell.col.abs_diff(b.cell.col),
            1,
            "case {case}: a move to a neighbour"
        );
        assert!(!grid.is_blocked(b.cell), "case {case}: into a building");
        for c in [a.cell, b.cell] {
            for (x, y) in blocked_s(c) {
                assert!(
                    t1 < x || t0 > y,
                    "case {case}: moves through a blocked time"
                );
            }
        }
        for (x, y) in blocked_s(a.cell) {
            assert!(
                a.leave_s < x || a.arrive_s > y,
                "case {case}: waits in a blocked time"
            );
        }
    }
}

/// A random grid of up to `max_side` cells a side, start at its first cell and goal at its
/// last, with up to two blocked times per cell of whole seconds under 12 s.
fn random_case(rng: &mut ChaCha8Rng, max_side: u32) -> (Grid2, Blocked) {
    let (rows, cols) = (rng.random_range(2..max_side), rng.random_range(2..max_side));
    let mut cells: Vec<bool> = (0..rows * cols).map(|_| rng.random_bool(0.15)).collect();
    cells[0] = false;
    cells[(rows * cols - 1) as usize] = false;
    let grid = Grid2::new(rows, cols, cells, GridFrame::default()).expect("grid");
    let blocked: Blocked = (0..grid.len())
        .map(|_| {
            (0..rng.random_range(0..3))
                .map(|_| {
                    let a = rng.random_range(0..12i64);
                    (a * MS, (a + rng.random_range(0..4i64)) * MS)
                })
                .collect()
        })
        .collect();
    (grid, blocked)
}

/// The blocked times of `blocked` as the search's timeline.
fn timeline_of<'a>(
    grid: &'a Grid2,
    blocked: &'a Blocked,
) -> impl FnMut(Cell) -> Vec<Interval> + 'a {
    |c: Cell| {
        blocked[grid.index(c)]
            .iter()
            .map(|&(a, b)| Interval {
                start_s: a as f64 / 1000.0,
                end_s: b as f64 / 1000.0,
            })
            .collect()
    }
}

/// A query on a random grid ([`random_case`]) from its first cell to its last, with moves of
/// one second, a latest departure of 0 to 3 s and a horizon of 30 s.
fn random_query(
    rng: &mut ChaCha8Rng,
    max_side: u32,
    exact_until: Option<std::time::Instant>,
) -> (Grid2, Blocked, SippQuery) {
    let (grid, blocked) = random_case(rng, max_side);
    let q = SippQuery {
        start: grid.cell(0),
        goal: grid.cell(grid.len() - 1),
        cell_s: 1.0,
        latest_departure_s: rng.random_range(0..4i64) as f64,
        horizon_s: 30.0,
        diagonals: false,
        max_expansions: 1_000_000,
        deadline: None,
        exact_until,
    };
    (grid, blocked, q)
}

/// The sweep's earliest arrival for `q` (ms).
fn sweep(grid: &Grid2, blocked: &Blocked, q: &SippQuery) -> Option<i64> {
    let ms = |s: f64| (s * 1000.0).round() as i64;
    oracle(
        grid,
        blocked,
        grid.index(q.start),
        grid.index(q.goal),
        ms(q.latest_departure_s),
        ms(q.horizon_s),
    )
}

#[test]
fn earliest_arrival_equals_a_time_expanded_sweep() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (mut compared, mut waited, mut unreachable) = (0, 0, 0);
    for case in 0..40 {
        let (grid, blocked, q) = random_query(&mut rng, 6, None);
        let latest_s = q.latest_departure_s;
        let mut timeline = timeline_of(&grid, &blocked);
        let found = sipp(&grid, &q, &mut timeline);
        let truth = sweep(&grid, &blocked, &q);
        match (found, truth) {
            (Ok(path), Some(t_ms)) => {
                let got = path.arrival_s();
                assert!(
                    (got - t_ms as f64 / 1000.0).abs() < 1e-6,
                    "case {case}: SIPP arrives at {got} s, the sweep at {t_ms} ms"
                );
                keeps_out(&grid, &blocked, &path, case);
                assert!(path.departure_s() <= latest_s + 1e-9);
                // The horizon is a hard bound, and a tight one: at the earliest arrival the
                // same route is found, half a second earlier none.
                let t_s = t_ms as f64 / 1000.0;
                let tight = sipp(
                    &grid,
                    &SippQuery {
                        horizon_s: t_s,
                        ..q
                    },
                    &mut timeline,
                );
                assert!(
                    tight
                        .as_ref()
                        .is_ok_and(|p| (p.arrival_s() - t_s).abs() < 1e-6),
                    "case {case}: horizon {t_s} s: {tight:?}"
                );
                let short = sipp(
                    &grid,
                    &SippQuery {
                        horizon_s: t_s - 0.5,
                        ..q
                    },
                    &mut timeline,
                );
                assert!(
                    matches!(short, Err(SippError::NoRoute { .. })),
                    "case {case}: horizon {} s: {short:?}",
                    t_s - 0.5
                );
                waited += usize::from(path.hover_s() > 0.0 || path.departure_s() > 0.0);
                compared += 1;
            }
            (Err(SippError::NoRoute { .. }), None) => unreachable += 1,
            (found, truth) => panic!("case {case}: SIPP {found:?}, the sweep {truth:?}"),
        }
    }
    eprintln!("compared {compared}, unreachable {unreachable}, waited {waited}");
    // The cases exercised both outcomes and the waits.
    assert!(
        compared >= 20 && unreachable >= 1 && waited >= 5,
        "{compared} {unreachable} {waited}"
    );
}

/// A search that stops proving the earliest arrival at once (its `exact_until` passed) and
/// heads for the goal: a route exactly when the sweep finds one, keeping out of every blocked
/// time, never before the sweep's earliest arrival, with a bound never above it; "proven" only
/// when it is the earliest.
#[test]
fn a_search_that_stops_proving_still_finds_a_safe_route_and_bounds_its_cost() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let (mut compared, mut later, mut unreachable) = (0, 0, 0);
    for case in 0..60 {
        let (grid, blocked, q) = random_query(&mut rng, 9, Some(std::time::Instant::now()));
        let (latest_s, horizon_s) = (q.latest_departure_s, q.horizon_s);
        let mut timeline = timeline_of(&grid, &blocked);
        let found = sipp(&grid, &q, &mut timeline);
        let truth = sweep(&grid, &blocked, &q);
        match (found, truth) {
            (Ok(path), Some(t_ms)) => {
                let earliest = t_ms as f64 / 1000.0;
                keeps_out(&grid, &blocked, &path, case);
                assert!(path.departure_s() <= latest_s + 1e-9);
                assert!(path.arrival_s() <= horizon_s + 1e-6);
                assert!(
                    path.arrival_s() >= earliest - 1e-6,
                    "case {case}: arrives at {} s, before the earliest {earliest} s",
                    path.arrival_s()
                );
                assert!(
                    path.earliest_bound_s <= earliest + 1e-6,
                    "case {case}: bound {} s above the earliest {earliest} s",
                    path.earliest_bound_s
                );
                if path.proven_earliest() {
                    assert!((path.arrival_s() - earliest).abs() < 1e-6, "case {case}");
                }
                later += usize::from(path.arrival_s() > earliest + 1e-6);
                compared += 1;
            }
            (Err(SippError::NoRoute { .. }), None) => unreachable += 1,
            (found, truth) => panic!("case {case}: SIPP {found:?}, the sweep {truth:?}"),
        }
    }
    eprintln!("compared {compared}, later than the earliest {later}, unreachable {unreachable}");
    // Both outcomes, and routes the weighted search found later than the earliest.
    assert!(
        compared >= 30 && unreachable >= 1 && later >= 3,
        "{compared} {later} {unreachable}"
    );
}
