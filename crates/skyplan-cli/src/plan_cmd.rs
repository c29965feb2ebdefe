//! `skyplan plan`: options → pipeline → files, picture and summary.

use crate::args::{Pair, PlanArgs, PlannerArg, PruneArg};
use crate::config::Config;
use crate::exit::{Classify, Failure, Kind, Result, bad_input};
use crate::files::{BUNDLED_COLLIDERS, BUNDLED_NAME, read_text, write_atomic};
use anyhow::anyhow;
use serde_json::{Value, json};
use skyplan_cspace::GridSpec;
use skyplan_export::Format;
use skyplan_pipeline::{PlanError, PlanOutcome, PlanRequest, Position, Prune, plan};
use skyplan_search::{MoveModel, Planner};
use std::path::PathBuf;
use std::time::Instant;

/// The default goal on the bundled map: a free street corner across the city from the home.
pub const DEFAULT_GOAL_NE: (f64, f64) = (420.0, 390.0);

/// The resolved options: command line over config file over defaults.
pub(crate) struct Options {
    pub(crate) map: Option<PathBuf>,
    pub(crate) request: PlanRequest,
    pub(crate) out: PathBuf,
    pub(crate) format: Format,
    pub(crate) plot: Option<PathBuf>,
    pub(crate) json: bool,
}

fn position(
    ne: Option<Pair>,
    lla: Option<Pair>,
    cfg_ne: Option<[f64; 2]>,
    cfg_lla: Option<[f64; 2]>,
) -> Option<Position> {
    let from_ne = |p: Pair| Position::Ne {
        north_m: p.0,
        east_m: p.1,
    };
    let from_lla = |p: Pair| Position::Lla {
        lat_deg: p.0,
        lon_deg: p.1,
    };
    ne.map(from_ne)
        .or(lla.map(from_lla))
        .or(cfg_ne.map(|[a, b]| from_ne(Pair(a, b))))
        .or(cfg_lla.map(|[a, b]| from_lla(Pair(a, b))))
}

/// The waypoint file and its format: the given path (or `waypoints.json`), and the given format
/// name (or the file's extension).
pub(crate) fn output_file(
    out: Option<PathBuf>,
    format: Option<String>,
) -> Result<(PathBuf, Format)> {
    let out = out.unwrap_or_else(|| PathBuf::from("waypoints.json"));
    let format = match format {
        Some(name) => Format::from_name(&name)
            .ok_or_else(|| bad_input(format!("--format: expected json, csv, hdf5, geojson or plan, found {name:?}")))?,
        None => Format::from_path(&out).ok_or_else(|| {
            bad_input(format!(
                "--out {}: cannot tell the format from the extension; use .json .csv .h5 .geojson .plan or --format",
                out.display()
            ))
        })?,
    };
    Ok((out, format))
}

pub(crate) fn resolve(args: PlanArgs) -> Result<Options> {
    let cfg = match &args.config {
        Some(path) => Config::load(path)?,
        None => Config::default(),
    };
    if cfg.start_ne.is_some() && cfg.start_lla.is_some() {
        return Err(bad_input(
            "config: give either start_ne or start_lla, not both",
        ));
    }
    if cfg.goal_ne.is_some() && cfg.goal_lla.is_some() {
        return Err(bad_input(
            "config: give either goal_ne or goal_lla, not both",
        ));
    }
    let connectivity = args.connectivity.or(cfg.connectivity).unwrap_or(8);
    let corner_cutting = args.corner_cutting || cfg.corner_cutting.unwrap_or(false);
    let model = match (connectivity, corner_cutting) {
        (8, false) => MoveModel::Octile,
        (8, true) => MoveModel::OctileCornerCutting,
        (4, false) => MoveModel::FourConnected,
        (4, true) => {
            return Err(bad_input(
                "--corner-cutting needs diagonal moves: use it with --connectivity 8",
            ));
        }
        (other, _) => {
            return Err(bad_input(format!(
                "--connectivity: expected 4 or 8, found {other}"
            )));
        }
    };
    let planner = match args.planner.or(cfg.planner).unwrap_or(PlannerArg::Jps) {
        PlannerArg::Astar => Planner::AStar,
        PlannerArg::Dijkstra => Planner::Dijkstra,
        PlannerArg::Jps => Planner::Jps,
        PlannerArg::JpsPlus => Planner::JpsPlus,
        PlannerArg::Theta => Planner::ThetaStar,
        PlannerArg::Wavefront | PlannerArg::Costmap => {
            return Err(bad_input(
                "planner wavefront/costmap from a config file: give it as --planner on the command line",
            ));
        }
        PlannerArg::Prm
        | PlannerArg::LazyPrm
        | PlannerArg::RrtConnect
        | PlannerArg::RrtStar
        | PlannerArg::Voxel
        | PlannerArg::Voronoi => {
            return Err(bad_input(
                "planner prm/rrt-connect/rrt-star/voxel/voronoi from a config file: give it as --planner on the command line",
            ));
        }
    };
    let prune = match (args.epsilon.or(cfg.epsilon), args.prune.or(cfg.prune)) {
        (Some(eps), _) if eps < 0.0 => {
            return Err(bad_input(format!(
                "--epsilon: expected a tolerance ≥ 0, found {eps}"
            )));
        }
        (Some(_), Some(PruneArg::None)) => {
            return Err(bad_input(
                "--epsilon asks for pruning, --prune none forbids it",
            ));
        }
        (Some(eps), _) => Prune::Epsilon(eps),
        (None, Some(PruneArg::None)) => Prune::None,
        (None, _) => Prune::Collinear,
    };
    let start = position(args.start_ne, args.start_lla, cfg.start_ne, cfg.start_lla).unwrap_or(
        Position::Ne {
            north_m: 0.0,
            east_m: 0.0,
        },
    );
    let goal =
        position(args.goal_ne, args.goal_lla, cfg.goal_ne, cfg.goal_lla).unwrap_or(Position::Ne {
            north_m: DEFAULT_GOAL_NE.0,
            east_m: DEFAULT_GOAL_NE.1,
        });
    let spec = GridSpec {
        alt_m: args.alt_m.or(cfg.alt_m).unwrap_or(5.0),
        safety_m: args.safety_m.or(cfg.safety_m).unwrap_or(5.0),
        cell_m: args.cell_m.or(cfg.cell_m).unwrap_or(1.0),
    };
    let start_heading_rad = args
        .start_heading_deg
        .or(cfg.start_heading_deg)
        .unwrap_or(0.0)
        .to_radians();
    let (out, format) = output_file(args.out.or(cfg.out), args.format.or(cfg.format))?;
    let plot = args.plot.or(cfg.plot);
    if let Some(p) = &plot
        && skyplan_plot::PlotFormat::from_path(p).is_none()
    {
        return Err(bad_input(format!(
            "--plot {}: expected a .png or .svg file name",
            p.display()
        )));
    }
    Ok(Options {
        map: args.map.or(cfg.map),
        request: PlanRequest {
            spec,
            start,
            goal,
            model,
            planner,
            prune,
            shortcut: !args.no_shortcut && cfg.shortcut.unwrap_or(true),
            start_heading_rad,
        },
        out,
        format,
        plot,
        json: args.json,
    })
}

fn model_name(model: MoveModel) -> &'static str {
    match model {
        MoveModel::FourConnected => "4-connected",
        MoveModel::Octile => "8-connected, no corner cutting",
        MoveModel::OctileCornerCutting => "8-connected, corner cutting",
    }
}

fn planner_name(planner: Planner) -> &'static str {
    match planner {
        Planner::AStar => "A*",
        Planner::Dijkstra => "Dijkstra",
        Planner::Jps => "JPS",
        Planner::JpsPlus => "JPS+",
        Planner::ThetaStar => "Theta*",
    }
}

pub fn run(args: PlanArgs) -> Result<()> {
    let json_mode = args.json;
    let result = run_inner(args);
    if json_mode {
        crate::exit::print_json_failure(&result);
    }
    result
}

fn run_inner(args: PlanArgs) -> Result<()> {
    if crate::voronoi_cmd::handles(&args) {
        return crate::voronoi_cmd::run(args);
    }
    if crate::plan3d_cmd::handles(&args)? {
        return crate::plan3d_cmd::run(args);
    }
    if crate::grid_cmd::handles(&args) {
        return crate::grid_cmd::run_plan(args);
    }
    let t0 = Instant::now();
    let opts = resolve(args)?;
    let (map_name, text) = match &opts.map {
        Some(path) => (path.display().to_string(), read_text(path)?),
        None => (BUNDLED_NAME.to_string(), BUNDLED_COLLIDERS.to_string()),
    };
    let map = skyplan_map::colliders::parse_colliders(&text)
        .map_err(|e| bad_input(format!("{map_name}: {e}")))?;
    let outcome = plan(&map, &opts.request).map_err(|e: PlanError| {
        let kind = if e.is_no_path() {
            Kind::NoPath
        } else if matches!(e, PlanError::Internal(_)) {
            Kind::Runtime
        } else {
            Kind::BadInput
        };
        Failure {
            kind,
            error: anyhow!(e),
        }
    })?;

    let summary = summary_json(&map_name, map.boxes.len(), &opts, &outcome);
    let bytes =
        skyplan_export::encode(opts.format, &outcome.mission, &summary).or_exit(Kind::Runtime)?;
    write_atomic(&opts.out, &bytes)?;
    if let Some(plot_path) = &opts.plot {
        write_plot(plot_path, &map_name, &opts, &outcome)?;
    }
    if opts.json {
        let mut full = summary;
        full["status"] = json!("ok");
        full["waypoints"] = json!(outcome.mission.rows());
        full["waypoints_lla"] = json!(
            outcome
                .mission
                .waypoints
                .iter()
                .map(|w| [w.lat_deg, w.lon_deg])
                .collect::<Vec<_>>()
        );
        full["wall_time_us"] = json!(t0.elapsed().as_micros() as u64);
        println!("{full}");
    } else {
        print_summary(&map_name, map.boxes.len(), &opts, &outcome, t0);
    }
    Ok(())
}

fn write_plot(
    path: &std::path::Path,
    map_name: &str,
    opts: &Options,
    o: &PlanOutcome,
) -> Result<()> {
    let format = skyplan_plot::PlotFormat::from_path(path)
        .ok_or_else(|| bad_input(format!("--plot {}: expected .png or .svg", path.display())))?;
    let raw: Vec<(f64, f64)> = o.path.cells.iter().map(|&c| o.grid.center_ne(c)).collect();
    let waypoints: Vec<(f64, f64)> = o
        .mission
        .waypoints
        .iter()
        .map(|w| (w.north_m, w.east_m))
        .collect();
    let spec = opts.request.spec;
    let scene = skyplan_plot::Scene {
        title: format!(
            "{} at {} m altitude, {} m margin: {:.1} m, {} waypoints",
            short_name(map_name),
            spec.alt_m,
            spec.safety_m,
            o.cost_m,
            waypoints.len()
        ),
        grid: &o.grid,
        obstacles: &o.active_obstacles,
        raw_path_ne: &raw,
        pruned_path_ne: &waypoints,
        start_ne: Some((o.start.north_m, o.start.east_m)),
        goal_ne: Some((o.goal.north_m, o.goal.east_m)),
        graph_ne: &[],
        connectors_ne: &[],
    };
    let bytes = skyplan_plot::render(&scene, format, 1000, 1000).or_exit(Kind::Runtime)?;
    write_atomic(path, &bytes)
}

pub(crate) fn short_name(map_name: &str) -> &str {
    if map_name == BUNDLED_NAME {
        return "FCND city map";
    }
    std::path::Path::new(map_name)
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or(map_name)
}

fn summary_json(map_name: &str, obstacles: usize, opts: &Options, o: &PlanOutcome) -> Value {
    let spec = opts.request.spec;
    let f = o.grid.frame();
    let place = |p: &skyplan_pipeline::Place, c: skyplan_cspace::Cell| json!({ "north_m": p.north_m, "east_m": p.east_m, "lat_deg": p.lat_deg, "lon_deg": p.lon_deg, "cell": [c.row, c.col] });
    json!({
        "map": map_name,
        "obstacles": obstacles,
        "home": { "lat_deg": o.frame.home().lat_deg, "lon_deg": o.frame.home().lon_deg },
        "grid": {
            "rows": o.grid.rows(), "cols": o.grid.cols(), "cell_m": spec.cell_m,
            "origin_north_m": f.origin_north_m, "origin_east_m": f.origin_east_m,
            "alt_m": spec.alt_m, "safety_m": spec.safety_m, "blocked_cells": o.grid.blocked_count(),
        },
        "start": place(&o.start, o.start_cell),
        "goal": place(&o.goal, o.goal_cell),
        "move_model": model_name(opts.request.model),
        "planner": planner_name(opts.request.planner),
        "prune": opts.request.prune,
        "shortcut": opts.request.shortcut,
        "cost_m": o.cost_m,
        "octile_optimum_m": o.octile_optimum_m,
        "straight_line_m": o.straight_line_m,
        "path_cells": o.path.cells.len(),
        "straight_moves": o.path.straight_moves,
        "diagonal_moves": o.path.diagonal_moves,
        "expansions": o.path.expansions,
        "waypoint_counts": {
            "grid_path": o.path.cells.len(),
            "after_pruning": o.pruned.len(),
            "after_shortcut": o.shortcut.len(),
            "mission": o.mission.waypoints.len(),
        },
        "mission_length_m": o.mission.length_m(),
        "search_time_us": o.timings.search_us,
        "timings_us": o.timings,
        "outputs": {
            "waypoints": opts.out.display().to_string(),
            "format": opts.format.name(),
            "plot": opts.plot.as_ref().map(|p| p.display().to_string()),
        },
    })
}

fn print_summary(map_name: &str, obstacles: usize, opts: &Options, o: &PlanOutcome, t0: Instant) {
    let spec = opts.request.spec;
    let blocked = o.grid.blocked_count();
    let ms = |us: u64| us as f64 / 1000.0;
    let home = o.frame.home();
    println!(
        "map        {map_name}: {obstacles} obstacles, home lat {:.6}, lon {:.6}",
        home.lat_deg, home.lon_deg
    );
    println!(
        "grid       {} × {} cells of {} m at {} m altitude, {} m margin: {} blocked ({:.1} %), built in {:.2} ms",
        o.grid.rows(),
        o.grid.cols(),
        spec.cell_m,
        spec.alt_m,
        spec.safety_m,
        blocked,
        100.0 * blocked as f64 / o.grid.len().max(1) as f64,
        ms(o.timings.grid_build_us)
    );
    println!("start      {}", o.start);
    println!("goal       {}", o.goal);
    let shape = if o.path.any_angle_cells.is_some() {
        format!("{} turning points", o.path.cells.len())
    } else {
        format!(
            "{} cells ({} straight, {} diagonal)",
            o.path.cells.len(),
            o.path.straight_moves,
            o.path.diagonal_moves
        )
    };
    println!(
        "path       {} {}: {:.2} m, {shape}, {} expansions, {:.2} ms",
        planner_name(opts.request.planner),
        model_name(opts.request.model),
        o.cost_m,
        o.path.expansions,
        ms(o.timings.search_us)
    );
    if let Some(octile_m) = o.octile_optimum_m {
        println!(
            "any-angle  {:.2} m: {:.1} % shorter than the octile optimum {octile_m:.2} m; straight line {:.2} m",
            o.cost_m,
            100.0 * (1.0 - o.cost_m / octile_m),
            o.straight_line_m
        );
    }
    let shortcut = if opts.request.shortcut {
        format!(" → {} after line-of-sight shortcut", o.shortcut.len())
    } else {
        String::new()
    };
    println!(
        "waypoints  {} → {} after pruning{shortcut}; mission of {} waypoints, {:.2} m flown",
        o.path.cells.len(),
        o.pruned.len(),
        o.mission.waypoints.len(),
        o.mission.length_m()
    );
    let plot = opts
        .plot
        .as_ref()
        .map(|p| format!(", {}", p.display()))
        .unwrap_or_default();
    println!(
        "wrote      {} ({}){plot}",
        opts.out.display(),
        opts.format.name()
    );
    println!(
        "time       {:.2} ms in all",
        t0.elapsed().as_secs_f64() * 1000.0
    );
}
