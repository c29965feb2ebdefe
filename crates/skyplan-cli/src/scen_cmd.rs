//! `skyplan scen`: replay MovingAI scenarios and compare each cost with `optimal_length`.

use crate::args::ScenArgs;
use crate::exit::{Result, bad_input};
use crate::files::read_text;
use serde_json::json;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_search::MoveModel;
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
    // JPS+ builds its table once for all scenarios (reported, not counted per query).
    let mut search = skyplan_plan::CellSearch::new(&grid, args.planner, MoveModel::Octile)?;
    let table_ms = search.precompute_us() as f64 / 1e3;
    let progress = indicatif::ProgressBar::new(scenarios.len() as u64);
    if args.json {
        progress.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let mut buckets: BTreeMap<u32, Bucket> = BTreeMap::new();
    let mut failures = Vec::new();
    for s in &scenarios {
        // MovingAI: x = column, y = row; rows are used as they are (the grid is not geo-referenced).
        let start = Cell::new(s.start_y as u32, s.start_x as u32);
        let goal = Cell::new(s.goal_y as u32, s.goal_x as u32);
        let t = Instant::now();
        let result = search.search(start, goal);
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
            let found = match cost {
                Some(c) => format!("found {c:.8}"),
                None if grid.is_blocked(start) || grid.is_blocked(goal) => {
                    "no path: the start or goal is on a blocked cell".to_string()
                }
                None => "no path found".to_string(),
            };
            failures.push(format!(
                "line {}: {found}, optimal {}",
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
                    "mean_time_us": total_us / total.max(1) as f64, "planner": args.planner,
                    "precompute_ms": table_ms })
        );
    } else {
        let table = if args.planner == skyplan_plan::PlannerId::JpsPlus {
            format!(" (JPS+ table built in {table_ms:.1} ms)")
        } else {
            String::new()
        };
        println!(
            "{}: {} × {} grid, {} scenarios, planner {}{table}",
            args.map.display(),
            map.width,
            map.height,
            total,
            args.planner
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
        Err(crate::exit::runtime(format!(
            "{} of {total} scenarios do not match optimal_length (relative {REL_TOL}): {}",
            total - matched,
            shown.join("; ")
        )))
    }
}
