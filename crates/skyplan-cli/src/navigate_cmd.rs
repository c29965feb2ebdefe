//! `skyplan navigate`: follow the inflated cost map's gradient from a start through targets,
//! which may change mid-ride (the workshop's navigation functions). The map is loaded through the
//! planning API's `World`; the ride itself is `skyplan_navfn::navigate`.

use crate::args::Pair;
use crate::exit::{Failure, Kind, Result, bad_input};
use crate::files::read_text;
use crate::grid_args::{GridMapArgs, NavigateArgs};
use serde_json::{Value, json};
use skyplan_cspace::{Cell, Grid2};
use skyplan_navfn::{Costmap, Inflation, NavError, NavRequest, TargetChange, navigate};
use skyplan_search::MoveModel;
use std::io::IsTerminal;
use std::path::Path;
use std::time::Instant;

fn model_of(connectivity: u8, corner_cutting: bool) -> Result<MoveModel> {
    match (connectivity, corner_cutting) {
        (8, false) => Ok(MoveModel::Octile),
        (8, true) => Ok(MoveModel::OctileCornerCutting),
        (4, false) => Ok(MoveModel::FourConnected),
        (4, true) => Err(bad_input(
            "--corner-cutting needs diagonal moves: use it with --connectivity 8",
        )),
        (other, _) => Err(bad_input(format!(
            "--connectivity: expected 4 or 8, found {other}"
        ))),
    }
}

/// The cell of a position, or why it cannot be used (off the map or at an obstacle).
fn cell_of(grid: &Grid2, which: &str, (n, e): (f64, f64)) -> std::result::Result<Cell, String> {
    let b = skyplan_plan::BoundsNe {
        north_min_m: grid.frame().origin_north_m,
        north_max_m: grid.frame().origin_north_m + f64::from(grid.rows()) * grid.frame().cell_m,
        east_min_m: grid.frame().origin_east_m,
        east_max_m: grid.frame().origin_east_m + f64::from(grid.cols()) * grid.frame().cell_m,
    };
    let cell = grid
        .cell_at_ne(n, e)
        .ok_or_else(|| format!("the {which} N {n} m, E {e} m is off the map ({b})"))?;
    if grid.is_blocked(cell) {
        return Err(format!(
            "the {which} N {n} m, E {e} m (row {}, col {}) is at an obstacle",
            cell.row, cell.col
        ));
    }
    Ok(cell)
}

/// A position from the option, else the map's default, else a prompt on a terminal.
fn endpoint(
    grid: &Grid2,
    which: &str,
    option: &str,
    given: Option<Pair>,
    default: Option<[f64; 2]>,
) -> Result<(Cell, (f64, f64))> {
    let p = match (given, default) {
        (Some(p), _) => p,
        (None, Some([n, e])) => Pair(n, e),
        (None, None) if std::io::stdin().is_terminal() => crate::show::ask_position(grid, which)?,
        (None, None) => {
            return Err(bad_input(format!(
                "missing {option} N,E (the {which}, metres north,east of the map's origin)"
            )));
        }
    };
    let cell = cell_of(grid, which, (p.0, p.1)).map_err(bad_input)?;
    Ok((cell, (p.0, p.1)))
}

fn inflation_of(g: &GridMapArgs, cell_m: f64) -> Inflation {
    let inflation_radius_m = g.inflation_radius_m.unwrap_or(10.0 * cell_m);
    let cost_scaling_factor = g.cost_scaling.unwrap_or(if inflation_radius_m > 0.0 {
        3.0 / inflation_radius_m
    } else {
        0.0
    });
    Inflation {
        inscribed_radius_m: g.inscribed_radius_m.unwrap_or(0.0),
        inflation_radius_m,
        cost_scaling_factor,
    }
}

/// A navigation-function error as an exit: unreachable → 3, the rest → 2.
fn nav_failure(e: NavError, grid: &Grid2) -> Failure {
    let kind = match e {
        NavError::Unreachable { .. } => Kind::NoPath,
        _ => Kind::BadInput,
    };
    let describe = |c: Cell| {
        let (n, e) = grid.center_ne(c);
        format!("N {n:.2} m, E {e:.2} m")
    };
    let message = match &e {
        NavError::Unreachable {
            source_cell,
            destination_cell,
        } => format!(
            "{e}; the destination is at {}, the source at {}",
            describe(*destination_cell),
            describe(*source_cell)
        ),
        _ => e.to_string(),
    };
    Failure {
        kind,
        error: anyhow::anyhow!(message),
        plan_kind: None,
    }
}

/// JSON has no infinity: a clearance on a map without obstacles is `null`.
fn json_f64(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

fn read_targets_file(path: &Path) -> Result<Vec<Pair>> {
    let text = read_text(path)?;
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let p = crate::args::parse_pair(line)
            .map_err(|e| bad_input(format!("{}: line {}: {e}", path.display(), k + 1)))?;
        out.push(p);
    }
    if out.is_empty() {
        return Err(bad_input(format!(
            "{}: no targets (expected one N,E per line)",
            path.display()
        )));
    }
    Ok(out)
}

pub fn run_navigate(args: NavigateArgs) -> Result<()> {
    let json_mode = args.json;
    let result = navigate_inner(args);
    if json_mode {
        crate::exit::print_json_failure(&result);
    }
    match result? {
        Some(stopped_short) => Err(stopped_short),
        None => Ok(()),
    }
}

/// The human summary of a ride.
fn print_ride(map_name: &str, grid: &Grid2, run: &skyplan_navfn::NavRun) {
    let cell_m = grid.frame().cell_m;
    println!(
        "map        {map_name}: {} × {} cells of {cell_m} m",
        grid.rows(),
        grid.cols()
    );
    for (k, l) in run.legs.iter().enumerate() {
        let (n, e) = grid.center_ne(l.target);
        let how = match (l.reached, l.replaced) {
            (true, _) => "reached",
            (false, true) => "replaced",
            (false, false) => "not reached",
        };
        println!(
            "leg {:<6} N {n:.2} m, E {e:.2} m: steps {}..{}, {how}",
            k + 1,
            l.from_step,
            l.to_step
        );
    }
    println!(
        "ride       {}: {} steps, {:.2} m travelled, min clearance {:.2} m",
        if run.reached { "reached" } else { "stopped" },
        run.steps,
        run.distance_cells * cell_m,
        run.min_clearance_cells * cell_m
    );
}

/// The normalised cost map with the ride, as a PNG heat map.
fn write_heat(
    target: &crate::files::Target,
    grid: &Grid2,
    costmap: &Costmap,
    trace: &[Cell],
    start: Cell,
    goal: Cell,
) -> Result<()> {
    let values: Vec<f64> = costmap.normalised().iter().map(|&c| f64::from(c)).collect();
    let heat = skyplan_plot::Heatmap {
        title: format!(
            "navigation over the inflated cost map: {} steps",
            trace.len().saturating_sub(1)
        ),
        grid,
        values: &values,
        measure: "Nav2 cost (0 free to 254 lethal)",
        path: trace,
        start: Some(start),
        goal: Some(goal),
    };
    let bytes = skyplan_plot::render_heatmap_png(&heat, 1000).map_err(crate::exit::runtime)?;
    crate::files::write_target(target, &bytes)
}

/// The targets in order and the mid-ride changes, as free cells.
fn targets_of(
    grid: &Grid2,
    args: &NavigateArgs,
    goal_default: Option<[f64; 2]>,
) -> Result<(Vec<Cell>, Vec<TargetChange>)> {
    let target_pairs: Vec<Pair> = match (&args.targets, &args.targets_file) {
        (Some(t), _) => t.0.clone(),
        (None, Some(path)) => read_targets_file(path)?,
        (None, None) => {
            let (_, ne) = endpoint(grid, "target", "--targets", None, goal_default)?;
            vec![Pair(ne.0, ne.1)]
        }
    };
    let mut targets = Vec::new();
    for (k, p) in target_pairs.iter().enumerate() {
        let which = format!("target {}", k + 1);
        targets.push(cell_of(grid, &which, (p.0, p.1)).map_err(bad_input)?);
    }
    let mut changes = Vec::new();
    for c in &args.change_target_at {
        let which = format!("target of --change-target-at {}", c.at_step);
        let target = cell_of(grid, &which, (c.target.0, c.target.1)).map_err(bad_input)?;
        changes.push(TargetChange {
            at_step: c.at_step,
            target,
        });
    }
    Ok((targets, changes))
}

/// Runs the ride; `Ok(Some(failure))` when it stopped short (its summary is already printed).
fn navigate_inner(args: NavigateArgs) -> Result<Option<Failure>> {
    let g = &args.grid;
    let plot = match &args.plot {
        Some(path)
            if path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("png")) =>
        {
            Some(crate::files::output_target("--plot", path)?)
        }
        Some(path) => {
            return Err(bad_input(format!(
                "--plot {}: navigate draws a PNG heat map; use a .png file name",
                path.display()
            )));
        }
        None => None,
    };
    let limits = skyplan_plan::Limits {
        max_memory_bytes: args
            .max_memory
            .unwrap_or_else(crate::args::default_max_memory),
    };
    let world = crate::world_load::load_world(args.map.as_deref(), g, &limits)?;
    let (start_default, goal_default) = world.default_endpoints_ne();
    let mut session = skyplan_plan::Session::new(world).with_limits(limits);
    let grid_arc = session.grid(args.alt_m, args.safety_m, args.cell_m)?;
    let grid: &Grid2 = &grid_arc;
    let model = model_of(args.connectivity, args.corner_cutting)?;
    let (start, start_ne) = endpoint(grid, "source", "--start-ne", args.start_ne, start_default)?;
    let (targets, changes) = targets_of(grid, &args, goal_default)?;
    let cell_m = grid.frame().cell_m;
    let params = inflation_of(g, cell_m);
    let t0 = Instant::now();
    let costmap = Costmap::inflate(grid, params).map_err(|e| nav_failure(e, grid))?;
    let inflate_us = t0.elapsed().as_micros() as u64;
    let request = NavRequest {
        source: start,
        targets,
        changes,
        model,
        weight: g.cost_weight.unwrap_or(2.0),
    };
    let run = navigate(&costmap, &request).map_err(|e| nav_failure(e, grid))?;
    let ride_us = t0.elapsed().as_micros() as u64 - inflate_us;
    let cell_json = |c: Cell| {
        let (n, e) = grid.center_ne(c);
        json!({ "north_m": n, "east_m": e, "cell": [c.row, c.col] })
    };
    let legs: Vec<Value> = run
        .legs
        .iter()
        .map(|l| {
            json!({ "target": cell_json(l.target), "from_step": l.from_step, "to_step": l.to_step,
                    "reached": l.reached, "replaced": l.replaced })
        })
        .collect();
    let trace: Vec<[f64; 2]> = skyplan_postprocess::prune_collinear(&run.trace)
        .iter()
        .map(|&c| {
            let (n, e) = grid.center_ne(c);
            [n, e]
        })
        .collect();
    let summary = json!({
        "status": if run.reached { "ok" } else { "no_path" },
        "map": session.world().name(),
        "move_model": match model {
            MoveModel::FourConnected => "4-connected",
            MoveModel::Octile => "8-connected, no corner cutting",
            MoveModel::OctileCornerCutting => "8-connected, corner cutting",
        },
        "start": { "north_m": start_ne.0, "east_m": start_ne.1, "cell": [start.row, start.col] },
        "reached": run.reached,
        "steps": run.steps,
        "distance_m": run.distance_cells * cell_m,
        "min_clearance_m": json_f64(run.min_clearance_cells * cell_m),
        "legs": legs,
        "ignored_changes": run.ignored_changes,
        "failure": run.failure.as_ref().map(|e| e.to_string()),
        "waypoints": trace,
        "costmap": {
            "inscribed_radius_m": params.inscribed_radius_m,
            "inflation_radius_m": params.inflation_radius_m,
            "cost_scaling_factor": params.cost_scaling_factor,
            "cost_weight": g.cost_weight.unwrap_or(2.0),
        },
        "inflation_time_us": inflate_us,
        "ride_time_us": ride_us,
    });
    if args.show {
        let goal = run.legs.last().map_or(start, |l| l.target);
        crate::show::print(grid, start, goal, &run.trace, model, false);
    }
    if let Some(target) = &plot {
        let goal = run.legs.last().map_or(start, |l| l.target);
        write_heat(target, grid, &costmap, &run.trace, start, goal)?;
    }
    if args.json {
        println!("{summary}");
    } else {
        print_ride(session.world().name(), grid, &run);
    }
    Ok(match run.failure {
        Some(e) if !run.reached => Some(nav_failure(e, grid)),
        _ => None,
    })
}
