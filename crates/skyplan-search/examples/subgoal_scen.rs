//! Times the subgoal graph against JPS+ on a MovingAI map and its scenarios, checking every
//! length: `cargo run --release -p skyplan-search --example subgoal_scen -- MAP SCEN`.

use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_search::{GridSearch, JpsPlusTable, MoveModel, SubgoalGraph, SubgoalQuery};
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
    let map =
        skyplan_map::movingai::parse_map(&std::fs::read_to_string(&args[1]).unwrap()).unwrap();
    let scen =
        skyplan_map::movingai::parse_scen(&std::fs::read_to_string(&args[2]).unwrap()).unwrap();
    let blocked: Vec<bool> = map.passable.iter().map(|&p| !p).collect();
    let grid = Arc::new(
        Grid2::new(
            map.height as u32,
            map.width as u32,
            blocked,
            GridFrame::default(),
        )
        .unwrap(),
    );
    let t = Instant::now();
    let sg = SubgoalGraph::build(Arc::clone(&grid), MoveModel::Octile).unwrap();
    println!(
        "subgoal graph: {} subgoals, {} edges, {:.1} ms",
        sg.subgoals(),
        sg.edges(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let t = Instant::now();
    let table = JpsPlusTable::build(Arc::clone(&grid), MoveModel::Octile);
    println!("jps+ table: {:.1} ms", t.elapsed().as_secs_f64() * 1e3);
    let mut q = SubgoalQuery::new();
    let mut ws = GridSearch::new();
    let (mut ts, mut tj, mut exp) = (Vec::new(), Vec::new(), Vec::new());
    let mut bad = 0;
    for s in &scen {
        let a = Cell::new(s.start_y as u32, s.start_x as u32);
        let b = Cell::new(s.goal_y as u32, s.goal_x as u32);
        let t = Instant::now();
        let p = sg.search(&mut q, a, b).unwrap();
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
                    "line {}: subgoal {} (valid {ok}) jps+ {} published {}",
                    s.line,
                    p.cost_cells(),
                    j.cost_cells(),
                    s.optimal_length
                );
            }
        }
    }
    println!(
        "{} scenarios, {bad} wrong; median µs subgoal {:.1} (expansions {:.0}), jps+ {:.1}",
        scen.len(),
        median(ts),
        median(exp),
        median(tj)
    );
}
