//! D* Lite against searching from scratch on the city: an obstacle appears across the default route
//! ahead of the vehicle, which has flown part of the way. Times the repair (D* Lite:
//! `update_cells` + `move_start` + `compute`) against JPS and A* from scratch on the edited grid,
//! and prints the expansions of each (`cargo bench -p skyplan-replan`).

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use skyplan_cspace::Cell;
use skyplan_plan::{PlanRequest, Session, World};
use skyplan_replan::DStarLite;
use skyplan_search::{GridSearch, MoveModel, Planner};
use std::hint::black_box;

fn scenario() -> (skyplan_cspace::Grid2, DStarLite, Cell, Vec<(Cell, bool)>) {
    let mut session = Session::new(World::fcnd_city());
    let plan = session
        .plan(&PlanRequest::default())
        .expect("the default route");
    let grid = (*session.grid(5.0, 5.0, 1.0).expect("the grid")).clone();
    let cell = |n: f64, e: f64| grid.cell_at_ne(n, e).expect("on the map");
    let start = cell(plan.start.north_m, plan.start.east_m);
    let goal = cell(plan.goal.north_m, plan.goal.east_m);
    let mut d = DStarLite::new(&grid, start, goal, MoveModel::Octile).expect("inside");
    let path = d.compute().expect("a path");
    // The vehicle has flown a third of the way; a cross of two 31 × 11-cell bars (an obstacle
    // grown by the 5 m margin) stands on the path 30 cells ahead.
    let at = path.cells[path.cells.len() / 3];
    d.move_start(at);
    let ahead = path.cells[path.cells.len() / 3 + 30];
    let mut edits = Vec::new();
    for dr in -15i64..=15 {
        for dc in -15i64..=15 {
            let in_cross = dr.abs() <= 5 || dc.abs() <= 5;
            let cell = grid.checked_cell(i64::from(ahead.row) + dr, i64::from(ahead.col) + dc);
            if let Some(c) = cell.filter(|&c| in_cross && !grid.is_blocked(c)) {
                edits.push((c, true));
            }
        }
    }
    (grid, d, at, edits)
}

fn bench(c: &mut Criterion) {
    let (grid, d, at, edits) = scenario();
    let mut edited = grid.clone();
    for &(cell, b) in &edits {
        edited.set_blocked(cell, b);
    }
    let goal = d.goal();
    // Expansions, printed once.
    let mut repaired = d.clone();
    let before = repaired.expansions();
    repaired.update_cells(&edits);
    let p = repaired.compute().expect("a way round");
    let mut search = GridSearch::new();
    let jps = search
        .search(&edited, at, goal, MoveModel::Octile, Planner::Jps)
        .expect("jps");
    let astar = search
        .search(&edited, at, goal, MoveModel::Octile, Planner::AStar)
        .expect("a*");
    println!(
        "replan on the city after a wall: D* Lite {} expansions, JPS from scratch {}, A* from scratch {} (costs {:.3} / {:.3} / {:.3} cells)",
        repaired.expansions() - before,
        jps.expansions,
        astar.expansions,
        p.cost_cells(),
        jps.cost_cells(),
        astar.cost_cells()
    );
    let mut g = c.benchmark_group("replan_city");
    g.sample_size(20);
    g.bench_function("dstar_lite_repair", |b| {
        b.iter_batched(
            || d.clone(),
            |mut d| {
                d.update_cells(black_box(&edits));
                black_box(d.compute())
            },
            BatchSize::LargeInput,
        )
    });
    g.bench_function("jps_from_scratch", |b| {
        b.iter(|| black_box(search.search(&edited, at, goal, MoveModel::Octile, Planner::Jps)))
    });
    g.bench_function("astar_from_scratch", |b| {
        b.iter(|| black_box(search.search(&edited, at, goal, MoveModel::Octile, Planner::AStar)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
