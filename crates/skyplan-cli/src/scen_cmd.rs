//! `skyplan scen`: replay MovingAI scenarios and compare each cost with `optimal_length`.

use crate::args::{PlannerArg, ScenArgs};
use crate::exit::{Failure, Kind, Result, bad_input};
use crate::files::read_text;
use anyhow::anyhow;
use serde_json::json;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_search::{GridSearch, JpsPlus, MoveModel, Planner};
use std::collections::BTreeMap;
use std::time::Instant;

/// Relative tolerance for matching a published optimal length.
const REL_TOL: f64 = 1e-6;

#[derive(Default)]
struct Bucket {
    count: u64,
    matched: u64,
    total_us: f64,
}

pub fn run(args: ScenArgs) -> Result<()> {
    let map_text = read_text(&args.map)?;
    let scen_text = read_text(&args.scen)?;
    let map = skyplan_map::movingai::parse_map(&map_text)
        .map_err(|e| bad_input(format!("{}: {e}", args.map.display())))?;
    let scenarios = skyplan_map::movingai::parse_scen(&scen_text)
        .map_err(|e| bad_input(format!("{}: {e}", args.scen.display())))?;
    let blocked: Vec<bool> = map.passable.iter().map(|&p| !p).collect();
    let grid = Grid2::new(
        map.height as u32,
        map.width as u32,
        blocked,
        GridFrame::default(),
    )
    .map_err(|e| bad_input(format!("{}: {e}", args.map.display())))?;
    for s in &scenarios {
        for (what, x, y) in [
            ("start", s.start_x, s.start_y),
            ("goal", s.goal_x, s.goal_y),
        ] {
            if x >= map.width || y >= map.height {
                return Err(bad_input(format!(
                    "{}: line {}: {what} ({x}, {y}) is outside the {} × {} map",
                    args.scen.display(),
                    s.line,
                    map.width,
                    map.height
                )));
            }
        }
    }
    let planner = match args.planner {
        PlannerArg::Astar => Planner::AStar,
        PlannerArg::Dijkstra => Planner::Dijkstra,
        PlannerArg::Jps => Planner::Jps,
        PlannerArg::JpsPlus => Planner::JpsPlus,
        PlannerArg::Theta => {
            return Err(bad_input(
                "--planner theta finds any-angle paths; MovingAI lengths are octile: use jps-plus, jps, astar or dijkstra",
            ));
        }
        PlannerArg::Prm
        | PlannerArg::LazyPrm
        | PlannerArg::RrtConnect
        | PlannerArg::RrtStar
        | PlannerArg::Voxel => {
            return Err(bad_input(
                "scen replays grid scenarios: prm, rrt-connect, rrt-star and voxel are 3D planners for `skyplan plan`",
            ));
        }
        PlannerArg::Voronoi => {
            return Err(bad_input(
                "scen replays grid scenarios: voronoi is a roadmap planner for `skyplan plan` on colliders maps",
            ));
        }
        PlannerArg::Wavefront | PlannerArg::Costmap => {
            return Err(bad_input(
                "scen replays A*-family planners: use jps-plus, jps, astar or dijkstra (wavefront and costmap are for `skyplan plan`)",
            ));
        }
    };
    // JPS+ builds its table once for all scenarios (reported, not counted per query).
    let t_table = Instant::now();
    let mut jps_plus =
        (planner == Planner::JpsPlus).then(|| JpsPlus::new(&grid, MoveModel::Octile));
    let table_ms = t_table.elapsed().as_secs_f64() * 1e3;
    let progress = indicatif::ProgressBar::new(scenarios.len() as u64);
    if args.json {
        progress.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let mut search = GridSearch::new();
    let mut buckets: BTreeMap<u32, Bucket> = BTreeMap::new();
    let mut failures = Vec::new();
    for s in &scenarios {
        // MovingAI: x = column, y = row; rows are used as they are (the grid is not geo-referenced).
        let start = Cell::new(s.start_y as u32, s.start_x as u32);
        let goal = Cell::new(s.goal_y as u32, s.goal_x as u32);
        let t = Instant::now();
        let result = match jps_plus.as_mut() {
            Some(plus) => plus.search(start, goal),
            None => search.search(&grid, start, goal, MoveModel::Octile, planner),
        };
        let time_us = t.elapsed().as_secs_f64() * 1e6;
        let (cost, expansions) = match &result {
            Ok(p) => (Some(p.cost_cells()), p.expansions),
            Err(_) => (None, 0),
        };
        let ok = cost
            .is_some_and(|c| (c - s.optimal_length).abs() <= REL_TOL * s.optimal_length.max(1.0));
        let b = buckets.entry(s.bucket).or_default();
        b.count += 1;
        b.matched += u64::from(ok);
        b.total_us += time_us;
        if !ok {
            failures.push(format!(
                "line {}: cost {cost:?}, optimal {}",
                s.line, s.optimal_length
            ));
        }
        if args.json {
            println!(
                "{}",
                json!({
                    "line": s.line, "bucket": s.bucket, "cost": cost, "optimal_length": s.optimal_length,
                    "ok": ok, "time_us": time_us, "expansions": expansions,
                })
            );
        }
        progress.inc(1);
    }
    progress.finish_and_clear();
    let total: u64 = buckets.values().map(|b| b.count).sum();
    let matched: u64 = buckets.values().map(|b| b.matched).sum();
    let total_us: f64 = buckets.values().map(|b| b.total_us).sum();
    if args.json {
        println!(
            "{}",
            json!({ "summary": true, "map": args.map.display().to_string(), "scenarios": total, "matched": matched,
                    "mean_time_us": total_us / total.max(1) as f64, "planner": format!("{planner:?}"),
                    "precompute_ms": table_ms })
        );
    } else {
        let table = if jps_plus.is_some() {
            format!(" (JPS+ table built in {table_ms:.1} ms)")
        } else {
            String::new()
        };
        println!(
            "{}: {} × {} grid, {} scenarios, planner {planner:?}{table}",
            args.map.display(),
            map.width,
            map.height,
            total
        );
        println!(
            "{:>6} {:>9} {:>9} {:>14}",
            "bucket", "scenarios", "matched", "mean time µs"
        );
        for (bucket, b) in &buckets {
            println!(
                "{bucket:>6} {:>9} {:>9} {:>14.1}",
                b.count,
                b.matched,
                b.total_us / b.count as f64
            );
        }
        println!(
            "{:>6} {total:>9} {matched:>9} {:>14.1}",
            "all",
            total_us / total.max(1) as f64
        );
    }
    if matched == total {
        Ok(())
    } else {
        let shown: Vec<&str> = failures.iter().take(5).map(String::as_str).collect();
        Err(Failure {
            kind: Kind::Runtime,
            error: anyhow!(
                "{} of {total} scenarios do not match optimal_length (relative {REL_TOL}): {}",
                total - matched,
                shown.join("; ")
            ),
        })
    }
}
