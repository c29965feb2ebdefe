//! Time per expansion of A*, JPS and JPS+ on the bundled city (921 × 921 cells, 5 m altitude,
//! 5 m margin), 26 far-apart queries from a fixed generator. Run with
//! `cargo run --release -p skyplan-search --example city_astar [REPEATS]`; for instruction
//! counts, under `valgrind --tool=callgrind` with REPEATS = 1.

use skyplan_cspace::{Grid2, GridSpec};
use skyplan_search::{GridSearch, JpsPlus, MoveModel, Planner};
use std::time::Instant;

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let only = std::env::args().nth(2);
    let map = skyplan_map::colliders::parse_colliders(skyplan_testkit::CITY_CSV)
        .expect("bundled map parses");
    let grid = Grid2::from_colliders(&map, GridSpec::default()).expect("city grid");
    // Far-apart free cell pairs with a path (found with a workspace of their own, dropped here).
    let queries = {
        let mut search = GridSearch::new();
        skyplan_testkit::lcg_far_pairs(&grid, 26, |a, b| {
            search
                .search(&grid, a, b, MoveModel::Octile, Planner::Jps)
                .is_ok()
        })
    };
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
