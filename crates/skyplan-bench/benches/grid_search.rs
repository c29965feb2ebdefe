//! criterion benches: the grid build on the city map, every planner on the city map and on a
//! MovingAI map (`cargo bench -p skyplan-bench`). The same queries as `skyplan bench`.

use criterion::{Criterion, criterion_group, criterion_main};
use skyplan_bench::random_far_queries;
use skyplan_cspace::{Cell, Grid2, GridFrame, GridSpec};
use skyplan_search::{GridSearch, JpsPlus, MoveModel, Planner};
use std::hint::black_box;

const CITY: &str = include_str!("../../../data/colliders.csv");

fn city_map() -> skyplan_map::colliders::CollidersMap {
    skyplan_map::colliders::parse_colliders(CITY).expect("bundled map parses")
}

fn movingai(name: &str) -> Option<(Grid2, Vec<(Cell, Cell)>)> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/movingai/");
    let map = std::fs::read_to_string(format!("{dir}{name}.map")).ok()?;
    let scen = std::fs::read_to_string(format!("{dir}{name}.map.scen")).ok()?;
    let map = skyplan_map::movingai::parse_map(&map).ok()?;
    let blocked = map.passable.iter().map(|&p| !p).collect();
    let grid = Grid2::new(
        map.height as u32,
        map.width as u32,
        blocked,
        GridFrame::default(),
    )
    .ok()?;
    let queries = skyplan_map::movingai::parse_scen(&scen)
        .ok()?
        .iter()
        .rev() // the longest buckets
        .take(100)
        .map(|s| {
            (
                Cell::new(s.start_y as u32, s.start_x as u32),
                Cell::new(s.goal_y as u32, s.goal_x as u32),
            )
        })
        .collect();
    Some((grid, queries))
}

fn grid_build(c: &mut Criterion) {
    let map = city_map();
    let mut group = c.benchmark_group("grid_build");
    for alt_m in [5.0, 50.0] {
        let spec = GridSpec {
            alt_m,
            safety_m: 5.0,
            cell_m: 1.0,
        };
        group.bench_function(format!("city_{alt_m}m"), |b| {
            b.iter(|| Grid2::from_colliders(black_box(&map), spec))
        });
    }
    group.finish();
}

fn planners_on(c: &mut Criterion, label: &str, grid: &Grid2, queries: &[(Cell, Cell)]) {
    let model = MoveModel::Octile;
    let mut group = c.benchmark_group(label);
    group.sample_size(10);
    let mut plus = JpsPlus::new(grid, model);
    group.bench_function("jps_plus", |b| {
        b.iter(|| {
            queries
                .iter()
                .map(|&(s, g)| plus.search(s, g).map(|p| p.cost_cells()).unwrap_or(0.0))
                .sum::<f64>()
        })
    });
    let mut search = GridSearch::new();
    for (name, planner) in [("jps", Planner::Jps), ("astar", Planner::AStar)] {
        group.bench_function(name, |b| {
            b.iter(|| {
                queries
                    .iter()
                    .map(|&(s, g)| {
                        search
                            .search(grid, s, g, model, planner)
                            .map(|p| p.cost_cells())
                            .unwrap_or(0.0)
                    })
                    .sum::<f64>()
            })
        });
    }
    group.bench_function("jps_plus_table_build", |b| {
        b.iter(|| JpsPlus::new(black_box(grid), model).table_bytes())
    });
    group.finish();
}

fn city_planners(c: &mut Criterion) {
    let grid = Grid2::from_colliders(&city_map(), GridSpec::default()).expect("city grid");
    let diagonal = f64::from(grid.rows()).hypot(f64::from(grid.cols()));
    let queries = random_far_queries(&grid, MoveModel::Octile, 26, 1, 0.5 * diagonal);
    planners_on(c, "city_26_far_queries", &grid, &queries);
}

fn movingai_planners(c: &mut Criterion) {
    if let Some((grid, queries)) = movingai("Boston_0_512") {
        planners_on(c, "boston_100_longest_scenarios", &grid, &queries);
    }
}

criterion_group!(benches, grid_build, city_planners, movingai_planners);
criterion_main!(benches);
