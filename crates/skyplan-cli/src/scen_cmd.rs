//! `skyplan scen`: replay MovingAI scenarios and compare each cost with `optimal_length`
//! (the replay itself is `skyplan_bench::replay`).

use crate::args::ScenArgs;
use crate::exit::{Result, bad_input};
use crate::files::read_text;
use serde_json::json;
use skyplan_bench::replay::{file_order_grid, first_off_map, replay_prepared};
use skyplan_bench::replay_report::ReplayOf;
use skyplan_cspace::Grid2;
use skyplan_plan::auto::{MapStats, pick, pick_with_first_move_table, pick_with_hierarchy};
use skyplan_plan::{CellSearch, PlannerId};
use skyplan_search::{ContractionHierarchy, FirstMoveTable, MoveModel};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

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
    if let Some(path) = &args.save_preprocess {
        crate::files::output_target("--save-preprocess", path)?;
    }
    let progress = indicatif::ProgressBar::new(scenarios.len() as u64);
    if args.json {
        progress.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let search = prepare(&args, &grid, scenarios.len() as u64)?;
    if let Some(path) = &args.save_preprocess {
        save_preprocessing(path, &search, args.json)?;
    }
    let replayed = replay_prepared(&grid, search, &scenarios, |o| {
        if args.json {
            println!("{}", rounded(json!(o)));
        }
        progress.inc(1);
    });
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

/// The search for `queries` scenarios: the planner (auto picking for that many), or saved
/// preprocessing (`--preprocess`: a contraction hierarchy or a first-move table, told apart by
/// the file's header).
fn prepare<'g>(args: &ScenArgs, grid: &'g Grid2, queries: u64) -> Result<CellSearch<'g>> {
    let planner_error = |e: skyplan_plan::PlanFailure| {
        // Messages that name the planner already ("planner ch: …") are not prefixed twice.
        let own = format!("planner {}: ", args.planner);
        let why = e.message.strip_prefix(&own).unwrap_or(&e.message);
        bad_input(format!("--planner {}: {why}", args.planner))
    };
    let Some(path) = &args.preprocess else {
        return CellSearch::for_queries(grid, args.planner, MoveModel::Octile, queries)
            .map_err(planner_error);
    };
    let shown = path.display();
    let t = Instant::now();
    let (input, first_move) = crate::files::open_preprocess(path)?;
    let stats = MapStats::of(grid);
    let auto = match (args.planner, first_move) {
        (PlannerId::Auto, true) => Some(pick_with_first_move_table(&stats, queries)),
        (PlannerId::Auto, false) => {
            let Some(p) = pick_with_hierarchy(&stats, queries) else {
                return Err(bad_input(format!(
                    "--preprocess {shown}: auto does not use a contraction hierarchy on this map ({}: it picks {})",
                    pick(&stats, queries).why,
                    pick(&stats, queries).planner
                )));
            };
            Some(p)
        }
        (PlannerId::FirstMove, true) | (PlannerId::Ch, false) => None,
        (other, _) => {
            let what = if first_move {
                "a saved first-move table is for --planner first-move or auto"
            } else {
                "a saved contraction hierarchy is for --planner ch or auto"
            };
            return Err(bad_input(format!(
                "--preprocess {shown}: {what}, not {other}"
            )));
        }
    };
    let grid_arc = Arc::new(grid.clone());
    let us = |t: Instant| u64::try_from(t.elapsed().as_micros()).unwrap_or(u64::MAX);
    if first_move {
        let table = FirstMoveTable::read_from(input, grid_arc, MoveModel::Octile)
            .map_err(|e| bad_input(format!("--preprocess {shown}: {e}")))?;
        return CellSearch::with_first_move_table(grid, Arc::new(table), us(t), auto)
            .map_err(planner_error);
    }
    let ch = ContractionHierarchy::read_from(input, grid_arc, MoveModel::Octile)
        .map_err(|e| bad_input(format!("--preprocess {shown}: {e}")))?;
    CellSearch::with_hierarchy(grid, Arc::new(ch), us(t), auto).map_err(planner_error)
}

/// Writes the search's preprocessing (a contraction hierarchy or a first-move table) to `path`
/// atomically (a failed save leaves no partial file); refused when the search has none.
fn save_preprocessing(path: &Path, search: &CellSearch<'_>, json: bool) -> Result<()> {
    let built_ms = search.precompute_us() as f64 / 1e3;
    let (what, mb) = if let Some(ch) = search.hierarchy() {
        crate::files::write_atomic_with(path, |out| {
            ch.write_to(out).map_err(std::io::Error::other)
        })?;
        ("contraction hierarchy", ch.file_bytes() as f64 / 1e6)
    } else if let Some(table) = search.first_move_table() {
        crate::files::write_atomic_with(path, |out| {
            table.write_to(out).map_err(std::io::Error::other)
        })?;
        ("first-move table", table.file_bytes() as f64 / 1e6)
    } else {
        let what = match search.auto_pick() {
            Some(p) => format!("auto picked {} ({})", p.planner, p.why),
            None => "the planner builds none".to_string(),
        };
        return Err(bad_input(format!(
            "--save-preprocess {}: no contraction hierarchy or first-move table to save: {what}; use --planner ch or first-move",
            path.display()
        )));
    };
    if !json {
        eprintln!(
            "saved    {what} ({mb:.1} MB, built in {built_ms:.0} ms) to {}",
            path.display()
        );
    }
    Ok(())
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
