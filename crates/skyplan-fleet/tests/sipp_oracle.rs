//! The safe-interval search against an independent oracle: a time-expanded reachability sweep
//! on a lattice of milliseconds (every cell at every millisecond), on random small grids with
//! random blocked times. With 4-connected moves of one second and blocked intervals whose ends
//! are whole seconds, every optimal departure and wait of the continuous problem lies on that
//! lattice, so the earliest arrivals must be equal.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_fleet::sipp::{Interval, SippError, SippQuery, sipp};

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

#[test]
fn earliest_arrival_equals_a_time_expanded_sweep() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (mut compared, mut waited, mut unreachable) = (0, 0, 0);
    for case in 0..40 {
        let (rows, cols) = (rng.random_range(2..6u32), rng.random_range(2..6u32));
        let mut cells: Vec<bool> = (0..rows * cols).map(|_| rng.random_bool(0.15)).collect();
        let start = 0usize;
        let goal = (rows * cols - 1) as usize;
        cells[start] = false;
        cells[goal] = false;
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
        let latest_s = rng.random_range(0..4i64);
        let horizon_s = 30;
        let q = SippQuery {
            start: grid.cell(start),
            goal: grid.cell(goal),
            cell_s: 1.0,
            latest_departure_s: latest_s as f64,
            horizon_s: horizon_s as f64,
            diagonals: false,
            max_expansions: 1_000_000,
            deadline: None,
        };
        let mut timeline = |c: Cell| {
            blocked[grid.index(c)]
                .iter()
                .map(|&(a, b)| Interval {
                    start_s: a as f64 / 1000.0,
                    end_s: b as f64 / 1000.0,
                })
                .collect()
        };
        let found = sipp(&grid, &q, &mut timeline);
        let truth = oracle(&grid, &blocked, start, goal, latest_s * MS, horizon_s * MS);
        match (found, truth) {
            (Ok(path), Some(t_ms)) => {
                let got = path.arrival_s();
                assert!(
                    (got - t_ms as f64 / 1000.0).abs() < 1e-6,
                    "case {case}: SIPP arrives at {got} s, the sweep at {t_ms} ms"
                );
                // The route itself keeps out of every blocked time.
                for w in path.cells.windows(2) {
                    let (a, b) = (w[0], w[1]);
                    let (t0, t1) = (a.leave_s, b.arrive_s);
                    assert!(
                        (t1 - t0 - 1.0).abs() < 1e-9,
                        "case {case}: a move takes 1 s"
                    );
                    for c in [a.cell, b.cell] {
                        for &(x, y) in &blocked[grid.index(c)] {
                            let (x, y) = (x as f64 / 1000.0, y as f64 / 1000.0);
                            assert!(
                                t1 < x || t0 > y,
                                "case {case}: moves through a blocked time"
                            );
                        }
                    }
                    for &(x, y) in &blocked[grid.index(a.cell)] {
                        let (x, y) = (x as f64 / 1000.0, y as f64 / 1000.0);
                        assert!(
                            a.leave_s < x || a.arrive_s > y,
                            "case {case}: waits in a blocked time"
                        );
                    }
                }
                assert!(path.departure_s() <= latest_s as f64 + 1e-9);
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
