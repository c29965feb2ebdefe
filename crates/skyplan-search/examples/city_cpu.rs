//! Wall-clock and CPU time per query of JPS+ and JPS on a (tiled) colliders map, for a machine
//! shared with other work: the CPU time (from /proc/thread-self/schedstat, nanoseconds on the
//! CPU) does not count the time the thread waited for a core. Run with
//! `cargo run --release -p skyplan-search --example city_cpu -- MAP.csv [QUERIES] [TABLE_FILE] [jps-plus|jps]`
//! (with a table file saved by `skyplan bench --save-preprocess`, JPS+ loads it instead of
//! building it).

use skyplan_cspace::{Cell, Grid2, GridSpec};
use skyplan_search::{Components, GridSearch, JpsPlusTable, MoveModel, Planner};
use std::sync::Arc;
use std::time::Instant;

/// Nanoseconds this thread has run on a CPU (0 where schedstat is missing).
fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// Far-apart connected free cell pairs from a fixed 64-bit LCG.
fn far_queries(grid: &Grid2, count: usize) -> Vec<(Cell, Cell)> {
    let components = Components::new(grid, MoveModel::Octile);
    skyplan_testkit::lcg_far_pairs(grid, count, |a, b| {
        !grid.is_blocked(a) && !grid.is_blocked(b) && components.connected(a, b)
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .expect("usage: city_cpu MAP.csv [QUERIES] [TABLE_FILE] [jps-plus|jps]");
    let count: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(20);
    let text = std::fs::read_to_string(path).expect("map file");
    let map = skyplan_map::colliders::parse_colliders(&text).expect("colliders map");
    drop(text);
    let grid = Arc::new(Grid2::from_colliders(&map, GridSpec::default()).expect("grid"));
    drop(map);
    let queries = far_queries(&grid, count);
    let model = MoveModel::Octile;
    let (wall, cpu) = (Instant::now(), cpu_ns());
    let table = match args.get(3) {
        Some(file) => {
            let f = std::fs::File::open(file).expect("table file");
            JpsPlusTable::read_from(f, Arc::clone(&grid)).expect("table loads")
        }
        None => JpsPlusTable::build(Arc::clone(&grid), model),
    };
    println!(
        "{} × {} cells; JPS+ table {} in {:.0} ms wall, {:.0} ms CPU",
        grid.rows(),
        grid.cols(),
        if args.get(3).is_some() {
            "loaded"
        } else {
            "built"
        },
        wall.elapsed().as_secs_f64() * 1e3,
        (cpu_ns() - cpu) as f64 / 1e6
    );
    let mut search = GridSearch::new();
    let only = args.get(4);
    for name in ["jps-plus", "jps"] {
        if only.is_some_and(|o| o != name) {
            continue;
        }
        let (mut walls, mut cpus) = (Vec::new(), Vec::new());
        for (k, &(a, b)) in queries.iter().enumerate() {
            let (wall, cpu) = (Instant::now(), cpu_ns());
            let path = if name == "jps" {
                search.search(&grid, a, b, model, Planner::Jps)
            } else {
                table.search(&mut search, a, b)
            }
            .expect("connected query");
            if k > 0 || count == 1 {
                walls.push(wall.elapsed().as_secs_f64() * 1e3);
                cpus.push((cpu_ns() - cpu) as f64 / 1e6);
            }
            std::hint::black_box(path);
        }
        println!(
            "{name:>8}: {} queries (after one warm-up), median {:.2} ms wall, {:.2} ms CPU; max {:.2} ms wall, {:.2} ms CPU",
            walls.len(),
            median(walls.clone()),
            median(cpus.clone()),
            walls.iter().copied().fold(0.0, f64::max),
            cpus.iter().copied().fold(0.0, f64::max)
        );
    }
}
