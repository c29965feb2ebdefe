//! `skyplan scen`: replay MovingAI scenarios and compare each cost with `optimal_length`
//! (the replay itself is `skyplan_bench::replay`).

use crate::args::ScenArgs;
use crate::exit::{Result, bad_input};
use crate::files::read_text;
use serde_json::json;
use skyplan_bench::replay::{file_order_grid, first_off_map, replay};
use skyplan_bench::replay_report::ReplayOf;

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
    let replayed = replay(&grid, &scenarios, args.planner, |o| {
        if args.json {
            println!("{}", rounded(json!(o)));
        }
        progress.inc(1);
    })?;
    progress.finish_and_clear();
    let of = ReplayOf {
        map: &map_name,
        width: map.width,
        height: map.height,
        planner: args.planner,
    };
    if args.json {
        println!("{}", rounded(replayed.json_summary(&of)));
    } else {
        print!("{}", replayed.table(&of));
    }
    match replayed.mismatches() {
        Some(why) => Err(crate::exit::runtime(why)),
        None => Ok(()),
    }
}

/// The JSON lines without float noise (`5.3229999999999995`): times (`…_us`, `…_ms`) to the
/// nanosecond or microsecond they mean (3 decimals), lengths (`cost`, `optimal_length`) to 1e-9
/// (MovingAI's published lengths have 8 decimals).
fn rounded(mut v: serde_json::Value) -> serde_json::Value {
    if let Some(fields) = v.as_object_mut() {
        for (key, value) in fields.iter_mut() {
            let decimals = if key.ends_with("_us") || key.ends_with("_ms") {
                3
            } else if key == "cost" || key == "optimal_length" {
                9
            } else {
                continue;
            };
            if let Some(x) = value.as_f64().filter(|x| x.is_finite() && value.is_f64()) {
                let scale = 10f64.powi(decimals);
                *value = json!((x * scale).round() / scale);
            }
        }
    }
    v
}
