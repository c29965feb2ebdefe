//! Times contraction-hierarchy queries on a MovingAI map and its scenarios, every length checked
//! against the published one: `cargo run --release -p skyplan-search --example ch_scen -- MAP
//! SCEN [HIERARCHY]` (a hierarchy saved by `skyplan scen --planner ch --save-preprocess`, else
//! built). `ROUNDS=R` repeats the scenarios R times (default 5); each round's median is printed.

use skyplan_cspace::Cell;
use skyplan_search::{ChQuery, ContractionHierarchy, MoveModel};
use std::sync::Arc;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (grid, scen) = skyplan_testkit::movingai(&args[1], &args[2]);
    let grid = Arc::new(grid);
    let t = Instant::now();
    let ch = match args.get(3) {
        Some(file) => ContractionHierarchy::read_from(
            std::io::BufReader::new(std::fs::File::open(file).unwrap()),
            Arc::clone(&grid),
            MoveModel::Octile,
        )
        .unwrap(),
        None => ContractionHierarchy::build(Arc::clone(&grid), MoveModel::Octile).unwrap(),
    };
    println!(
        "hierarchy: {} upward edges, {:.1} ms",
        ch.upward_edges(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let rounds: usize = std::env::var("ROUNDS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(5);
    let mut query = ChQuery::default();
    for round in 0..rounds {
        let mut times = Vec::with_capacity(scen.len());
        let mut wrong = 0;
        for s in &scen {
            let start = Cell::new(s.start_y as u32, s.start_x as u32);
            let goal = Cell::new(s.goal_y as u32, s.goal_x as u32);
            let t = Instant::now();
            let path = ch.search(&mut query, start, goal).unwrap();
            times.push(t.elapsed().as_secs_f64() * 1e6);
            if (path.cost_cells() - s.optimal_length).abs() > 1e-4 {
                wrong += 1;
            }
        }
        times.sort_by(f64::total_cmp);
        println!(
            "round {round}: {} queries, {wrong} wrong, median {:.2} µs",
            times.len(),
            times[times.len() / 2]
        );
    }
}
