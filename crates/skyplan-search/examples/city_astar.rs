//! Time per expansion of A*, JPS and JPS+ on the bundled city (921 × 921 cells, 5 m altitude,
//! 5 m margin), 26 far-apart queries from a fixed generator. Run with
//! `cargo run --release -p skyplan-search --example city_astar [REPEATS]`; for instruction
//! counts, under `valgrind --tool=callgrind` with REPEATS = 1.

use skyplan_cspace::{Cell, Grid2, GridSpec};
use skyplan_search::{GridSearch, JpsPlus, MoveModel, Planner};
use std::time::Instant;

const CITY: &str = include_str!("../../../data/colliders.csv");

/// Far-apart free cell pairs from a fixed 64-bit LCG (the same pairs on every machine).
fn far_queries(grid: &Grid2, count: usize) -> Vec<(Cell, Cell)> {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = |n: usize| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 33) as usize) % n
    };
    let min_d = 0.5 * f64::from(grid.rows()).hypot(f64::from(grid.cols()));
    let mut out = Vec::new();
    let mut search = GridSearch::new();
    while out.len() < count {
        let a = grid.cell(next(grid.len()));
        let b = grid.cell(next(grid.len()));
        let d = (f64::from(a.row) - f64::from(b.row)).hypot(f64::from(a.col) - f64::from(b.col));
        if d >= min_d
            && search
                .search(grid, a, b, MoveModel::Octile, Planner::Jps)
                .is_ok()
        {
            out.push((a, b));
        }
    }
    out
}

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let only = std::env::args().nth(2);
    let map = skyplan_map::colliders::parse_colliders(CITY).expect("bundled map parses");
    let grid = Grid2::from_colliders(&map, GridSpec::default()).expect("city grid");
    let queries = far_queries(&grid, 26);
    let model = MoveModel::Octile;
    let mut search = GridSearch::new();
    let mut plus = JpsPlus::new(&grid, model);
    for (name, planner) in [
        ("astar", Planner::AStar),
        ("jps", Planner::Jps),
        ("jps-plus", Planner::JpsPlus),
    ] {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let mut best = f64::INFINITY;
        let (mut expansions, mut cost) = (0u64, 0.0);
        for _ in 0..repeats {
            let t = Instant::now();
            (expansions, cost) = (0, 0.0);
            for &(s, g) in &queries {
                let path = if planner == Planner::JpsPlus {
                    plus.search(s, g)
                } else {
                    search.search(&grid, s, g, model, planner)
                }
                .expect("connected");
                expansions += path.expansions;
                cost += path.cost_cells();
            }
            best = best.min(t.elapsed().as_secs_f64());
        }
        println!(
            "{name:9} {expansions:9} expansions  total cost {cost:.4}  best {:.2} ms  {:.1} ns/expansion",
            best * 1e3,
            best * 1e9 / expansions as f64
        );
    }
}
