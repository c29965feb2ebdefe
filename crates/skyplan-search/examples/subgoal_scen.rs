//! Times the subgoal graph (or the first-move table) against JPS+ on a MovingAI map and its
//! scenarios, checking every length:
//! `cargo run --release -p skyplan-search --example subgoal_scen -- MAP SCEN [first-move]`.

use skyplan_cspace::{Cell, Grid2};
use skyplan_search::{
    FirstMoveTable, GridPath, GridSearch, JpsPlusTable, MoveModel, SearchError, SubgoalGraph,
    SubgoalQuery,
};
use std::sync::Arc;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args[1] == "city" {
        let map = skyplan_map::colliders::parse_colliders(skyplan_testkit::CITY_CSV).unwrap();
        let grid =
            Arc::new(Grid2::from_colliders(&map, skyplan_cspace::GridSpec::default()).unwrap());
        let t = Instant::now();
        let sg = SubgoalGraph::build(Arc::clone(&grid), MoveModel::Octile).unwrap();
        println!(
            "city {}x{}: {} subgoals, {} edges, {:.1} ms",
            grid.rows(),
            grid.cols(),
            sg.subgoals(),
            sg.edges(),
            t.elapsed().as_secs_f64() * 1e3
        );
        return;
    }
    let (grid, scen) = skyplan_testkit::movingai(&args[1], &args[2]);
    let grid = Arc::new(grid);
    let t = Instant::now();
    let first_move = args.get(3).is_some_and(|a| a == "first-move");
    let name = if first_move { "first-move" } else { "subgoal" };
    let mut q = SubgoalQuery::new();
    let mut search: Box<dyn FnMut(Cell, Cell) -> Result<GridPath, SearchError>> = if first_move {
        let fm = FirstMoveTable::build(Arc::clone(&grid), MoveModel::Octile, 1 << 30).unwrap();
        println!(
            "first-move table: {} free cells, {:.1} MB, {:.1} ms",
            fm.free_cells(),
            fm.table_bytes() as f64 / 1e6,
            t.elapsed().as_secs_f64() * 1e3
        );
        // Throughput: every scenario 200 times, no timer per query.
        let pairs: Vec<(Cell, Cell)> = (scen.iter())
            .map(|s| {
                (
                    Cell::new(s.start_y as u32, s.start_x as u32),
                    Cell::new(s.goal_y as u32, s.goal_x as u32),
                )
            })
            .collect();
        let t = Instant::now();
        let mut cells = 0usize;
        for _ in 0..200 {
            for &(a, b) in &pairs {
                cells += fm.search(a, b).map_or(0, |p| p.cells.len());
            }
        }
        let ns = t.elapsed().as_secs_f64() * 1e9;
        println!(
            "first-move throughput: {:.0} ns per query, {:.2} ns per path cell",
            ns / (200 * pairs.len()) as f64,
            ns / cells as f64
        );
        Box::new(move |a, b| fm.search(a, b))
    } else {
        let sg = SubgoalGraph::build(Arc::clone(&grid), MoveModel::Octile).unwrap();
        println!(
            "subgoal graph: {} subgoals, {} edges, {:.1} ms",
            sg.subgoals(),
            sg.edges(),
            t.elapsed().as_secs_f64() * 1e3
        );
        Box::new(move |a, b| sg.search(&mut q, a, b))
    };
    let t = Instant::now();
    let table = JpsPlusTable::build(Arc::clone(&grid), MoveModel::Octile);
    println!("jps+ table: {:.1} ms", t.elapsed().as_secs_f64() * 1e3);
    let mut ws = GridSearch::new();
    let (mut ts, mut tj, mut exp) = (Vec::new(), Vec::new(), Vec::new());
    let mut bad = 0;
    for s in &scen {
        let a = Cell::new(s.start_y as u32, s.start_x as u32);
        let b = Cell::new(s.goal_y as u32, s.goal_x as u32);
        let t = Instant::now();
        let p = search(a, b).unwrap();
        ts.push(t.elapsed().as_secs_f64() * 1e6);
        exp.push(p.expansions as f64);
        let t = Instant::now();
        let j = table.search(&mut ws, a, b).unwrap();
        tj.push(t.elapsed().as_secs_f64() * 1e6);
        let ok = skyplan_search::check_path(&grid, &p.cells, MoveModel::Octile).is_ok();
        if !ok
            || (p.cost_cells() - s.optimal_length).abs() > 1e-4
            || (j.cost_cells() - p.cost_cells()).abs() > 1e-6
            || p.cells.first() != Some(&a)
            || p.cells.last() != Some(&b)
        {
            bad += 1;
            if bad < 5 {
                println!(
                    "line {}: {name} {} (valid {ok}) jps+ {} published {}",
                    s.line,
                    p.cost_cells(),
                    j.cost_cells(),
                    s.optimal_length
                );
            }
        }
    }
    println!(
        "{} scenarios, {bad} wrong; median µs {name} {:.2} (expansions {:.0}), jps+ {:.2}",
        scen.len(),
        median(ts),
        median(exp),
        median(tj)
    );
}
