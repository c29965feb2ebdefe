//! Grid maps and their planners: `plan --planner wavefront|costmap` (and A*-family planners on
//! image, MovingAI and random maps), and `navigate`.
//!
//! Maps are chosen by extension: `.csv` FCND colliders (at `--alt-m`), `.yaml` ROS map_server,
//! `.png`/`.pgm` bare images with `--resolution`, `.map` MovingAI; or `--random WxH`. Positions
//! are metres north,east of the map's origin (the home for colliders maps, the YAML `origin` —
//! the lower-left corner — for images, the lower-left corner for MovingAI and random maps: north
//! is up the picture). A position names the cell that contains it; waypoints are cell centres.

use crate::args::{Pair, PlanArgs, PlannerArg};
use crate::exit::{Classify, Failure, Kind, Result, bad_input};
use crate::files::{BUNDLED_COLLIDERS, BUNDLED_NAME, read_text, write_atomic};
use crate::grid_args::{FieldArg, GridMapArgs, NavigateArgs};
use anyhow::Context;
use serde_json::{Value, json};
use skyplan_cspace::{Cell, Grid2, GridSpec};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_imagemap::{MapYaml, decode_image, image_map_with};
use skyplan_navfn::{
    Costmap, DistanceField, FieldMetric, Inflation, NavError, NavRequest, TargetChange,
    cost_search, cost_to_go, distance_field, navigate, show,
};
use skyplan_search::{GridSearch, MoveModel, Planner, SearchError};
use std::io::{BufRead, IsTerminal, Write};
use std::path::Path;
use std::time::Instant;

/// Largest grid `--show` prints as text.
const SHOW_MAX_ROWS: u32 = 60;
const SHOW_MAX_COLS: u32 = 80;

/// True if `plan` should run here rather than in the colliders pipeline.
pub fn handles(args: &PlanArgs) -> bool {
    matches!(
        args.planner,
        Some(PlannerArg::Wavefront | PlannerArg::Costmap)
    ) || args.grid.random.is_some()
        || args.map.as_deref().is_some_and(|p| !is_ext(p, &["csv"]))
}

fn is_ext(path: &Path, exts: &[&str]) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| exts.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// A map turned into a grid, with what is known of its place on Earth.
struct GridMap {
    name: String,
    grid: Grid2,
    /// The geodetic frame (colliders maps, or `--home`).
    frame: Option<LocalFrame>,
    alt_m: f64,
    /// Default start and goal (the bundled map's), metres north,east.
    defaults: Option<((f64, f64), (f64, f64))>,
    /// Start and goal drawn among free cells (random maps).
    drawn: Option<(Cell, Cell)>,
}

fn load_map(map: Option<&Path>, spec: GridSpec, g: &GridMapArgs) -> Result<GridMap> {
    let mut alt_m = 0.0;
    let mut defaults = None;
    let mut drawn = None;
    let mut colliders_home = None;
    let (name, grid) = if let Some(size) = g.random {
        let grid = skyplan_imagemap::random_workspace(size.height, size.width, g.density, g.seed)
            .map_err(|e| bad_input(format!("--random: {e}")))?;
        // The farthest-apart pair of 16 drawn free cells, so that the route is worth showing.
        let cells = skyplan_imagemap::draw_free_cells(&grid, 16, g.seed);
        let dist2 = |a: Cell, b: Cell| {
            u64::from(a.row.abs_diff(b.row)).pow(2) + u64::from(a.col.abs_diff(b.col)).pow(2)
        };
        for (i, &a) in cells.iter().enumerate() {
            for &b in &cells[i + 1..] {
                if drawn.is_none_or(|(x, y)| dist2(a, b) > dist2(x, y)) {
                    drawn = Some((a, b));
                }
            }
        }
        (
            format!(
                "random {}x{} (density {}, seed {})",
                size.width, size.height, g.density, g.seed
            ),
            grid,
        )
    } else {
        match map {
            None => {
                let m = skyplan_map::colliders::parse_colliders(BUNDLED_COLLIDERS)
                    .map_err(|e| bad_input(format!("{BUNDLED_NAME}: {e}")))?;
                alt_m = spec.alt_m;
                defaults = Some(((0.0, 0.0), crate::plan_cmd::DEFAULT_GOAL_NE));
                colliders_home = Some(m.home);
                let grid = Grid2::from_colliders(&m, spec)
                    .map_err(|e| bad_input(format!("{BUNDLED_NAME}: {e}")))?;
                (BUNDLED_NAME.to_string(), grid)
            }
            Some(path) => {
                let name = path.display().to_string();
                let grid = if is_ext(path, &["csv"]) {
                    let m = skyplan_map::colliders::parse_colliders(&read_text(path)?)
                        .map_err(|e| bad_input(format!("{name}: {e}")))?;
                    alt_m = spec.alt_m;
                    colliders_home = Some(m.home);
                    Grid2::from_colliders(&m, spec)
                        .map_err(|e| bad_input(format!("{name}: {e}")))?
                } else if is_ext(path, &["yaml", "yml"]) {
                    let meta = MapYaml::parse(&read_text(path)?)
                        .map_err(|e| bad_input(format!("{name}: {e}")))?;
                    let image = path.parent().unwrap_or(Path::new("")).join(&meta.image);
                    image_grid(&image, &meta, g.unknown_free)
                        .map_err(|e| bad_input(format!("{name}: field image: {e:#}")))?
                } else if is_ext(path, &["png", "pgm"]) {
                    let resolution = g.resolution.ok_or_else(|| {
                        bad_input(format!(
                            "{name}: a bare image needs --resolution M (metres per pixel), or use a map_server .yaml"
                        ))
                    })?;
                    image_grid(path, &MapYaml::bare(resolution), g.unknown_free)
                        .map_err(|e| bad_input(format!("{e:#}")))?
                } else if is_ext(path, &["map"]) {
                    let m = skyplan_map::movingai::parse_map(&read_text(path)?)
                        .map_err(|e| bad_input(format!("{name}: {e}")))?;
                    skyplan_imagemap::grid_from_movingai(&m)
                        .map_err(|e| bad_input(format!("{name}: {e}")))?
                } else {
                    return Err(bad_input(format!(
                        "{name}: unknown map type; expected .csv (colliders), .yaml (map_server), .png/.pgm (with --resolution) or .map (MovingAI)"
                    )));
                };
                (name, grid)
            }
        }
    };
    let frame = match (colliders_home, g.home) {
        (Some(_), Some(_)) => {
            return Err(bad_input(
                "--home: a colliders map carries its own home (line 1); drop --home",
            ));
        }
        (Some(h), None) => Some(Lla {
            lat_deg: h.lat_deg,
            lon_deg: h.lon_deg,
            alt_m: 0.0,
        }),
        (None, Some(Pair(lat_deg, lon_deg))) => Some(Lla {
            lat_deg,
            lon_deg,
            alt_m: 0.0,
        }),
        (None, None) => None,
    }
    .map(|home| LocalFrame::new(home).map_err(|e| bad_input(format!("home: {e}"))))
    .transpose()?;
    Ok(GridMap {
        name,
        grid,
        frame,
        alt_m,
        defaults,
        drawn,
    })
}

/// Reads and decodes an image map; errors name the image file.
fn image_grid(path: &Path, meta: &MapYaml, unknown_free: bool) -> anyhow::Result<Grid2> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let raster = decode_image(&bytes).with_context(|| path.display().to_string())?;
    let map =
        image_map_with(&raster, meta, unknown_free).with_context(|| path.display().to_string())?;
    Ok(map.grid)
}

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

fn model_name(model: MoveModel) -> &'static str {
    match model {
        MoveModel::FourConnected => "4-connected",
        MoveModel::Octile => "8-connected, no corner cutting",
        MoveModel::OctileCornerCutting => "8-connected, corner cutting",
    }
}

fn extent(grid: &Grid2) -> String {
    let f = grid.frame();
    format!(
        "north {:.2}..{:.2} m, east {:.2}..{:.2} m",
        f.origin_north_m,
        f.origin_north_m + f64::from(grid.rows()) * f.cell_m,
        f.origin_east_m,
        f.origin_east_m + f64::from(grid.cols()) * f.cell_m
    )
}

/// The cell of a position, or why it cannot be used (exit 2: off the map or at an obstacle).
fn cell_of(grid: &Grid2, which: &str, (n, e): (f64, f64)) -> std::result::Result<Cell, String> {
    let cell = grid.cell_at_ne(n, e).ok_or_else(|| {
        format!(
            "the {which} N {n} m, E {e} m is off the map ({})",
            extent(grid)
        )
    })?;
    if grid.is_blocked(cell) {
        return Err(format!(
            "the {which} N {n} m, E {e} m (row {}, col {}) is at an obstacle",
            cell.row, cell.col
        ));
    }
    Ok(cell)
}

/// Asks on the terminal until the answer is a free cell on the map.
fn ask_position(grid: &Grid2, which: &str) -> Result<(Cell, (f64, f64))> {
    let stdin = std::io::stdin();
    loop {
        eprint!("{which} as N,E metres ({}): ", extent(grid));
        let _ = std::io::stderr().flush();
        let mut line = String::new();
        let read = stdin.lock().read_line(&mut line).or_exit(Kind::Runtime)?;
        if read == 0 {
            return Err(bad_input(format!("no {which} given (end of input)")));
        }
        match crate::args::parse_pair(line.trim()) {
            Err(e) => eprintln!("  {e}; try again"),
            Ok(Pair(n, e)) => match cell_of(grid, which, (n, e)) {
                Ok(cell) => return Ok((cell, (n, e))),
                Err(msg) => eprintln!("  {msg}; try again"),
            },
        }
    }
}

/// A position from the option, else the map's default, else the drawn cell, else a prompt on a
/// terminal; otherwise a bad-input error naming the option.
fn endpoint(
    map: &GridMap,
    which: &str,
    option: &str,
    given: Option<Pair>,
    default: Option<(f64, f64)>,
    drawn: Option<Cell>,
) -> Result<(Cell, (f64, f64))> {
    if let Some(Pair(n, e)) = given.or(default.map(|(n, e)| Pair(n, e))) {
        let cell = cell_of(&map.grid, which, (n, e)).map_err(bad_input)?;
        return Ok((cell, (n, e)));
    }
    if let Some(cell) = drawn {
        return Ok((cell, map.grid.center_ne(cell)));
    }
    if std::io::stdin().is_terminal() {
        return ask_position(&map.grid, which);
    }
    Err(bad_input(format!(
        "missing {option} N,E (the {which}, metres north,east of the map's origin; {})",
        extent(&map.grid)
    )))
}

fn inflation_of(g: &GridMapArgs, cell_m: f64) -> Inflation {
    let inflation_radius_m = g.inflation_radius_m.unwrap_or(10.0 * cell_m);
    let cost_scaling_factor = g.cost_scaling.unwrap_or(if inflation_radius_m > 0.0 {
        3.0 / inflation_radius_m
    } else {
        0.0
    });
    Inflation {
        inscribed_radius_m: g.inscribed_radius_m,
        inflation_radius_m,
        cost_scaling_factor,
    }
}

/// Maps a navigation-function error to an exit: unreachable → 3, the rest → 2.
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
    }
}

/// What one `plan` run found on a grid map.
struct GridPlan {
    planner: &'static str,
    cells: Vec<Cell>,
    straight: u64,
    diagonal: u64,
    /// Field shown by --show and --plot, in cells (distance or cost-to-go).
    field_cells: Option<Vec<f64>>,
    /// Wavefront field for the distance matrix.
    wavefront: Option<DistanceField>,
    extra: Value,
    time_us: u64,
}

pub fn run_plan(args: PlanArgs) -> Result<()> {
    let t0 = Instant::now();
    let spec = GridSpec {
        alt_m: args.alt_m.unwrap_or(5.0),
        safety_m: args.safety_m.unwrap_or(5.0),
        cell_m: args.cell_m.unwrap_or(1.0),
    };
    let g = &args.grid;
    if args.config.is_some() {
        return Err(bad_input(
            "--config is read by the colliders pipeline only; give grid-map options on the command line",
        ));
    }
    if args.start_lla.is_some() || args.goal_lla.is_some() {
        return Err(bad_input(
            "--start-lla/--goal-lla: grid maps take --start-ne/--goal-ne (metres north,east of the map's origin)",
        ));
    }
    let map = load_map(args.map.as_deref(), spec, g)?;
    let model = model_of(args.connectivity.unwrap_or(8), args.corner_cutting)?;
    let (start_default, goal_default) = map.defaults.unzip();
    let (start_drawn, goal_drawn) = map.drawn.unzip();
    let (start, start_ne) = endpoint(
        &map,
        "source",
        "--start-ne",
        args.start_ne,
        start_default,
        start_drawn,
    )?;
    let (goal, goal_ne) = endpoint(
        &map,
        "destination",
        "--goal-ne",
        args.goal_ne,
        goal_default,
        goal_drawn,
    )?;
    let grid = &map.grid;
    let cell_m = grid.frame().cell_m;
    let planner = args.planner.unwrap_or(PlannerArg::Jps);
    let want_field = g.show || args.plot.is_some();
    let metric = match g.field {
        Some(FieldArg::Steps) => FieldMetric::Steps,
        _ => FieldMetric::Length,
    };
    let t_search = Instant::now();
    let result: Result<GridPlan> = match planner {
        PlannerArg::Wavefront => {
            let field =
                distance_field(grid, goal, model, metric).map_err(|e| nav_failure(e, grid))?;
            let time_field_us = t_search.elapsed().as_micros() as u64;
            match field.descend(start) {
                Ok(d) => Ok(GridPlan {
                    planner: "wavefront",
                    cells: d.cells,
                    straight: d.straight_moves,
                    diagonal: d.diagonal_moves,
                    field_cells: Some(field.values().to_vec()),
                    extra: json!({ "field": format!("{metric:?}").to_lowercase(), "field_time_us": time_field_us }),
                    wavefront: Some(field),
                    time_us: 0,
                }),
                Err(e) => {
                    if g.show {
                        print_show(grid, start, goal, &[], Some(&field));
                    }
                    Err(nav_failure(e, grid))
                }
            }
        }
        PlannerArg::Costmap => {
            let params = inflation_of(g, cell_m);
            let costmap = Costmap::inflate(grid, params).map_err(|e| nav_failure(e, grid))?;
            let found = cost_search(&costmap, start, goal, model, g.cost_weight, true)
                .map_err(|e| nav_failure(e, grid));
            let found = match found {
                Ok(p) => p,
                Err(f) => {
                    if g.show {
                        let field =
                            distance_field(&costmap.passable_grid(), goal, model, metric).ok();
                        print_show(grid, start, goal, &[], field.as_ref());
                    }
                    return Err(f);
                }
            };
            let min_clearance_m = found
                .cells
                .iter()
                .filter_map(|&c| costmap.clearance_m(c))
                .fold(f64::INFINITY, f64::min);
            let field_cells = if want_field {
                Some(
                    cost_to_go(&costmap, goal, model, g.cost_weight)
                        .map_err(|e| nav_failure(e, grid))?
                        .values()
                        .to_vec(),
                )
            } else {
                None
            };
            Ok(GridPlan {
                planner: "costmap A*",
                straight: found.straight_moves,
                diagonal: found.diagonal_moves,
                extra: json!({
                    "costmap": {
                        "inscribed_radius_m": params.inscribed_radius_m,
                        "inflation_radius_m": params.inflation_radius_m,
                        "cost_scaling_factor": params.cost_scaling_factor,
                        "cost_weight": g.cost_weight,
                        "objective_m": found.objective_cells * cell_m,
                        "min_clearance_m": json_f64(min_clearance_m),
                    },
                    "expansions": found.expansions,
                }),
                cells: found.cells,
                field_cells,
                wavefront: None,
                time_us: 0,
            })
        }
        other => {
            let (planner, label) = match other {
                PlannerArg::Astar => (Planner::AStar, "A*"),
                PlannerArg::Dijkstra => (Planner::Dijkstra, "Dijkstra"),
                PlannerArg::Jps => (Planner::Jps, "JPS"),
                PlannerArg::JpsPlus => (Planner::JpsPlus, "JPS+"),
                _ => (Planner::ThetaStar, "Theta*"),
            };
            match GridSearch::new().search(grid, start, goal, model, planner) {
                Ok(p) => Ok(GridPlan {
                    planner: label,
                    cells: p.cells,
                    straight: p.straight_moves,
                    diagonal: p.diagonal_moves,
                    field_cells: None,
                    wavefront: None,
                    extra: json!({ "expansions": p.expansions, "any_angle_m": p.any_angle_cells.map(|c| c * cell_m) }),
                    time_us: 0,
                }),
                Err(SearchError::Unreachable { .. }) => Err(nav_failure(
                    NavError::Unreachable {
                        source_cell: start,
                        destination_cell: goal,
                    },
                    grid,
                )),
                Err(e) => Err(bad_input(e)),
            }
        }
    };
    let mut found = match result {
        Ok(p) => p,
        Err(f) => {
            if g.show && f.kind == Kind::NoPath && planner != PlannerArg::Wavefront {
                let field = distance_field(grid, goal, model, metric).ok();
                print_show(grid, start, goal, &[], field.as_ref());
            }
            return Err(f);
        }
    };
    found.time_us = t_search.elapsed().as_micros() as u64;
    if want_field && found.wavefront.is_none() && planner != PlannerArg::Wavefront {
        found.wavefront = distance_field(grid, goal, model, metric).ok();
    }
    if found.field_cells.is_none() && want_field {
        found.field_cells = found.wavefront.as_ref().map(|f| f.values().to_vec());
    }
    let cost_m = match found.extra.get("any_angle_m").and_then(Value::as_f64) {
        Some(m) => m,
        None => skyplan_search::octile_cost(found.straight, found.diagonal) * cell_m,
    };
    let pruned = skyplan_postprocess::prune_collinear(&found.cells);
    let points: Vec<(f64, f64)> = pruned.iter().map(|&c| grid.center_ne(c)).collect();
    let mission = match &map.frame {
        Some(frame) => Some(
            skyplan_mission::Mission::from_points_ne(frame, &points, map.alt_m, 0.0)
                .map_err(|e| bad_input(format!("waypoints: {e}")))?,
        ),
        None => None,
    };
    let rows: Vec<[f64; 4]> = match &mission {
        Some(m) => m.rows(),
        None => {
            let mut heading = 0.0;
            points
                .iter()
                .enumerate()
                .map(|(k, &(n, e))| {
                    if k > 0 {
                        heading = skyplan_mission::heading_rad(points[k - 1], (n, e));
                    }
                    [n, e, map.alt_m, heading]
                })
                .collect()
        }
    };
    if let Some(out) = &args.out {
        let Some(mission) = &mission else {
            return Err(bad_input(format!(
                "--out {}: waypoint files carry lat/lon; this map has no geodetic home: pass --home LAT,LON",
                out.display()
            )));
        };
        let format = match &args.format {
            Some(name) => skyplan_export::Format::from_name(name)
                .ok_or_else(|| bad_input(format!("--format: unknown format {name:?}")))?,
            None => skyplan_export::Format::from_path(out).ok_or_else(|| {
                bad_input(format!(
                    "--out {}: cannot tell the format from the extension",
                    out.display()
                ))
            })?,
        };
        let bytes = skyplan_export::encode(format, mission, &json!({ "map": map.name }))
            .or_exit(Kind::Runtime)?;
        write_atomic(out, &bytes)?;
    }
    if g.show {
        print_show(grid, start, goal, &found.cells, found.wavefront.as_ref());
    }
    if let Some(path) = &args.plot {
        let values: Vec<f64> = found.field_cells.clone().unwrap_or_default();
        write_heatmap(path, grid, &values, &found.cells, start, goal)?;
    }
    let place = |c: Cell, ne: (f64, f64)| json!({ "north_m": ne.0, "east_m": ne.1, "cell": [c.row, c.col] });
    let f = grid.frame();
    let mut summary = json!({
        "status": "ok",
        "map": map.name,
        "planner": found.planner,
        "move_model": model_name(model),
        "grid": { "rows": grid.rows(), "cols": grid.cols(), "cell_m": f.cell_m,
                  "origin_north_m": f.origin_north_m, "origin_east_m": f.origin_east_m,
                  "blocked_cells": grid.blocked_count() },
        "home": map.frame.as_ref().map(|fr| json!({ "lat_deg": fr.home().lat_deg, "lon_deg": fr.home().lon_deg })),
        "start": place(start, start_ne),
        "goal": place(goal, goal_ne),
        "cost_m": cost_m,
        "path_cells": found.cells.len(),
        "straight_moves": found.straight,
        "diagonal_moves": found.diagonal,
        "waypoints": rows,
        "waypoints_lla": mission.as_ref().map(|m| m.waypoints.iter().map(|w| [w.lat_deg, w.lon_deg]).collect::<Vec<_>>()),
        "search_time_us": found.time_us,
        "wall_time_us": t0.elapsed().as_micros() as u64,
    });
    if let (Some(obj), Value::Object(extra)) = (summary.as_object_mut(), found.extra) {
        for (k, v) in extra {
            if k != "any_angle_m" || !v.is_null() {
                obj.insert(k, v);
            }
        }
    }
    if args.json {
        println!("{summary}");
    } else {
        println!(
            "map        {}: {} × {} cells of {} m, {} blocked",
            map.name,
            grid.rows(),
            grid.cols(),
            f.cell_m,
            grid.blocked_count()
        );
        println!(
            "start      N {:.2} m, E {:.2} m (row {}, col {})",
            start_ne.0, start_ne.1, start.row, start.col
        );
        println!(
            "goal       N {:.2} m, E {:.2} m (row {}, col {})",
            goal_ne.0, goal_ne.1, goal.row, goal.col
        );
        println!(
            "path       {} {}: {cost_m:.2} m, {} cells ({} straight, {} diagonal), {:.2} ms",
            found.planner,
            model_name(model),
            found.cells.len(),
            found.straight,
            found.diagonal,
            found.time_us as f64 / 1000.0
        );
        if let Some(c) = summary.get("costmap") {
            println!(
                "costmap    objective {:.2} m (length + {} · cost), min clearance {:.2} m",
                c["objective_m"].as_f64().unwrap_or(f64::NAN),
                g.cost_weight,
                c["min_clearance_m"].as_f64().unwrap_or(f64::INFINITY)
            );
        }
        println!("waypoints  {} (cell centres, collinear pruned)", rows.len());
        let mut wrote: Vec<String> = Vec::new();
        wrote.extend(args.out.iter().map(|p| p.display().to_string()));
        wrote.extend(args.plot.iter().map(|p| p.display().to_string()));
        if !wrote.is_empty() {
            println!("wrote      {}", wrote.join(", "));
        }
    }
    Ok(())
}

/// JSON has no infinity: a clearance on a map without obstacles is `null`.
fn json_f64(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

fn print_show(grid: &Grid2, start: Cell, goal: Cell, path: &[Cell], field: Option<&DistanceField>) {
    if grid.rows() > SHOW_MAX_ROWS || grid.cols() > SHOW_MAX_COLS {
        eprintln!(
            "--show: the grid is {} × {} cells; text output is for grids up to {SHOW_MAX_COLS} × {SHOW_MAX_ROWS} (use --plot)",
            grid.rows(),
            grid.cols()
        );
        return;
    }
    println!("workspace (north up; {})", show::WORKSPACE_LEGEND);
    print!(
        "{}",
        show::workspace(grid, Some(start), Some(goal), path, field)
    );
    if let Some(field) = field {
        println!("\ndistance matrix (cells; {})", show::MATRIX_LEGEND);
        print!("{}", show::distance_matrix(field, Some(start)));
    }
    if !path.is_empty() {
        let cells: Vec<String> = path
            .iter()
            .map(|c| format!("({},{})", c.row, c.col))
            .collect();
        println!("\npath (row,col): {}", cells.join(" → "));
    }
}

fn write_heatmap(
    path: &Path,
    grid: &Grid2,
    values: &[f64],
    route: &[Cell],
    start: Cell,
    goal: Cell,
) -> Result<()> {
    if !is_ext(path, &["png"]) {
        return Err(bad_input(format!(
            "--plot {}: grid-map heat maps are PNG; use a .png file name",
            path.display()
        )));
    }
    let fallback;
    let values = if values.len() == grid.len() {
        values
    } else {
        fallback = vec![0.0; grid.len()];
        &fallback
    };
    let map = skyplan_plot::Heatmap {
        rows: grid.rows(),
        cols: grid.cols(),
        values,
        blocked: grid.blocked_cells(),
        path: route,
        start: Some(start),
        goal: Some(goal),
    };
    let bytes = skyplan_plot::render_heatmap_png(&map, 1000).or_exit(Kind::Runtime)?;
    write_atomic(path, &bytes)
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

/// Runs the ride; `Ok(Some(failure))` when it stopped short (its summary is already printed).
fn navigate_inner(args: NavigateArgs) -> Result<Option<Failure>> {
    let spec = GridSpec {
        alt_m: args.alt_m,
        safety_m: args.safety_m,
        cell_m: args.cell_m,
    };
    let g = &args.grid;
    let map = load_map(args.map.as_deref(), spec, g)?;
    let grid = &map.grid;
    let model = model_of(args.connectivity, args.corner_cutting)?;
    let (start_default, _) = map.defaults.unzip();
    let (start_drawn, target_drawn) = map.drawn.unzip();
    let (start, start_ne) = endpoint(
        &map,
        "source",
        "--start-ne",
        args.start_ne,
        start_default,
        start_drawn,
    )?;
    let target_pairs: Vec<Pair> = match (&args.targets, &args.targets_file) {
        (Some(t), _) => t.0.clone(),
        (None, Some(path)) => read_targets_file(path)?,
        (None, None) => match (target_drawn, map.defaults) {
            (Some(c), _) => {
                let (n, e) = grid.center_ne(c);
                vec![Pair(n, e)]
            }
            (None, Some((_, goal))) => vec![Pair(goal.0, goal.1)],
            (None, None) => {
                let (_, ne) = endpoint(&map, "target", "--targets", None, None, None)?;
                vec![Pair(ne.0, ne.1)]
            }
        },
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
        weight: g.cost_weight,
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
        "map": map.name,
        "move_model": model_name(model),
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
            "cost_weight": g.cost_weight,
        },
        "inflation_time_us": inflate_us,
        "ride_time_us": ride_us,
    });
    if g.show {
        let goal = run.legs.last().map_or(start, |l| l.target);
        print_show(grid, start, goal, &run.trace, None);
    }
    if let Some(path) = &args.plot {
        let values: Vec<f64> = costmap.normalised().iter().map(|&c| f64::from(c)).collect();
        let goal = run.legs.last().map_or(start, |l| l.target);
        write_heatmap(path, grid, &values, &run.trace, start, goal)?;
    }
    if args.json {
        println!("{summary}");
    } else {
        println!(
            "map        {}: {} × {} cells of {} m",
            map.name,
            grid.rows(),
            grid.cols(),
            cell_m
        );
        for (k, l) in run.legs.iter().enumerate() {
            let (n, e) = grid.center_ne(l.target);
            let how = if l.reached {
                "reached"
            } else if l.replaced {
                "replaced"
            } else {
                "not reached"
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
    Ok(match run.failure {
        Some(e) if !run.reached => Some(nav_failure(e, grid)),
        _ => None,
    })
}
