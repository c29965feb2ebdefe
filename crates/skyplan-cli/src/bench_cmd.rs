//! `skyplan bench`: every planner on the same queries, a table of times and costs, and the
//! peers people use instead (the Rust `pathfinding` crate; Python A\*s with `--peers`). The runs
//! are `skyplan_bench::grid_bench`'s; this reads the files, prints and writes.

use crate::args::BenchArgs;
use crate::exit::{Classify, Failure, Kind, Result, bad_input, runtime};
use crate::files::{map_text, read_text, write_atomic};
use anyhow::Context;
use skyplan_bench::Contender;
use skyplan_bench::grid_bench::{self, JpsPlusPrep, QuerySource, RunAllError};
use skyplan_plan::{PlanRequest, PlannerId};
use skyplan_search::MoveModel;
use std::path::Path;
use std::time::Instant;

/// How `bench` names the bundled map.
pub(crate) const BUNDLED_NAME: &str = "FCND city map (bundled)";

fn is_movingai(args: &BenchArgs) -> bool {
    args.map
        .as_ref()
        .is_some_and(|p| p.extension().is_some_and(|e| e == "map"))
}

/// The grid's values as a table file's record of how it was built (`NaN` for a MovingAI map).
fn table_spec(args: &BenchArgs) -> Result<[f64; 3]> {
    if is_movingai(args) {
        Ok([f64::NAN; 3])
    } else {
        let s = args.slice.spec()?;
        Ok([s.alt_m, s.safety_m, s.cell_m])
    }
}

pub fn run_bench(args: BenchArgs) -> Result<()> {
    if let Some(flights) = args.fleet {
        return crate::fleet_cmd::bench(&args, flights as usize);
    }
    if let Some(flights) = args.replan {
        return replan_bench(&args, flights);
    }
    if args.three_d {
        return crate::bench3d_cmd::run(args);
    }
    if args.trajectory {
        return crate::bench_traj_cmd::run(&args);
    }
    if args.random == Some(0) {
        return Err(bad_input("--random 0: expected at least 1 query"));
    }
    if let Some(out) = &args.out
        && !out.extension().is_some_and(|e| e == "csv" || e == "json")
    {
        return Err(bad_input(format!(
            "--out {}: expected a .csv or .json file name",
            out.display()
        )));
    }
    if let Some(out) = &args.out {
        crate::files::output_target("--out", out)?;
    }
    let spec = PlanRequest {
        corner_cutting: args.corner_cutting.then_some(true),
        ..args.slice.request()
    }
    .spec()?;
    let model = spec.move_model;
    let planners = grid_bench::contenders(args.planners.as_deref(), is_movingai(&args), args.peers)
        .map_err(bad_input)?;
    let (name, text) = map_text(args.map.as_deref(), BUNDLED_NAME)?;
    let source = grid_bench::load_grid(&name, &text, is_movingai(&args), spec.grid_spec())
        .map_err(bad_input)?;
    let grid = &source.grid;
    let (queries, described) = queries(&args, grid, model)?;
    let target = match args.json {
        true => indicatif::ProgressDrawTarget::hidden(),
        false => indicatif::ProgressDrawTarget::stderr(),
    };
    let steps = Some((planners.len() * queries.len()) as u64);
    let progress = crate::show::progress("{msg:>24} [{bar:40}] {pos}/{len} queries", steps, target);
    let (first_move, hierarchy, subgoal) = loaded_preprocessing(&args, grid, model)?;
    let jps_plus = if first_move.is_some() || hierarchy.is_some() || subgoal.is_some() {
        JpsPlusPrep::Build
    } else {
        jps_plus_prep(&args, grid, model, &planners)?
    };
    let mut runs = grid_bench::run_all(
        grid,
        model,
        &planners,
        &queries,
        grid_bench::Preprocessing {
            jps_plus,
            first_move,
            hierarchy,
            subgoal,
        },
        |planner| progress.set_message(planner.name()),
        || progress.inc(1),
    )
    .map_err(|e| match (e, &args.preprocess) {
        (RunAllError::Table(e), Some(path)) => {
            bad_input(format!("--preprocess {}: {e}", path.display()))
        }
        (RunAllError::Refused(e), _) => bad_input(format!("--planners: {e}")),
        (e, _) => runtime(e),
    })?;
    progress.finish_and_clear();
    let mut notes = Vec::new();
    if args.peers {
        if !args.json {
            eprintln!(
                "running the Python peers (budget {} s each)…",
                args.peer_budget_s
            );
        }
        let (py_runs, py_notes) =
            skyplan_bench::python_peers::grid_peers(grid, &queries, model, args.peer_budget_s);
        runs.extend(py_runs);
        notes.extend(py_notes);
    }
    let report = grid_bench::Report::new(&source, &described, model, &runs, queries.len(), notes);
    if let Some(out) = &args.out {
        let json = out.extension().is_some_and(|e| e == "json");
        let bytes =
            grid_bench::records_bytes(json, &source.name, &described, &runs).map_err(runtime)?;
        write_atomic(out, &bytes)?;
    }
    if args.json {
        println!("{}", report.json());
        return Ok(());
    }
    print!("{report}");
    if let Some(out) = &args.out {
        println!("wrote    {}", out.display());
    }
    Ok(())
}

/// The queries of `--scen FILE` (read here), or `--random` ones, and how they were drawn.
fn queries(
    args: &BenchArgs,
    grid: &skyplan_cspace::Grid2,
    model: MoveModel,
) -> Result<(Vec<(skyplan_cspace::Cell, skyplan_cspace::Cell)>, String)> {
    let scen = (args.scen.as_ref())
        .map(|path| Ok::<_, Failure>((path.display().to_string(), read_text(path)?)))
        .transpose()?;
    let from = match &scen {
        Some((name, text)) => QuerySource::Scen(name, text, args.random),
        None => QuerySource::Random {
            count: args.random.unwrap_or(26),
            seed: args.seed,
            min_distance_m: args.min_distance_m,
        },
    };
    grid_bench::queries(grid, model, from).map_err(bad_input)
}

/// Preprocessing loaded from a file, and the load's time, µs.
type Loaded<T> = Option<(std::sync::Arc<T>, u64)>;

/// A first-move table and its load time (µs), for `first-move` and `auto`, or a contraction
/// hierarchy and its load time, for `ch` and `auto`, given by `--preprocess` (saved by `scen`
/// or `plan --save-preprocess`; told apart from each other and from a JPS+ table by the
/// header). Neither for a JPS+ table, which [`jps_plus_prep`] streams when JPS+ runs.
fn loaded_preprocessing(
    args: &BenchArgs,
    grid: &std::sync::Arc<skyplan_cspace::Grid2>,
    model: MoveModel,
) -> Result<(
    Loaded<skyplan_search::FirstMoveTable>,
    Loaded<skyplan_search::ContractionHierarchy>,
    Loaded<skyplan_search::SubgoalGraph>,
)> {
    let Some(path) = &args.preprocess else {
        return Ok((None, None, None));
    };
    let t = Instant::now();
    let (input, kind) = crate::files::open_preprocess(path)?;
    let damaged =
        |e: &dyn std::fmt::Display| bad_input(format!("--preprocess {}: {e}", path.display()));
    let grid = std::sync::Arc::clone(grid);
    let us = || u64::try_from(t.elapsed().as_micros()).unwrap_or(u64::MAX);
    Ok(match kind {
        crate::files::Saved::FirstMove => {
            let table = skyplan_search::FirstMoveTable::read_from(input, grid, model)
                .map_err(|e| damaged(&e))?;
            (Some((std::sync::Arc::new(table), us())), None, None)
        }
        crate::files::Saved::Hierarchy => {
            let ch = skyplan_search::ContractionHierarchy::read_from(input, grid, model)
                .map_err(|e| damaged(&e))?;
            (None, Some((std::sync::Arc::new(ch), us())), None)
        }
        crate::files::Saved::Subgoal => {
            if model != MoveModel::Octile {
                return Err(bad_input(format!(
                    "--preprocess {}: a subgoal graph is for 8-connected moves without corner cutting, not with --corner-cutting",
                    path.display()
                )));
            }
            let graph =
                skyplan_search::SubgoalGraph::read_from(input, grid).map_err(|e| damaged(&e))?;
            (None, None, Some((std::sync::Arc::new(graph), us())))
        }
        crate::files::Saved::JpsPlus | crate::files::Saved::Unknown => (None, None, None),
    })
}

/// How JPS+ gets its table: built here and saved (`--save-preprocess`), streamed from a file
/// (`--preprocess`, opened only when JPS+ runs), or built by itself.
fn jps_plus_prep(
    args: &BenchArgs,
    grid: &std::sync::Arc<skyplan_cspace::Grid2>,
    model: MoveModel,
    planners: &[Contender],
) -> Result<JpsPlusPrep<std::fs::File>> {
    if let Some(path) = &args.save_preprocess {
        let (table, us) = save_table(path, grid, model, args)?;
        return Ok(JpsPlusPrep::Built(table, us));
    }
    match &args.preprocess {
        // `auto` uses a loaded table too: load it once for both.
        Some(path) if planners.contains(&Contender::Skyplan(PlannerId::Auto)) => {
            let t = Instant::now();
            let (input, _) = crate::files::open_preprocess(path)?;
            let table = grid_bench::load_jps_plus_table(input, grid, model)
                .map_err(|e| bad_input(format!("--preprocess {}: {e}", path.display())))?;
            let us = u64::try_from(t.elapsed().as_micros()).unwrap_or(u64::MAX);
            Ok(JpsPlusPrep::Loaded(std::sync::Arc::new(table), us))
        }
        Some(path) if planners.contains(&Contender::Skyplan(PlannerId::JpsPlus)) => {
            let file = std::fs::File::open(path)
                .with_context(|| format!("--preprocess {}: cannot open", path.display()))
                .or_exit(Kind::BadInput)?;
            Ok(JpsPlusPrep::File(file))
        }
        _ => Ok(JpsPlusPrep::Build),
    }
}

/// Builds the JPS+ table of `grid` and streams it to `path` atomically (a failed save leaves no
/// partial table); the table and its build time (µs).
fn save_table(
    path: &Path,
    grid: &std::sync::Arc<skyplan_cspace::Grid2>,
    model: MoveModel,
    args: &BenchArgs,
) -> Result<(skyplan_search::JpsPlusTable, u64)> {
    let (table, built_us) = grid_bench::build_jps_plus_table(grid, model);
    // A saved table serves many later queries: it keeps landmarks for them.
    let count = skyplan_search::landmarks_for(grid.len());
    if !args.json {
        eprintln!(
            "building {count} landmarks (one Dijkstra over the grid each) for the saved JPS+ table…"
        );
    }
    let t = Instant::now();
    let kept = table.add_landmarks(count).cells().len();
    let landmarks_us = u64::try_from(t.elapsed().as_micros()).unwrap_or(u64::MAX);
    let t = Instant::now();
    let spec = table_spec(args)?;
    crate::files::write_atomic_with(path, |out| table.write_to(out, spec))?;
    if !args.json {
        eprintln!(
            "saved    JPS+ table with {kept} landmarks ({:.1} MB, built in {:.0} ms + {:.0} ms for the landmarks, written in {:.0} ms) to {}",
            table.file_bytes() as f64 / 1e6,
            built_us as f64 / 1e3,
            landmarks_us as f64 / 1e3,
            t.elapsed().as_secs_f64() * 1e3,
            path.display()
        );
    }
    Ok((table, built_us.saturating_add(landmarks_us)))
}

/// `bench --replan N`: seeded flights into hidden buildings, one row per replanner.
fn replan_bench(args: &BenchArgs, flights: usize) -> Result<()> {
    if flights == 0 {
        return Err(bad_input("--replan 0: expected at least 1 flight"));
    }
    let limits = skyplan_plan::Limits::default();
    let world =
        crate::world_load::load_world(args.map.as_deref(), &Default::default(), 1, &limits)?;
    let slice = args.slice.spec()?;
    let spec = skyplan_replan::bench::ScenarioSpec {
        flights,
        seed: args.seed,
        hidden: args.hidden_random,
        alt_m: slice.alt_m,
        safety_m: slice.safety_m,
        min_distance_m: args.min_distance_m.unwrap_or(300.0),
    };
    print!("{}", crate::replan_cmd::bench(&world, &spec, 50.0)?);
    Ok(())
}
