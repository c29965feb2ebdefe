//! `skyplan scen`: replay MovingAI scenarios and compare each cost with `optimal_length`
//! (the replay itself is `skyplan_bench::replay`).

use crate::args::ScenArgs;
use crate::exit::{Result, bad_input};
use crate::files::read_text;
use serde_json::json;
use skyplan_bench::replay::{REL_TOL, file_order_grid, first_off_map, replay};

pub fn run(args: ScenArgs) -> Result<()> {
    let (map_name, scen_name) = (
        args.map.display().to_string(),
        args.scen.display().to_string(),
    );
    let map = skyplan_map::movingai::parse_map(&read_text(&args.map)?)
        .map_err(|e| bad_input(format!("{map_name}: {e}")))?;
    let scenarios = skyplan_map::movingai::parse_scen(&read_text(&args.scen)?)
        .map_err(|e| bad_input(format!("{scen_name}: {e}")))?;
    // MovingAI: x = column, y = row; rows are used as they are (the grid is not geo-referenced).
    let grid = file_order_grid(&map).map_err(|e| bad_input(format!("{map_name}: {e}")))?;
    if let Some(why) = first_off_map(&map, &scenarios) {
        return Err(bad_input(format!("{scen_name}: {why}")));
    }
    let progress = indicatif::ProgressBar::new(scenarios.len() as u64);
    if args.json {
        progress.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let skyplan_bench::replay::Replay {
        buckets,
        failures,
        table_ms,
    } = replay(&grid, &scenarios, args.planner, |o| {
        if args.json {
            println!("{}", json!(o));
        }
        progress.inc(1);
    })?;
    progress.finish_and_clear();
    let total: u64 = buckets.values().map(|b| b.count).sum();
    let matched: u64 = buckets.values().map(|b| b.matched).sum();
    let mean_us = buckets.values().map(|b| b.total_us).sum::<f64>() / total.max(1) as f64;
    if args.json {
        println!(
            "{}",
            json!({ "summary": true, "map": map_name, "scenarios": total, "matched": matched,
                    "mean_time_us": mean_us, "planner": args.planner, "precompute_ms": table_ms })
        );
    } else {
        let table = if args.planner == skyplan_plan::PlannerId::JpsPlus {
            format!(" (JPS+ table built in {table_ms:.1} ms)")
        } else {
            String::new()
        };
        println!(
            "{map_name}: {} × {} grid, {total} scenarios, planner {}{table}",
            map.width, map.height, args.planner
        );
        println!(
            "{:>6} {:>9} {:>9} {:>14}",
            "bucket", "scenarios", "matched", "mean time µs"
        );
        for (bucket, b) in &buckets {
            let mean = b.total_us / b.count as f64;
            println!("{bucket:>6} {:>9} {:>9} {mean:>14.1}", b.count, b.matched);
        }
        println!("{:>6} {total:>9} {matched:>9} {mean_us:>14.1}", "all");
    }
    if failures.is_empty() {
        return Ok(());
    }
    let shown: Vec<&str> = failures
        .iter()
        .take(5)
        .filter_map(|o| o.why.as_deref())
        .collect();
    Err(crate::exit::runtime(format!(
        "{} of {total} scenarios do not match optimal_length (relative {REL_TOL}): {}",
        failures.len(),
        shown.join("; ")
    )))
}
