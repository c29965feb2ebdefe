//! `skyplan bench`: every planner on the same queries, a table of times and costs, and the
//! peers people use instead (the Rust `pathfinding` crate; Python A\*s with `--peers`).

use crate::args::BenchArgs;
use crate::exit::{Classify, Kind, Result, bad_input};
use crate::files::{read_bytes, read_text, write_atomic};
use anyhow::Context;
use serde_json::json;
use skyplan_bench::{Contender, Record, Run, random_far_queries, run, run_prepared};
use skyplan_cspace::{Cell, Grid2, GridSpec};
use skyplan_plan::{CellSearch, FCND_CITY_CSV as BUNDLED_COLLIDERS, PlannerId};
use skyplan_search::{JpsPlusTable, MoveModel};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use std::time::Instant;

/// The Python peers script, compiled in so that `bench --peers` works from any directory.
const PEERS_PY: &str = include_str!("../../../bench/peers.py");

struct Source {
    name: String,
    grid: Grid2,
}

fn load(args: &BenchArgs) -> Result<Source> {
    let spec = GridSpec {
        alt_m: args.alt_m,
        safety_m: args.safety_m,
        cell_m: args.cell_m,
    };
    match &args.map {
        Some(path) if path.extension().is_some_and(|e| e == "map") => {
            let text = read_text(path)?;
            let map = skyplan_map::movingai::parse_map(&text)
                .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
            let grid = skyplan_bench::replay::file_order_grid(&map)
                .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
            Ok(Source {
                name: path.display().to_string(),
                grid,
            })
        }
        other => {
            let (name, text) = match other {
                Some(path) => (path.display().to_string(), read_text(path)?),
                None => (
                    "FCND city map (bundled)".to_string(),
                    BUNDLED_COLLIDERS.to_string(),
                ),
            };
            let map = skyplan_map::colliders::parse_colliders(&text)
                .map_err(|e| bad_input(format!("{name}: {e}")))?;
            let grid =
                Grid2::from_colliders(&map, spec).map_err(|e| bad_input(format!("{name}: {e}")))?;
            Ok(Source {
                name: format!("{name} at {} m, {} m margin", spec.alt_m, spec.safety_m),
                grid,
            })
        }
    }
}

fn queries(
    args: &BenchArgs,
    grid: &Grid2,
    model: MoveModel,
) -> Result<(Vec<(Cell, Cell)>, String)> {
    if let Some(scen) = &args.scen {
        let text = read_text(scen)?;
        let list = skyplan_map::movingai::parse_scen(&text)
            .map_err(|e| bad_input(format!("{}: {e}", scen.display())))?;
        let mut out = Vec::new();
        for s in list.iter().take(args.random.unwrap_or(usize::MAX)) {
            let (a, b) = (
                Cell::new(s.start_y as u32, s.start_x as u32),
                Cell::new(s.goal_y as u32, s.goal_x as u32),
            );
            if !grid.contains(a) || !grid.contains(b) {
                return Err(bad_input(format!(
                    "{}: line {}: a scenario endpoint is off the map",
                    scen.display(),
                    s.line
                )));
            }
            out.push((a, b));
        }
        return Ok((out, format!("scenarios of {}", scen.display())));
    }
    let count = args.random.unwrap_or(26);
    let diagonal = f64::from(grid.rows()).hypot(f64::from(grid.cols()));
    let min_cells = args
        .min_distance_m
        .map_or(0.5 * diagonal, |m| m / grid.frame().cell_m);
    let q = random_far_queries(grid, model, count, args.seed, min_cells);
    if q.len() < count {
        return Err(bad_input(
            "the map has fewer than two connected free cells to draw queries from",
        ));
    }
    Ok((
        q,
        format!(
            "{count} random queries (seed {}) ≥ {min_cells:.0} cells apart",
            args.seed
        ),
    ))
}

pub(crate) fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("SKYPLAN_PYTHON") {
        return PathBuf::from(p);
    }
    let candidates = [
        PathBuf::from("bench/.venv/bin/python"),
        PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../bench/.venv/bin/python"
        )),
    ];
    candidates
        .into_iter()
        .find(|p| p.exists())
        .unwrap_or_else(|| PathBuf::from("python3"))
}

/// Runs the Python peers on the same grid and queries; returns their runs and any notes.
fn python_peers(
    grid: &Grid2,
    queries: &[(Cell, Cell)],
    model: MoveModel,
    budget_s: f64,
) -> (Vec<Run>, Vec<String>) {
    let dir = match tempfile_dir() {
        Ok(d) => d,
        Err(e) => return (Vec::new(), vec![format!("python peers skipped: {e:#}")]),
    };
    let grid_bytes: Vec<u8> = grid.blocked_cells().iter().map(|&b| u8::from(b)).collect();
    let q: Vec<[u32; 4]> = queries
        .iter()
        .map(|(a, b)| [a.row, a.col, b.row, b.col])
        .collect();
    let written = std::fs::write(dir.join("grid.bin"), grid_bytes)
        .and_then(|_| std::fs::write(dir.join("queries.json"), json!(q).to_string()))
        .and_then(|_| std::fs::write(dir.join("peers.py"), PEERS_PY));
    if let Err(e) = written {
        return (Vec::new(), vec![format!("python peers skipped: {e}")]);
    }
    let py = python();
    let model_name = if model == MoveModel::OctileCornerCutting {
        "octile-cc"
    } else {
        "octile"
    };
    let output = Command::new(&py)
        .arg(dir.join("peers.py"))
        .arg(dir.join("grid.bin"))
        .arg(grid.rows().to_string())
        .arg(grid.cols().to_string())
        .arg(dir.join("queries.json"))
        .arg(model_name)
        .arg(budget_s.to_string())
        .output();
    let _ = std::fs::remove_dir_all(&dir);
    let output = match output {
        Ok(o) if o.status.success() => o,
        Ok(o) => {
            let err = String::from_utf8_lossy(&o.stderr);
            return (
                Vec::new(),
                vec![format!(
                    "python peers failed ({}): {}",
                    py.display(),
                    err.trim()
                )],
            );
        }
        Err(e) => {
            return (
                Vec::new(),
                vec![format!(
                    "python peers skipped: cannot run {}: {e}",
                    py.display()
                )],
            );
        }
    };
    let (runs, notes) = skyplan_bench::parse_peer_lines(&String::from_utf8_lossy(&output.stdout));
    (runs, notes)
}

fn tempfile_dir() -> anyhow::Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("skyplan-peers-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    Ok(dir)
}

/// The planners of `--planners` (or [`skyplan_bench::default_contenders`]: (ch on MovingAI maps,) jps-plus, jps, astar, and the Rust peer with `--peers`).
fn contenders(args: &BenchArgs) -> Result<Vec<Contender>> {
    Ok(match &args.planners {
        Some(list) => list
            .split(',')
            .map(|n| {
                Contender::from_name(n.trim()).ok_or_else(|| {
                    bad_input(format!(
                        "--planners: unknown planner {n:?}; expected some of ch, jps-plus, jps, astar, dijkstra, theta, rust-pathfinding-astar"
                    ))
                })
            })
            .collect::<Result<_>>()?,
        None => {
            let movingai = args
                .map
                .as_ref()
                .is_some_and(|p| p.extension().is_some_and(|e| e == "map"));
            skyplan_bench::default_contenders(movingai, args.peers)
        }
    })
}

/// Every record (planner, query, time, expansions, cost) to a .csv or .json file.
fn write_records(out: &std::path::Path, map: &str, described: &str, runs: &[Run]) -> Result<()> {
    let records: Vec<&Record> = runs.iter().flat_map(|r| &r.records).collect();
    let bytes = if out.extension().is_some_and(|e| e == "json") {
        serde_json::to_vec_pretty(&json!({ "map": map, "queries": described, "records": records }))
            .or_exit(Kind::Runtime)?
    } else {
        let mut w = csv::Writer::from_writer(Vec::new());
        for r in &records {
            w.serialize(r).or_exit(Kind::Runtime)?;
        }
        w.into_inner()
            .map_err(|e| anyhow::anyhow!("{e}"))
            .or_exit(Kind::Runtime)?
    };
    write_atomic(out, &bytes)
}

/// Resets the process's peak resident set (Linux: `5` to /proc/self/clear_refs), so that VmHWM
/// then measures one planner; false where that is not possible.
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// VmHWM of /proc/self/status (the peak resident set since the last reset), bytes.
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

/// The grid's values as a table file's record of how it was built (`NaN` for a MovingAI map).
fn table_spec(args: &BenchArgs) -> [f64; 3] {
    match &args.map {
        Some(path) if path.extension().is_some_and(|e| e == "map") => [f64::NAN; 3],
        _ => [args.alt_m, args.safety_m, args.cell_m],
    }
}

/// Builds the JPS+ table of `grid` and writes it to `path`.
fn save_table(path: &Path, grid: &Grid2, model: MoveModel, args: &BenchArgs) -> Result<()> {
    let t = Instant::now();
    let table = JpsPlusTable::build(Arc::new(grid.clone()), model);
    let bytes = table.to_bytes(table_spec(args));
    write_atomic(path, &bytes)?;
    if !args.json {
        eprintln!(
            "saved    JPS+ table ({:.1} MB, built in {:.0} ms) to {}",
            bytes.len() as f64 / 1e6,
            t.elapsed().as_secs_f64() * 1e3,
            path.display()
        );
    }
    Ok(())
}

/// JPS+ prepared from the table in `path` (the load time is its preparation time).
fn load_table<'g>(path: &Path, grid: &'g Grid2, model: MoveModel) -> Result<CellSearch<'g>> {
    let t = Instant::now();
    let bytes = read_bytes(path)?;
    let table = JpsPlusTable::from_bytes(&bytes, Arc::new(grid.clone())).map_err(|e| {
        bad_input(format!(
            "--preprocess {}: {e}; rebuild it with --save-preprocess",
            path.display()
        ))
    })?;
    let rule = |m: MoveModel| {
        if m == MoveModel::OctileCornerCutting {
            "with corner cutting (--corner-cutting)"
        } else {
            "without corner cutting"
        }
    };
    if table.model() != model {
        return Err(bad_input(format!(
            "--preprocess {}: the JPS+ table was built {}; this run is {}",
            path.display(),
            rule(table.model()),
            rule(model)
        )));
    }
    let us = u64::try_from(t.elapsed().as_micros()).unwrap_or(u64::MAX);
    CellSearch::with_jps_plus_table(grid, Arc::new(table), us)
        .map_err(|e| bad_input(format!("--preprocess {}: {e}", path.display())))
}

pub fn run_bench(args: BenchArgs) -> Result<()> {
    if let Some(flights) = args.replan {
        return replan_bench(&args, flights);
    }
    if args.three_d {
        return crate::bench3d_cmd::run(args);
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
    let model = if args.corner_cutting {
        MoveModel::OctileCornerCutting
    } else {
        MoveModel::Octile
    };
    let planners = contenders(&args)?;
    let source = load(&args)?;
    let grid = &source.grid;
    let (queries, described) = queries(&args, grid, model)?;
    let cell_m = grid.frame().cell_m;

    let progress = indicatif::ProgressBar::new((planners.len() * queries.len()) as u64);
    progress.set_style(
        indicatif::ProgressStyle::with_template("{msg:>24} [{bar:40}] {pos}/{len} queries")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    if args.json {
        progress.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    if let Some(path) = &args.save_preprocess {
        save_table(path, grid, model, &args)?;
    }
    let mut runs: Vec<Run> = Vec::new();
    for &planner in &planners {
        progress.set_message(planner.name());
        let measured = reset_peak_rss();
        let mut r = match (&args.preprocess, planner) {
            (Some(path), Contender::Skyplan(PlannerId::JpsPlus)) => {
                let engine = load_table(path, grid, model)?;
                run_prepared(grid, model, planner, Some(engine), &queries, |_| {
                    progress.inc(1)
                })
            }
            _ => run(grid, model, planner, &queries, |_| progress.inc(1)),
        };
        r.peak_rss_bytes = measured.then(peak_rss_bytes).flatten();
        runs.push(r);
    }
    progress.finish_and_clear();
    let mut notes = Vec::new();
    if args.peers {
        if !args.json {
            eprintln!(
                "running the Python peers (budget {} s each)…",
                args.peer_budget_s
            );
        }
        let (py_runs, py_notes) = python_peers(grid, &queries, model, args.peer_budget_s);
        runs.extend(py_runs);
        notes.extend(py_notes);
    }

    let rows = skyplan_bench::table(&runs, queries.len(), cell_m);

    if let Some(out) = &args.out {
        write_records(out, &source.name, &described, &runs)?;
    }
    if args.json {
        println!(
            "{}",
            json!({ "map": source.name, "grid": [grid.rows(), grid.cols()], "queries": described, "rows": rows, "notes": notes })
        );
        return Ok(());
    }
    println!(
        "map      {}: {} × {} cells of {} m",
        source.name,
        grid.rows(),
        grid.cols(),
        cell_m
    );
    let model_name = if args.corner_cutting {
        "8-connected, corner cutting"
    } else {
        "8-connected, no corner cutting"
    };
    println!("queries  {described}; move model {model_name}");
    println!();
    print!("{}", skyplan_bench::format_table(&rows));
    for n in &notes {
        println!("note     {n}");
    }
    if let Some(out) = &args.out {
        println!("wrote    {}", out.display());
    }
    Ok(())
}

/// `bench --replan N`: seeded flights into hidden buildings, one row per replanner.
fn replan_bench(args: &BenchArgs, flights: usize) -> Result<()> {
    if flights == 0 {
        return Err(bad_input("--replan 0: expected at least 1 flight"));
    }
    let limits = skyplan_plan::Limits::default();
    let world = crate::world_load::load_world(args.map.as_deref(), &Default::default(), &limits)?;
    let spec = skyplan_replan::bench::ScenarioSpec {
        flights,
        seed: args.seed,
        hidden: args.hidden_random,
        alt_m: args.alt_m,
        safety_m: args.safety_m,
        min_distance_m: args.min_distance_m.unwrap_or(300.0),
    };
    print!("{}", crate::replan_cmd::bench(&world, &spec, 50.0)?);
    Ok(())
}
