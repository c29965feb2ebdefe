//! Times the planners on the city's 26 far-apart bench queries (seed 1) and prints per-planner
//! medians, A\*'s nanoseconds per expansion, and path lengths:
//! `cargo run --release -p skyplan-anyangle --example city_anyangle`.

use skyplan_bench::random_far_queries;
use skyplan_cspace::{Cell, Grid2, GridSpec};
use skyplan_search::{GridSearch, JpsPlus, MoveModel, Planner};
use std::time::Instant;

const CITY: &str = include_str!("../../../data/colliders.csv");

/// This thread's CPU time in nanoseconds (Linux `schedstat`), immune to other processes' load;
/// `None` elsewhere.
fn cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn main() {
    let map = skyplan_map::colliders::parse_colliders(CITY).expect("bundled map parses");
    // The bench's grid: 5 m altitude, 5 m margin, 1 m cells.
    let grid = Grid2::from_colliders(&map, GridSpec::default()).expect("city grid");
    let diagonal = f64::from(grid.rows()).hypot(f64::from(grid.cols()));
    let queries = random_far_queries(&grid, MoveModel::Octile, 26, 1, 0.5 * diagonal);
    println!(
        "grid {} x {}, {} queries",
        grid.rows(),
        grid.cols(),
        queries.len()
    );
    let model = MoveModel::Octile;
    let mut search = GridSearch::new();
    let reps: usize = std::env::var("REPS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(5);
    // `city_anyangle astar` (or jps, theta, anyangle, jps+): that planner only.
    let only = std::env::args().nth(1);
    for (name, planner) in [
        ("astar", Planner::AStar),
        ("jps", Planner::Jps),
        ("theta", Planner::ThetaStar),
    ] {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let _ = search.search(&grid, queries[0].0, queries[0].1, model, planner);
        let mut times = vec![];
        let (mut total_s, mut total_exp, mut cpu_total) = (0.0, 0u64, 0u64);
        let mut lengths = vec![];
        for &(s, g) in &queries {
            let mut best = f64::INFINITY;
            for _ in 0..reps {
                let t = Instant::now();
                let p = search.search(&grid, s, g, model, planner).expect("path");
                let dt = t.elapsed().as_secs_f64();
                best = best.min(dt);
                if lengths.len() < queries.len() && times.len() == lengths.len() {
                    lengths.push(p.cost_cells());
                    total_exp += p.expansions;
                }
            }
            total_s += best;
            times.push(best);
        }
        // CPU time of whole passes over the queries (the clock is too coarse for one query).
        for _ in 0..reps.min(3) {
            let c0 = cpu_ns();
            for &(s, g) in &queries {
                let _ = search.search(&grid, s, g, model, planner);
            }
            if let (Some(c0), Some(c1)) = (c0, cpu_ns()) {
                cpu_total = if cpu_total == 0 {
                    c1 - c0
                } else {
                    cpu_total.min(c1 - c0)
                };
            }
        }
        println!(
            "{name:8} median {:9.3} ms  total {:8.2} ms  {:7.1} ns/expansion (wall, best of {reps} per query), {:7.1} (CPU, best pass)  mean length {:.3}",
            median(times) * 1e3,
            total_s * 1e3,
            total_s * 1e9 / total_exp as f64,
            cpu_total as f64 / total_exp as f64,
            lengths.iter().sum::<f64>() / lengths.len() as f64
        );
    }
    let wanted = |name: &str| only.as_deref().is_none_or(|o| o == name);
    if wanted("anyangle") {
        anyangle(&grid, &queries, &mut search, reps);
    }
    if wanted("jps+") {
        jps_plus(&grid, &queries, reps);
    }
}

fn anyangle(grid: &Grid2, queries: &[(Cell, Cell)], search: &mut GridSearch, reps: usize) {
    let (grid, model) = (grid, MoveModel::Octile);
    let t = Instant::now();
    let planner = skyplan_anyangle::AnyAngle::new(grid);
    println!(
        "anyangle graph: {:.1} ms, {} corners, {} edges, {:.1} MB",
        t.elapsed().as_secs_f64() * 1e3,
        planner.corner_count(),
        planner.edge_count(),
        planner.graph_bytes() as f64 / 1e6
    );
    let mut times = vec![];
    let (mut exp, mut tests) = (0, 0);
    let mut worst_ratio = 0.0f64;
    for &(s, g) in queries {
        let mut best = f64::INFINITY;
        let (ps, pg) = (
            skyplan_anyangle::GridPoint::center(s),
            skyplan_anyangle::GridPoint::center(g),
        );
        let mut length = 0.0;
        for _ in 0..reps {
            let t = Instant::now();
            let p = planner.plan(ps, pg).expect("path");
            best = best.min(t.elapsed().as_secs_f64());
            length = p.length_cells;
            exp = p.expansions;
            tests = p.segment_tests;
        }
        let theta = search
            .search(grid, s, g, model, Planner::ThetaStar)
            .expect("theta")
            .cost_cells();
        let octile = search
            .search(grid, s, g, model, Planner::Jps)
            .expect("jps")
            .cost_cells();
        worst_ratio = worst_ratio.max(length / theta);
        println!(
            "  query {:3}: anyangle {:9.3} theta {:9.3} octile {:9.3}  {:7.3} ms  {exp} expansions {tests} tests",
            times.len(),
            length,
            theta,
            octile,
            best * 1e3
        );
        times.push(best);
    }
    println!(
        "anyangle median {:9.3} ms, worst length / theta {worst_ratio:.6}",
        median(times) * 1e3
    );
}

fn jps_plus(grid: &Grid2, queries: &[(Cell, Cell)], reps: usize) {
    let t = Instant::now();
    let mut plus = JpsPlus::new(grid, MoveModel::Octile);
    println!("jps+ table {:.1} ms", t.elapsed().as_secs_f64() * 1e3);
    let mut times = vec![];
    for &(s, g) in queries {
        let mut best = f64::INFINITY;
        for _ in 0..reps {
            let t = Instant::now();
            plus.search(s, g).expect("path");
            best = best.min(t.elapsed().as_secs_f64());
        }
        times.push(best);
    }
    println!("jps+     median {:9.3} ms", median(times) * 1e3);
}
