use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_search::*;
use std::sync::Arc;
use std::time::Instant;
fn main() {
    for name in std::env::args().skip(1) {
        let text = std::fs::read_to_string(format!("data/movingai/{name}.map")).unwrap();
        let map = skyplan_map::movingai::parse_map(&text).unwrap();
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
        let scen = skyplan_map::movingai::parse_scen(
            &std::fs::read_to_string(format!("data/movingai/{name}.map.scen")).unwrap(),
        )
        .unwrap();
        let t = Instant::now();
        let ch = ContractionHierarchy::build(Arc::clone(&grid), MoveModel::Octile).unwrap();
        let prep = t.elapsed().as_secs_f64() * 1e3;
        let mut q = ChQuery::default();
        let mut times = Vec::new();
        let mut bad = 0;
        let mut exp = 0u64;
        for s in &scen {
            let (a, b) = (
                Cell::new(s.start_y as u32, s.start_x as u32),
                Cell::new(s.goal_y as u32, s.goal_x as u32),
            );
            let t = Instant::now();
            let p = ch.search(&mut q, a, b).unwrap();
            times.push(t.elapsed().as_secs_f64() * 1e6);
            exp += p.expansions;
            if (p.cost_cells() - s.optimal_length).abs() > 1e-3 {
                bad += 1;
            }
        }
        times.sort_by(f64::total_cmp);
        let mean = times.iter().sum::<f64>() / times.len() as f64;
        println!(
            "{name}: prep {prep:.0} ms, up edges {}, median {:.1} us mean {mean:.1} us, settled {:.0}, wrong {bad}/{}",
            ch.upward_edges(),
            times[times.len() / 2],
            exp as f64 / times.len() as f64,
            times.len()
        );
    }
}
