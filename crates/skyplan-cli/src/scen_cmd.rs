//! `skyplan scen`: replay MovingAI scenarios and compare each cost with `optimal_length`
//! (the replay itself is `skyplan_bench::replay`).

use crate::args::ScenArgs;
use crate::exit::{Result, bad_input};
use crate::files::Saved;
use crate::files::read_text;
use serde_json::json;
use skyplan_bench::replay::{file_order_grid, first_off_map, replay_prepared};
use skyplan_bench::replay_report::ReplayOf;
use skyplan_cspace::Grid2;
use skyplan_plan::auto::{
    MapStats, pick, pick_with_first_move_table, pick_with_hierarchy, pick_with_jps_plus_table,
    pick_with_subgoal_graph,
};
use skyplan_plan::{CellSearch, PlannerId};
use skyplan_search::{ContractionHierarchy, FirstMoveTable, JpsPlusTable, MoveModel, SubgoalGraph};
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
    // Preparing can take minutes (a contraction hierarchy of an open map, a large first-move
    // table): a spinner with the elapsed time until the scenarios start.
    let preparing = match args.json {
        true => indicatif::ProgressBar::hidden(),
        false => crate::show::spinner(format!("preparing {}", args.planner)),
    };
    let search = prepare(&args, &grid, scenarios.len() as u64, &preparing);
    preparing.finish_and_clear();
    let search = search?;
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
/// preprocessing (`--preprocess`: a contraction hierarchy, a first-move table or a JPS+ table,
/// told apart by the file's header).
fn prepare<'g>(
    args: &ScenArgs,
    grid: &'g Grid2,
    queries: u64,
    preparing: &indicatif::ProgressBar,
) -> Result<CellSearch<'g>> {
    let planner_error = |e: skyplan_plan::PlanFailure| {
        // Messages that name the planner already ("planner ch: …") are not prefixed twice.
        let own = format!("planner {}: ", args.planner);
        let why = e.message.strip_prefix(&own).unwrap_or(&e.message);
        bad_input(format!("--planner {}: {why}", args.planner))
    };
    if args.max_table.is_some()
        || (args.planner == PlannerId::FirstMove && args.preprocess.is_none())
    {
        return first_move_up_to(args, grid, preparing);
    }
    let Some(path) = &args.preprocess else {
        return CellSearch::for_queries(grid, args.planner, MoveModel::Octile, queries)
            .map_err(planner_error);
    };
    let shown = path.display();
    let t = Instant::now();
    let (input, saved) = crate::files::open_preprocess(path)?;
    let Some(kind) = saved.planner() else {
        return Err(bad_input(format!(
            "--preprocess {shown}: {}",
            crate::files::NOT_SAVED
        )));
    };
    let first_move = saved == Saved::FirstMove;
    let subgoal = saved == Saved::Subgoal;
    let stats = MapStats::of(grid);
    let auto = match (args.planner, kind) {
        (PlannerId::Auto, PlannerId::FirstMove) => {
            Some(pick_with_first_move_table(&stats, queries))
        }
        (PlannerId::Auto, PlannerId::Subgoal) => {
            let rule = pick(&stats, queries);
            // Whether the graph has labels is known once it is read: assumed here, checked below.
            let Some(p) = pick_with_subgoal_graph(&stats, queries, true) else {
                return Err(bad_input(format!(
                    "--preprocess {shown}: auto does not use a subgoal graph on this map (mean free run {:.1} cells > {}: it picks {}, {})",
                    stats.mean_run,
                    skyplan_plan::auto::SUBGOAL_KEPT_MAX_RUN,
                    rule.planner,
                    rule.why
                )));
            };
            Some(p)
        }
        (PlannerId::Auto, PlannerId::JpsPlus) => {
            let with_table = pick_with_jps_plus_table(&stats, queries, MoveModel::Octile, true);
            let Some(p) = with_table else {
                let rule = pick(&stats, queries);
                return Err(bad_input(format!(
                    "--preprocess {shown}: auto does not use a JPS+ table on this map ({}: it picks {})",
                    rule.why, rule.planner
                )));
            };
            Some(p)
        }
        (PlannerId::Auto, _) => {
            let Some(p) = pick_with_hierarchy(&stats, queries) else {
                return Err(bad_input(format!(
                    "--preprocess {shown}: auto does not use a contraction hierarchy on this map ({}: it picks {})",
                    pick(&stats, queries).why,
                    pick(&stats, queries).planner
                )));
            };
            Some(p)
        }
        (planner, kind) if planner == kind => None,
        (other, kind) => {
            let what = match kind {
                PlannerId::FirstMove => {
                    "a saved first-move table is for --planner first-move or auto"
                }
                PlannerId::JpsPlus => "a saved JPS+ table is for --planner jps-plus or auto",
                PlannerId::Subgoal => "a saved subgoal graph is for --planner subgoal or auto",
                _ => "a saved contraction hierarchy is for --planner ch or auto",
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
    if subgoal {
        let graph = SubgoalGraph::read_from(input, grid_arc)
            .map_err(|e| bad_input(format!("--preprocess {shown}: {e}")))?;
        let auto = match auto {
            Some(_) => {
                let labelled = graph.labelled();
                let Some(p) = pick_with_subgoal_graph(&stats, queries, labelled) else {
                    return Err(bad_input(format!(
                        "--preprocess {shown}: auto does not use this subgoal graph on this map: its queries would flood and search (the corners see too far for hub labels); use --planner subgoal"
                    )));
                };
                Some(p)
            }
            None => None,
        };
        return CellSearch::with_subgoal_graph(grid, Arc::new(graph), us(t), auto)
            .map_err(planner_error);
    }
    if kind == PlannerId::JpsPlus {
        let table = JpsPlusTable::read_from(input, grid_arc)
            .map_err(|e| bad_input(format!("--preprocess {shown}: {e}")))?;
        if table.model() != MoveModel::Octile {
            return Err(bad_input(format!(
                "--preprocess {shown}: the JPS+ table was built with corner cutting; MovingAI scenarios are without"
            )));
        }
        // Said with or without landmarks, as the file holds them.
        let landmarks = table.landmarks().is_some();
        let auto = auto
            .and_then(|_| pick_with_jps_plus_table(&stats, queries, MoveModel::Octile, landmarks));
        return CellSearch::with_jps_plus_table(grid, Arc::new(table), us(t), auto)
            .map_err(planner_error);
    }
    let ch = ContractionHierarchy::read_from(input, grid_arc, MoveModel::Octile)
        .map_err(|e| bad_input(format!("--preprocess {shown}: {e}")))?;
    CellSearch::with_hierarchy(grid, Arc::new(ch), us(t), auto).map_err(planner_error)
}

/// `--planner first-move [--max-table SIZE]`: a first-move table of up to SIZE (by default the
/// planner's own cap, 64 MiB) and at most half the machine's memory, built here; a large one is
/// announced (its size and searches) before the build.
fn first_move_up_to<'g>(
    args: &ScenArgs,
    grid: &'g Grid2,
    preparing: &indicatif::ProgressBar,
) -> Result<CellSearch<'g>> {
    if args.planner != PlannerId::FirstMove {
        return Err(bad_input(format!(
            "--max-table is the largest first-move table to build; it needs --planner first-move, not {}",
            args.planner
        )));
    }
    let free = grid.len() - grid.blocked_count();
    let bytes = FirstMoveTable::bytes_for(grid.len(), free);
    let memory = crate::args::limits(None).max_memory_bytes;
    let human = skyplan_plan::human_bytes;
    let max_bytes = match args.max_table {
        Some(max) if bytes <= max && bytes > memory => {
            return Err(bad_input(format!(
                "--max-table {}: this grid's first-move table takes {}, more than half this machine's memory ({})",
                human(max),
                human(bytes),
                human(memory)
            )));
        }
        Some(max) => max,
        None => skyplan_plan::auto::FIRST_MOVE_MAX_BYTES,
    };
    if !args.json && bytes <= max_bytes && bytes > skyplan_plan::auto::FIRST_MOVE_MAX_BYTES {
        // The spinner's message on a terminal; a line of its own in a log.
        let building = format!(
            "building a first-move table of {} ({free} exact searches, one per free cell)",
            human(bytes)
        );
        if preparing.is_hidden() {
            eprintln!("{building}…");
        } else {
            preparing.set_message(building);
        }
    }
    let t = Instant::now();
    let table = FirstMoveTable::build(Arc::new(grid.clone()), MoveModel::Octile, max_bytes)
        .map_err(|e| match args.max_table {
            Some(_) => bad_input(format!("--planner first-move --max-table: {e}")),
            None if bytes <= memory => bad_input(format!(
                "--planner first-move: {e}; --max-table {}M builds it where memory allows",
                bytes.div_ceil(1 << 20)
            )),
            None => bad_input(format!("--planner first-move: {e}")),
        })?;
    let us = u64::try_from(t.elapsed().as_micros()).unwrap_or(u64::MAX);
    CellSearch::with_first_move_table(grid, Arc::new(table), us, None)
        .map_err(|e| bad_input(format!("--planner first-move: {}", e.message)))
}

/// Writes the search's preprocessing (a contraction hierarchy, a subgoal graph, a first-move
/// table, or a JPS+
/// table with landmarks added for the later runs) to `path` atomically (a failed save leaves
/// no partial file); refused when the search has none.
fn save_preprocessing(path: &Path, search: &CellSearch<'_>, json: bool) -> Result<()> {
    let built_ms = search.precompute_us() as f64 / 1e3;
    let mut landmarks = String::new();
    let (what, mb) = if let Some(ch) = search.hierarchy() {
        crate::files::write_atomic_with(path, |out| {
            ch.write_to(out).map_err(std::io::Error::other)
        })?;
        ("contraction hierarchy", ch.file_bytes() as f64 / 1e6)
    } else if let Some(graph) = search.subgoal_graph() {
        crate::files::write_atomic_with(path, |out| {
            graph.write_to(out).map_err(std::io::Error::other)
        })?;
        ("subgoal graph", graph.file_bytes() as f64 / 1e6)
    } else if let Some(table) = search.first_move_table() {
        crate::files::write_atomic_with(path, |out| {
            table.write_to(out).map_err(std::io::Error::other)
        })?;
        ("first-move table", table.file_bytes() as f64 / 1e6)
    } else if let Some(table) = search.jps_plus_table() {
        let t = std::time::Instant::now();
        let count = table
            .add_landmarks(skyplan_search::landmarks_for(table.grid().len()))
            .cells()
            .len();
        let ms = t.elapsed().as_secs_f64() * 1e3;
        crate::files::write_atomic_with(path, |out| table.write_to(out, [f64::NAN; 3]))?;
        landmarks = format!(", {count} landmarks in {ms:.0} ms");
        ("JPS+ table with landmarks", table.file_bytes() as f64 / 1e6)
    } else {
        let what = match search.auto_pick() {
            Some(p) => format!("auto picked {} ({})", p.planner, p.why),
            None => "the planner builds none".to_string(),
        };
        return Err(bad_input(format!(
            "--save-preprocess {}: no contraction hierarchy, subgoal graph, first-move or JPS+ table to save: {what}; use --planner ch, subgoal, first-move or jps-plus",
            path.display()
        )));
    };
    if !json {
        eprintln!(
            "saved    {what} ({mb:.1} MB, built in {built_ms:.0} ms{landmarks}) to {}",
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
