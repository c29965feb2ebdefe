//! `skyplan plan`: options → the planning API → files, picture and summary.

use crate::args::PlanArgs;
use crate::exit::{Classify, Failure, Kind, Result, bad_input};
use crate::files::{Target, output_target, read_bytes, write_target};
use crate::picture::PictureKind;
use crate::report::{Human, Written};
use skyplan_cspace::Cell;
use skyplan_export::Format;
use skyplan_plan::{Plan, PlanRequest, PlannerId, Session, World};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The waypoint file and its format: the given path, and the given format name (or the file's
/// extension).
pub(crate) fn output_file(out: &Path, format: Option<&str>) -> Result<(Target, Format)> {
    let format = match format {
        Some(name) => Format::from_name(name).ok_or_else(|| {
            bad_input(format!("--format: expected json, csv, hdf5, geojson or plan, found {name:?}"))
        })?,
        None => Format::from_path(out).ok_or_else(|| {
            bad_input(format!(
                "--out {}: cannot tell the format from the extension; use .json .csv .h5 .geojson .plan or --format",
                out.display()
            ))
        })?,
    };
    Ok((output_target("--out", out)?, format))
}

/// A waypoint file: the path as given, where it goes, its format.
pub(crate) type WaypointFile = (PathBuf, Target, Format);

/// Writes `mission` (with a summary of its plan) to a waypoint file; a `.plan` file carries
/// `fence` as its `geoFence`, and its altitudes above mean sea level when the home's height is
/// known (`home_amsl_m`: a plan over a DEM).
pub(crate) fn write_waypoints(
    (_, target, format): &WaypointFile,
    mission: &skyplan_mission::Mission,
    summary: &serde_json::Value,
    (fence, home_amsl_m): (&skyplan_export::GeoFence, Option<f64>),
) -> Result<()> {
    let options = skyplan_export::ExportOptions {
        qgc_plan: skyplan_export::QgcPlanOptions {
            geo_fence: fence.clone(),
            home_amsl_m,
            ..Default::default()
        },
    };
    let bytes =
        skyplan_export::encode_with(*format, mission, summary, &options).or_exit(Kind::Runtime)?;
    write_target(target, &bytes)
}

/// The `geoFence` of a plan's no-fly zones (`request.no_fly`, already checked by the plan) and
/// what it says, one line per zone: decided by the same rules as the vehicle's fence
/// (`skyplan_flight::fence::fence_shapes`) — the inclusion boundaries, and the exclusion
/// zones whose band grown by the margin meets the route's altitudes; an inclusion polygon's
/// holes become exclusion polygons; an exclusion polygon's holes, which a fence cannot carry,
/// are dropped (the vehicle keeps out of them too), and refused when the route flies in one.
/// No zones, or no mission in lat/lon: an empty fence.
pub(crate) fn geo_fence(
    request: &PlanRequest,
    plan: &Plan,
) -> Result<(skyplan_export::GeoFence, Vec<String>)> {
    use skyplan_flight::fence::{FenceShape, RouteForFence, fence_shapes};
    let mut fence = skyplan_export::GeoFence::default();
    let (Some(Ok(zones)), Some(mission)) = (
        request
            .no_fly
            .as_deref()
            .map(skyplan_map::nofly::parse_no_fly),
        &plan.mission,
    ) else {
        return Ok((fence, Vec::new()));
    };
    let alts = mission.waypoints.iter().map(|w| w.alt_m);
    let route = RouteForFence {
        points_lat_lon_deg: mission
            .waypoints
            .iter()
            .map(|w| [w.lat_deg, w.lon_deg])
            .collect(),
        alt_range_m: [
            alts.clone().fold(f64::INFINITY, f64::min),
            alts.fold(f64::NEG_INFINITY, f64::max),
        ],
        margin_m: plan.spec.safety_m,
    };
    let decided = fence_shapes(&zones, &route)
        .map_err(|e| bad_input(format!("the .plan file's geoFence: {}", e.0)))?;
    for shape in decided.shapes {
        match shape {
            FenceShape::Polygon {
                inclusion,
                vertices_lat_lon_deg,
            } => fence.polygons.push(skyplan_export::FencePolygon {
                inclusion,
                vertices_lat_lon_deg,
            }),
            FenceShape::Circle {
                inclusion,
                centre_lat_lon_deg,
                radius_m,
            } => fence.circles.push(skyplan_export::FenceCircle {
                inclusion,
                centre_lat_lon_deg,
                radius_m,
            }),
        }
    }
    Ok((fence, decided.notes))
}

/// Every output of a run, checked before planning so that a failing run writes nothing.
struct Outputs {
    waypoints: Option<WaypointFile>,
    plot: Option<(PathBuf, Target, PictureKind)>,
    roadmap: Option<(PathBuf, Target)>,
    samples: Option<(PathBuf, Target, bool)>,
}

fn check_outputs(
    args: &PlanArgs,
    cfg: &crate::config::Config,
    world: &World,
    planner: PlannerId,
    trajectory: bool,
) -> Result<Outputs> {
    let given_out = args.out.clone().or(cfg.path(&cfg.text.out));
    let format = args.format.clone().or(cfg.text.format.clone());
    let waypoints = match (given_out, world.frame()) {
        (Some(out), None) => {
            return Err(bad_input(format!(
                "--out {}: waypoint files carry lat/lon; {} has no geodetic home: pass --home LAT,LON",
                out.display(),
                world.name()
            )));
        }
        // `--json` puts the plan on stdout: no waypoint file unless one is asked for.
        (None, Some(_)) if args.json => None,
        (out, Some(_)) => {
            let out = out.unwrap_or_else(|| PathBuf::from("waypoints.json"));
            let (target, format) = output_file(&out, format.as_deref())?;
            Some((out, target, format))
        }
        (None, None) => None,
    };
    let plot = (args.plot.clone().or(cfg.path(&cfg.text.plot)))
        .map(|p| {
            let kind = crate::picture::kind_for(&p, planner)?;
            Ok::<_, Failure>((p.clone(), output_target("--plot", &p)?, kind))
        })
        .transpose()?;
    let prm = matches!(planner, PlannerId::Prm | PlannerId::LazyPrm);
    if !prm && (args.save_roadmap.is_some() || args.load_roadmap.is_some()) {
        return Err(bad_input(
            "--save-roadmap and --load-roadmap need --planner prm or lazy-prm",
        ));
    }
    let roadmap = (args.save_roadmap.as_ref())
        .map(|p| Ok::<_, Failure>((p.clone(), output_target("--save-roadmap", p)?)))
        .transpose()?;
    let samples = match &args.samples {
        None => None,
        Some(_) if !trajectory => {
            return Err(bad_input(
                "--samples writes a trajectory's samples: add --trajectory",
            ));
        }
        Some(p) => {
            let ext = p
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase);
            let hdf5 = match ext.as_deref() {
                Some("csv") => false,
                Some("h5" | "hdf5") => true,
                _ if p.as_os_str() == "-" => false,
                _ => {
                    return Err(bad_input(format!(
                        "--samples {}: expected a .csv or .h5 file (or - for CSV on standard output)",
                        p.display()
                    )));
                }
            };
            Some((p.clone(), output_target("--samples", p)?, hdf5))
        }
    };
    let outputs = Outputs {
        waypoints,
        plot,
        roadmap,
        samples,
    };
    let on_stdout = outputs.on_stdout();
    if on_stdout.len() + usize::from(args.json) > 1 {
        let mut names = on_stdout;
        if args.json {
            names.push("--json");
        }
        return Err(bad_input(format!(
            "{} would all write to standard output; send all but one to a file",
            names.join(" and ")
        )));
    }
    Ok(outputs)
}

impl Outputs {
    /// The options whose output goes to standard output (`-`).
    fn on_stdout(&self) -> Vec<&'static str> {
        let mut names = Vec::new();
        if matches!(&self.waypoints, Some((_, Target::Stdout, _))) {
            names.push("--out -");
        }
        if matches!(&self.plot, Some((_, Target::Stdout, _))) {
            names.push("--plot -");
        }
        if matches!(&self.roadmap, Some((_, Target::Stdout))) {
            names.push("--save-roadmap -");
        }
        if matches!(&self.samples, Some((_, Target::Stdout, _))) {
            names.push("--samples -");
        }
        names
    }
}

/// On a grid map without a default start or goal, ask on a terminal.
fn prompt_missing(world: &World, request: &mut PlanRequest) -> Result<()> {
    let (Some(grid), true) = (world.fixed_grid(), std::io::stdin().is_terminal()) else {
        return Ok(());
    };
    let (default_start, default_goal) = world.default_endpoints_ne();
    if request.start_ne.is_none() && request.start_lla.is_none() && default_start.is_none() {
        request.start_ne = Some(crate::show::ask_position(grid, "start")?);
    }
    if request.goal_ne.is_none() && request.goal_lla.is_none() && default_goal.is_none() {
        request.goal_ne = Some(crate::show::ask_position(grid, "goal")?);
    }
    Ok(())
}

pub fn run(args: PlanArgs) -> Result<()> {
    crate::exit::print_json_failure(args.json, run_inner(args))
}

fn run_inner(args: PlanArgs) -> Result<()> {
    let t0 = Instant::now();
    let crate::world_load::Resolved {
        world,
        limits,
        mut request,
        config,
    } = crate::world_load::resolve(&args.route)?;
    let planner = request.planner.unwrap_or_default();
    let trajectory = request.trajectory == Some(true);
    let outputs = check_outputs(&args, &config, &world, planner, trajectory)?;
    // A document on stdout (`--json`, `--out -`) is all stdout carries: the rest is for people.
    let human = Human::when_stdout_is_data(args.json || !outputs.on_stdout().is_empty());
    request.geometry = Some(outputs.plot.is_some() || args.show);
    request.roadmap.save = outputs.roadmap.is_some();
    if let Some(path) = &args.load_roadmap {
        request.roadmap.load = Some((path.display().to_string(), read_bytes(path)?));
    }
    prompt_missing(&world, &mut request)?;
    let mut session = Session::new(world).with_limits(limits);
    let save_preprocess = preprocess_files(&args, planner, &mut session, &request)?;
    let working = crate::show::spinner(format!("planning with {planner}"));
    let planned = session.plan(&request);
    working.finish_and_clear();
    let plan = match planned {
        Ok(plan) => plan,
        Err(f) => {
            if args.show && f.kind == skyplan_plan::FailureKind::NoPath {
                show_failure(human, &mut session, &request);
            }
            return Err(f.into());
        }
    };
    if let Some(path) = &args.preprocess {
        // A table for another grid loads, but this plan's grid then builds its own.
        let what = [
            "jps_plus_table",
            "contraction_hierarchy",
            "subgoal_graph",
            "first_move_table",
        ];
        if what
            .iter()
            .any(|k| plan.details.get(*k).and_then(|v| v.as_str()) == Some("built"))
        {
            return Err(bad_input(format!(
                "--preprocess {}: built for another grid or corner rule than this plan's ({} m altitude, {} m margin, {} m cells); save one with --save-preprocess and these options",
                path.display(),
                plan.spec.alt_m,
                plan.spec.safety_m,
                plan.spec.cell_m
            )));
        }
    }
    if let Some(path) = &save_preprocess {
        // The table or hierarchy the plan used (the session keeps it: nothing is built again),
        // streamed from its memory into a file that appears only once complete.
        crate::files::write_atomic_with(path, |out| {
            match planner {
                PlannerId::Ch => session.save_ch(&request, out),
                PlannerId::Subgoal => session.save_subgoal(&request, out),
                PlannerId::FirstMove => session.save_first_move(&request, out),
                _ => session.save_jps_plus(&request, out),
            }
            .map(|_| ())
            .map_err(|f| std::io::Error::other(f.message))
        })?;
    }
    // A .plan file carries the zones as its geoFence: decided (and possibly refused) before
    // anything is written.
    let writes_plan = matches!(&outputs.waypoints, Some((_, _, Format::QgcPlan)));
    let (fence, fence_notes) = if writes_plan {
        geo_fence(&request, &plan)?
    } else {
        Default::default()
    };
    let zones = crate::picture::zones_of(session.world(), &request);
    let written = write_outputs(session.world(), &plan, &outputs, (&fence, &zones))?;
    if args.show {
        show_plan(human, &plan, &request);
    }
    if args.json {
        println!(
            "{}",
            crate::report::json_report(&plan, &written, t0.elapsed().as_micros() as u64)
        );
    } else {
        let wall_ms = t0.elapsed().as_secs_f64() * 1000.0;
        human.print(&crate::report::summary(&plan, &written, wall_ms));
        for note in &fence_notes {
            human.print(&format!("geofence   {note}\n"));
        }
    }
    Ok(())
}

/// `--preprocess` (loaded into the session before planning) and `--save-preprocess` (its target,
/// checked before planning so that a failing run writes nothing): for `jps-plus` a JPS+ table,
/// for `ch` a contraction hierarchy, for `subgoal` a subgoal graph, for `first-move` a
/// first-move table; `auto` loads any of the four (told apart by its header) and uses it where it answers fastest; other planners
/// build nothing to keep.
fn preprocess_files(
    args: &PlanArgs,
    planner: PlannerId,
    session: &mut Session,
    request: &PlanRequest,
) -> Result<Option<PathBuf>> {
    let (option, path) = match (&args.preprocess, &args.save_preprocess) {
        (Some(p), _) => ("--preprocess", p),
        (None, Some(p)) => ("--save-preprocess", p),
        (None, None) => return Ok(None),
    };
    let loads_any = planner == PlannerId::Auto && args.preprocess.is_some();
    if !loads_any
        && !matches!(
            planner,
            PlannerId::JpsPlus | PlannerId::Ch | PlannerId::Subgoal | PlannerId::FirstMove
        )
    {
        return Err(bad_input(format!(
            "{option} {}: only jps-plus (a JPS+ table), ch (a contraction hierarchy), subgoal (a subgoal graph) and first-move (a first-move table) keep preprocessing, and auto loads any of them; the planner is {planner}",
            path.display()
        )));
    }
    let Some(path) = &args.preprocess else {
        if matches!(output_target("--save-preprocess", path)?, Target::Stdout) {
            return Err(bad_input(
                "--save-preprocess -: the table is binary and large; give a file name",
            ));
        }
        return Ok(Some(path.clone()));
    };
    let shown = path.display();
    let (input, saved) = crate::files::open_preprocess(path)?;
    let kind = match (loads_any, saved.planner()) {
        (false, _) => planner,
        (true, Some(kind)) => kind,
        (true, None) => {
            return Err(bad_input(format!(
                "--preprocess {shown}: {}",
                crate::files::NOT_SAVED
            )));
        }
    };
    match kind {
        PlannerId::Ch => session.load_ch(request, input),
        PlannerId::Subgoal => session.load_subgoal(request, input),
        PlannerId::FirstMove => session.load_first_move(request, input),
        _ => session.load_jps_plus(input),
    }
    .map_err(|f| bad_input(format!("--preprocess {shown}: {}", f.message)))?;
    Ok(None)
}

fn write_outputs(
    world: &World,
    plan: &Plan,
    outputs: &Outputs,
    (fence, zones): (&skyplan_export::GeoFence, &[skyplan_map::nofly::Zone]),
) -> Result<Written> {
    let mut written = Written {
        waypoints: None,
        altitudes: None,
        plot: None,
        roadmap: None,
        samples: None,
    };
    if let Some(file @ (path, _, format)) = &outputs.waypoints {
        let mission = plan
            .mission
            .as_ref()
            .ok_or_else(|| bad_input("waypoint files need a map with a geodetic home"))?;
        let summary =
            serde_json::json!({ "map": plan.map, "planner": plan.planner, "cost_m": plan.cost_m });
        let home_amsl_m = world.terrain().map(|t| t.home_ground_amsl_m());
        write_waypoints(file, mission, &summary, (fence, home_amsl_m))?;
        written.waypoints = Some((path.display().to_string(), format.name()));
        if *format == Format::QgcPlan {
            written.altitudes = Some(match home_amsl_m {
                Some(_) => "above mean sea level, MAV_FRAME_GLOBAL",
                None => "above home, MAV_FRAME_GLOBAL_RELATIVE_ALT",
            });
        }
    }
    if let Some((path, target, kind)) = &outputs.plot {
        write_target(
            target,
            &crate::picture::render(world, plan, kind, None, zones)?,
        )?;
        written.plot = Some(path.display().to_string());
    }
    if let (Some((path, target, hdf5)), Some(t)) = (&outputs.samples, &plan.trajectory) {
        let bytes = if *hdf5 {
            skyplan_export::samples_hdf5(&t.columns, &t.samples)
        } else {
            skyplan_export::samples_csv(&t.columns, &t.samples).map(String::into_bytes)
        }
        .or_exit(Kind::Runtime)?;
        write_target(target, &bytes)?;
        written.samples = Some(path.display().to_string());
    }
    if let (Some((path, target)), Some(bytes)) = (&outputs.roadmap, &plan.saved_roadmap) {
        write_target(target, bytes)?;
        written.roadmap = Some(path.display().to_string());
    }
    Ok(written)
}

fn show_plan(human: Human, plan: &Plan, request: &PlanRequest) {
    let (Some(grid), [Some(s), Some(g)]) =
        (plan.grid_used.as_deref(), [plan.start.cell, plan.goal.cell])
    else {
        eprintln!("--show: text pictures are for grid planners");
        return;
    };
    let (s, g) = (Cell::new(s[0], s[1]), Cell::new(g[0], g[1]));
    let (model, steps) = (plan.spec.move_model, request.counts_steps());
    crate::show::print_to(human, grid, s, g, &plan.path_cells(), model, steps);
}

fn show_failure(human: Human, session: &mut Session, request: &PlanRequest) {
    let Some(grid) = session.world().fixed_grid().cloned() else {
        return;
    };
    let cell = |ne: Option<[f64; 2]>| ne.and_then(|p| grid.cell_at_ne(p[0], p[1]));
    let (ds, dg) = session.world().default_endpoints_ne();
    if let (Some(s), Some(g)) = (cell(request.start_ne.or(ds)), cell(request.goal_ne.or(dg))) {
        // The request's move model as resolved (the default one if the request itself is bad).
        let model = request.spec().map(|s| s.move_model).unwrap_or_default();
        crate::show::print_to(human, &grid, s, g, &[], model, request.counts_steps());
    }
}
