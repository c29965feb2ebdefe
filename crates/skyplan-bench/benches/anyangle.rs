//! criterion benches of the exact any-angle planner on the city map (`cargo bench -p skyplan-bench
//! --bench anyangle`): the visibility-graph build, and the 26 far-apart queries of `skyplan bench`
//! (seed 1) answered by the any-angle planner and by JPS. Theta\* takes ~0.2 s per query here and is
//! timed by `cargo run --release -p skyplan-anyangle --example city_anyangle` instead.

use criterion::{Criterion, criterion_group, criterion_main};
use skyplan_anyangle::{AnyAngle, GridPoint};
use skyplan_bench::random_far_queries;
use skyplan_cspace::{Cell, Grid2, GridSpec};
use skyplan_search::{GridSearch, MoveModel, Planner};
use std::hint::black_box;

const CITY: &str = include_str!("../../../data/colliders.csv");

/// The summed lengths of every query's answer (0 for a query without one), so that the work is
/// not optimised away.
fn total_length<E>(
    queries: &[(Cell, Cell)],
    mut length: impl FnMut(Cell, Cell) -> Result<f64, E>,
) -> f64 {
    queries
        .iter()
        .map(|&(s, g)| length(s, g).unwrap_or(0.0))
        .sum()
}

fn city_anyangle(c: &mut Criterion) {
    let map = skyplan_map::colliders::parse_colliders(CITY).expect("bundled map parses");
    let spec = GridSpec {
        alt_m: 5.0,
        safety_m: 5.0,
        cell_m: 1.0,
    };
    let grid = Grid2::from_colliders(&map, spec).expect("city grid");
    let diagonal = f64::from(grid.rows()).hypot(f64::from(grid.cols()));
    let queries = random_far_queries(&grid, MoveModel::Octile, 26, 1, 0.5 * diagonal);
    let mut group = c.benchmark_group("city_anyangle");
    group.sample_size(10);
    group.bench_function("graph_build", |b| {
        b.iter(|| AnyAngle::new(black_box(&grid)).edge_count())
    });
    let planner = AnyAngle::new(&grid);
    // One query at a time, so criterion's estimate is a per-query time.
    for (k, &(s, g)) in queries.iter().enumerate().take(3) {
        let (ps, pg) = (GridPoint::center(s), GridPoint::center(g));
        group.bench_function(format!("anyangle_query_{k}"), |b| {
            b.iter(|| planner.plan(ps, pg).map(|p| p.length_cells).unwrap_or(0.0))
        });
    }
    group.bench_function("anyangle_26_queries", |b| {
        b.iter(|| {
            total_length(&queries, |s, g| {
                planner
                    .plan(GridPoint::center(s), GridPoint::center(g))
                    .map(|p| p.length_cells)
            })
        })
    });
    let mut search = GridSearch::new();
    group.bench_function("jps_26_queries", |b| {
        b.iter(|| {
            total_length(&queries, |s, g| {
                search
                    .search(&grid, s, g, MoveModel::Octile, Planner::Jps)
                    .map(|p| p.cost_cells())
            })
        })
    });
    group.finish();
}

criterion_group!(benches, city_anyangle);
criterion_main!(benches);
