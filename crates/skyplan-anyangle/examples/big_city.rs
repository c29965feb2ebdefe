//! The city tiled K × K (`skyplan_map::tile`), one far JPS query (and optionally A\* and the
//! any-angle planner): time, the search state's bytes and the process's peak resident memory.
//! `cargo run --release -p skyplan-anyangle --example big_city -- 10 [astar] [anyangle]`.

use skyplan_anyangle::{AnyAngle, GridPoint};
use skyplan_cspace::{Grid2, GridSpec};
use skyplan_search::{GridSearch, MoveModel, Planner};
use std::time::Instant;

const CITY: &str = include_str!("../../../data/colliders.csv");

/// Peak resident set of this process in MB (Linux; NaN elsewhere), for the report.
fn peak_rss_mb() -> f64 {
    skyplan_bench::grid_bench::peak_rss_bytes().map_or(f64::NAN, |b| b as f64 / (1024.0 * 1024.0))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let times: u32 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(10);
    let map = skyplan_map::colliders::parse_colliders(CITY).expect("bundled map parses");
    // The bench's grid: 5 m altitude, 5 m margin, 1 m cells.
    let one = Grid2::from_colliders(&map, GridSpec::default()).expect("city grid");
    let pitch_m = f64::from(one.rows());
    // The first bench query of one tile, its goal moved to the far tile.
    let diagonal = f64::from(one.rows()).hypot(f64::from(one.cols()));
    let (s0, g0) =
        skyplan_bench::random_far_queries(&one, MoveModel::Octile, 1, 1, 0.5 * diagonal)[0];
    drop(one);
    let t = Instant::now();
    let big = skyplan_map::tile(&map, times, pitch_m);
    let grid = Grid2::from_colliders(&big, GridSpec::default()).expect("tiled grid");
    println!(
        "K = {times}: {} boxes, grid {} x {} ({:.1} M cells) in {:.2} s, peak RSS {:.0} MB",
        big.boxes.len(),
        grid.rows(),
        grid.cols(),
        grid.len() as f64 / 1e6,
        t.elapsed().as_secs_f64(),
        peak_rss_mb()
    );
    let shift = (times - 1) * pitch_m as u32;
    let start = s0;
    let goal = skyplan_cspace::Cell::new(g0.row + shift, g0.col + shift);
    let mut search = GridSearch::new();
    let mut planners = vec![("jps", Planner::Jps)];
    if args.iter().any(|a| a == "astar") {
        planners.push(("astar", Planner::AStar));
    }
    for (name, planner) in planners {
        for run in 0..2 {
            let t = Instant::now();
            let path = search.search(&grid, start, goal, MoveModel::Octile, planner);
            let dt = t.elapsed().as_secs_f64();
            match path {
                Ok(p) => println!(
                    "{name} run {run}: {:.1} ms, cost {:.1} cells, {} expansions, search state {:.1} MB, peak RSS {:.0} MB",
                    dt * 1e3,
                    p.cost_cells(),
                    p.expansions,
                    search.node_bytes() as f64 / 1e6,
                    peak_rss_mb()
                ),
                Err(e) => println!("{name}: {e}"),
            }
        }
    }
    if args.iter().any(|a| a == "anyangle") {
        let t = Instant::now();
        let planner = AnyAngle::new(&grid);
        println!(
            "anyangle graph: {:.2} s, {} corners, {} edges, {:.1} MB, peak RSS {:.0} MB",
            t.elapsed().as_secs_f64(),
            planner.corner_count(),
            planner.edge_count(),
            planner.graph_bytes() as f64 / 1e6,
            peak_rss_mb()
        );
        let t = Instant::now();
        match planner.plan(GridPoint::center(start), GridPoint::center(goal)) {
            Ok(p) => println!(
                "anyangle: {:.1} ms, length {:.1} cells, {} expansions",
                t.elapsed().as_secs_f64() * 1e3,
                p.length_cells,
                p.expansions
            ),
            Err(e) => println!("anyangle: {e}"),
        }
    }
}
