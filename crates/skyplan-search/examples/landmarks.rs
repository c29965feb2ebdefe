//! JPS+ with and without landmarks (`JpsPlusTable::add_landmarks`) on the same queries:
//! median time and expansions, every cost compared. Run with
//! `cargo run --release -p skyplan-search --example landmarks -- MAP.map SCEN K` (a MovingAI map
//! and its scenarios) or `… -- MAP.csv N K` (a colliders map, N far-apart queries); K landmarks.
//! `ROUNDS=R` repeats the queries R times (default 2).

use skyplan_cspace::{Cell, Grid2, GridSpec};
use skyplan_search::{Components, GridSearch, JpsPlusTable, Landmarks, MoveModel};
use std::sync::Arc;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let k: usize = args[3].parse().unwrap();
    let (grid, pairs) = if args[1].ends_with(".csv") {
        let map =
            skyplan_map::colliders::parse_colliders(&std::fs::read_to_string(&args[1]).unwrap())
                .unwrap();
        let grid = Arc::new(Grid2::from_colliders(&map, GridSpec::default()).unwrap());
        let n: usize = args[2].parse().unwrap();
        let comp = Components::new(&grid, MoveModel::Octile);
        let pairs = skyplan_testkit::lcg_far_pairs(&grid, n, |a, b| {
            !grid.is_blocked(a) && !grid.is_blocked(b) && comp.connected(a, b)
        });
        (grid, pairs)
    } else {
        let (grid, scen) = skyplan_testkit::movingai(&args[1], &args[2]);
        let grid = Arc::new(grid);
        let pairs = scen
            .iter()
            .map(|s| {
                (
                    Cell::new(s.start_y as u32, s.start_x as u32),
                    Cell::new(s.goal_y as u32, s.goal_x as u32),
                )
            })
            .collect();
        (grid, pairs)
    };
    let t = Instant::now();
    let table = JpsPlusTable::build(Arc::clone(&grid), MoveModel::Octile);
    println!("jps+ table {:.1} ms", t.elapsed().as_secs_f64() * 1e3);
    let guided = JpsPlusTable::build(Arc::clone(&grid), MoveModel::Octile);
    let t = Instant::now();
    let lm: &Landmarks = guided.add_landmarks(k);
    println!(
        "{} landmarks {:.1} ms, {:.1} MB",
        lm.cells().len(),
        t.elapsed().as_secs_f64() * 1e3,
        lm.bytes() as f64 / 1e6
    );
    let mut ws = GridSearch::new();
    let rounds: usize = std::env::var("ROUNDS").map_or(2, |r| r.parse().unwrap());
    for _round in 0..rounds {
        let (mut t0, mut t1, mut e0, mut e1) = (vec![], vec![], vec![], vec![]);
        let mut bad = 0;
        for &(a, b) in &pairs {
            let t = Instant::now();
            let p = if std::env::var_os("GUIDED_ONLY").is_some() {
                guided.search(&mut ws, a, b).unwrap()
            } else {
                table.search(&mut ws, a, b).unwrap()
            };
            t0.push(t.elapsed().as_secs_f64() * 1e6);
            e0.push(p.expansions as f64);
            let t = Instant::now();
            let q = guided.search(&mut ws, a, b).unwrap();
            t1.push(t.elapsed().as_secs_f64() * 1e6);
            e1.push(q.expansions as f64);
            if (p.cost_cells() - q.cost_cells()).abs() > 1e-9 {
                bad += 1;
            }
        }
        println!(
            "{} queries, {bad} differ; jps+ median {:.2} µs ({:.0} exp, mean {:.0}), with landmarks {:.2} µs ({:.0} exp, mean {:.0})",
            pairs.len(),
            median(t0),
            median(e0.clone()),
            e0.iter().sum::<f64>() / e0.len() as f64,
            median(t1),
            median(e1.clone()),
            e1.iter().sum::<f64>() / e1.len() as f64,
        );
    }
}
