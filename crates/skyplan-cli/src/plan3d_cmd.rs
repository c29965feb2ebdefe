//! `skyplan plan --planner prm|rrt-connect|rrt-star|voxel`: 3D planners among the map's boxes
//! (grown by the margin in all three axes), with per-end altitudes: the sampling planners and the
//! voxel A* (altitude layers, climb cost). Every segment of the result is re-checked against every
//! box before anything is written.

use crate::args::{PlanArgs, PlannerArg, parse_finite};
use crate::exit::{Classify, Failure, Kind, Result, bad_input};
use crate::files::{read_text, write_atomic};
use anyhow::anyhow;
use clap::Args;
use serde_json::json;
use skyplan_mission::Mission;
use skyplan_sampling::{Budget, PlannerKind, Request, Status};
use skyplan_world3::{BoxWorld3, CollisionChecker, Neu, WorldSpec, distance_m};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Options of the 3D planners (flattened into `plan`; `--seed` is shared with random maps).
#[derive(Debug, Args)]
#[command(next_help_heading = "3D planners (prm, lazy-prm, rrt-connect, rrt-star)")]
pub struct Plan3dArgs {
    /// Start altitude above home, metres [default: --alt-m].
    #[arg(long, value_name = "M", value_parser = parse_finite, allow_hyphen_values = true)]
    pub start_alt_m: Option<f64>,
    /// Goal altitude above home, metres [default: --alt-m].
    #[arg(long, value_name = "M", value_parser = parse_finite, allow_hyphen_values = true)]
    pub goal_alt_m: Option<f64>,
    /// Time budget, milliseconds (rrt-star uses all of it; the others stop at the first path) [default: 1000].
    #[arg(long, value_name = "MS")]
    pub time_limit_ms: Option<u64>,
    /// Ceiling of the flight volume, metres [default: 120, at least 10 m above both ends].
    #[arg(long, value_name = "M", value_parser = parse_finite)]
    pub max_alt_m: Option<f64>,
    /// Floor of the flight volume: nothing flies lower, metres [default: 0, the ground].
    #[arg(long, value_name = "M", value_parser = parse_finite, allow_hyphen_values = true)]
    pub min_alt_m: Option<f64>,
    /// voxel: extra cost per metre climbed (0: shortest path) [default: 1].
    #[arg(long, value_name = "W", value_parser = parse_finite)]
    pub climb_weight: Option<f64>,
    /// voxel: horizontal pitch of the voxel lattice, metres [default: 5].
    #[arg(long, value_name = "M", value_parser = parse_finite)]
    pub voxel_m: Option<f64>,
    /// voxel: vertical pitch between altitude layers, metres [default: 5].
    #[arg(long, value_name = "M", value_parser = parse_finite)]
    pub layer_m: Option<f64>,
    /// prm, lazy-prm: save the roadmap after the run (JSON with the map's fingerprint).
    #[arg(long, value_name = "FILE")]
    pub save_roadmap: Option<PathBuf>,
    /// prm, lazy-prm: start from a saved roadmap (refused if built for another map, margin or volume).
    #[arg(long, value_name = "FILE")]
    pub load_roadmap: Option<PathBuf>,
}

fn kind_of(planner: Option<PlannerArg>) -> Option<PlannerKind> {
    match planner? {
        PlannerArg::Prm => Some(PlannerKind::Prm),
        PlannerArg::LazyPrm => Some(PlannerKind::LazyPrm),
        PlannerArg::RrtConnect => Some(PlannerKind::RrtConnect),
        PlannerArg::RrtStar => Some(PlannerKind::RrtStar),
        _ => None,
    }
}

/// True if `plan` runs here; refuses the 3D-only options with other planners.
pub fn handles(args: &PlanArgs) -> Result<bool> {
    let a = &args.plan3d;
    let voxel = args.planner == Some(PlannerArg::Voxel);
    let prm = matches!(args.planner, Some(PlannerArg::Prm | PlannerArg::LazyPrm));
    if !prm && (a.save_roadmap.is_some() || a.load_roadmap.is_some()) {
        return Err(bad_input(
            "--save-roadmap and --load-roadmap need --planner prm or lazy-prm",
        ));
    }
    if !voxel && (a.climb_weight.is_some() || a.voxel_m.is_some() || a.layer_m.is_some()) {
        return Err(bad_input(
            "--climb-weight, --voxel-m and --layer-m need --planner voxel",
        ));
    }
    if voxel || kind_of(args.planner).is_some() {
        return Ok(true);
    }
    if a.start_alt_m.is_some()
        || a.goal_alt_m.is_some()
        || a.time_limit_ms.is_some()
        || a.max_alt_m.is_some()
        || a.min_alt_m.is_some()
    {
        return Err(bad_input(
            "--start-alt-m, --goal-alt-m, --time-limit-ms, --min-alt-m and --max-alt-m need a 3D planner: --planner prm, rrt-connect, rrt-star or voxel",
        ));
    }
    Ok(false)
}

/// Runs a 3D planner.
pub fn run(args: PlanArgs) -> Result<()> {
    let t0 = Instant::now();
    let voxel = args.planner == Some(PlannerArg::Voxel);
    let kind = kind_of(args.planner);
    if kind.is_none() && !voxel {
        return Err(bad_input("not a 3D planner"));
    }
    let planner_name = kind.map_or("voxel", PlannerKind::name);
    if args.grid.random.is_some() {
        return Err(bad_input(
            "--random makes a grid; 3D planners need an FCND colliders map (--map FILE.csv)",
        ));
    }
    if let Some(p) = &args.plot
        && skyplan_plot::PlotFormat::from_path(p).is_none()
    {
        return Err(bad_input(format!(
            "--plot {}: expected a .png or .svg file name",
            p.display()
        )));
    }
    let crate::colliders_query::CollidersQuery {
        map_name,
        map,
        frame,
        cfg,
        alt_m,
        safety_m,
        start_ne,
        goal_ne,
    } = crate::colliders_query::resolve(&args)?;
    let start: Neu = [
        start_ne.0,
        start_ne.1,
        args.plan3d.start_alt_m.unwrap_or(alt_m),
    ];
    let goal: Neu = [
        goal_ne.0,
        goal_ne.1,
        args.plan3d.goal_alt_m.unwrap_or(alt_m),
    ];
    let max_alt_m = args
        .plan3d
        .max_alt_m
        .unwrap_or_else(|| 120f64.max(start[2] + 10.0).max(goal[2] + 10.0));
    let time_limit_ms = args.plan3d.time_limit_ms.unwrap_or(1000);
    if time_limit_ms == 0 {
        return Err(bad_input("--time-limit-ms: expected at least 1"));
    }
    let seed = args.grid.seed;
    let start_heading_rad = args
        .start_heading_deg
        .or(cfg.start_heading_deg)
        .unwrap_or(0.0)
        .to_radians();
    let (out, format) = crate::plan_cmd::output_file(
        args.out.clone().or(cfg.out.clone()),
        args.format.clone().or(cfg.format.clone()),
    )?;

    let min_alt_m = args.plan3d.min_alt_m.unwrap_or(0.0);
    if min_alt_m >= max_alt_m {
        return Err(bad_input(format!(
            "--min-alt-m {min_alt_m}: expected below the ceiling {max_alt_m} m"
        )));
    }
    let spec = WorldSpec {
        safety_m,
        min_alt_m,
        max_alt_m,
        margin_bounds_m: 0.0,
    };
    let t_world = Instant::now();
    let world = BoxWorld3::new(&map.boxes, &spec).map_err(|e| bad_input(format!("{e}")))?;
    let world_us = t_world.elapsed().as_micros() as u64;
    let request = Request {
        start,
        goal,
        seed,
        budget: Budget::time(Duration::from_millis(time_limit_ms)),
        range_m: None,
        simplify: true,
    };
    let mut plot_edges: Vec<(Neu, Neu)> = Vec::new();
    let mut voxel_json = serde_json::Value::Null;
    let mut raw_path: Vec<Neu> = Vec::new();
    let mut roadmap_json = serde_json::Value::Null;
    let mut roadmap_bytes: Option<Vec<u8>> = None;
    let roadmap_io = args.plan3d.save_roadmap.is_some() || args.plan3d.load_roadmap.is_some();
    let solution = match kind {
        Some(k @ (PlannerKind::Prm | PlannerKind::LazyPrm))
            if args.plot.is_some() || roadmap_io =>
        {
            // The same run as `skyplan_sampling::plan`, keeping the roadmap for the picture and
            // the file (or starting from a saved one).
            let (roadmap, mut solution) =
                run_prm(&args.plan3d, &world, k, seed, start, goal, request.budget)?;
            let st = roadmap.stats;
            roadmap_json = json!({
                "vertices": roadmap.vertices().len(),
                "edges": roadmap.edges(),
                "unchecked_edges": roadmap.unchecked_edges(),
                "edges_tested": st.edges_tested,
                "edges_removed": st.edges_removed,
                "connector_tests": st.connector_tests,
                "build_us": st.build_us,
                "loaded_from": args.plan3d.load_roadmap.as_ref().map(|p| p.display().to_string()),
                "saved_to": args.plan3d.save_roadmap.as_ref().map(|p| p.display().to_string()),
            });
            if args.plan3d.save_roadmap.is_some() {
                let bytes = roadmap.to_json(&world);
                roadmap_json["saved_bytes"] = json!(bytes.len());
                roadmap_bytes = Some(bytes);
            }
            let points = roadmap.vertices();
            plot_edges = roadmap
                .edge_list()
                .into_iter()
                .map(|(a, b)| (points[a as usize], points[b as usize]))
                .collect();
            if solution.status == Status::Exact {
                use rand::SeedableRng;
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_5eed);
                raw_path = solution.path.clone();
                solution.path =
                    skyplan_sampling::shortcut::simplify(&world, &solution.path, &mut rng, 200);
                solution.cost_m = skyplan_world3::path_length_m(&solution.path);
            }
            solution
        }
        Some(kind) if args.plot.is_some() => {
            // The same run as `skyplan_sampling::plan`, keeping the trees for the picture.
            let (solution, tree) = skyplan_sampling::plan_with_tree(&world, kind, &request);
            plot_edges = tree;
            solution
        }
        Some(kind) => skyplan_sampling::plan(&world, kind, &request),
        None => {
            let (solution, raw, info) = run_voxel(&args.plan3d, &world, start, goal, safety_m)?;
            raw_path = raw;
            voxel_json = info;
            solution
        }
    };
    let where_ = |p: Neu| format!("N {:.2} m, E {:.2} m, altitude {:.2} m", p[0], p[1], p[2]);
    let why_invalid = |p: Neu| {
        let b = world.bounds();
        if p[2] < b.min[2] && b.min[2] > 0.0 {
            format!("below --min-alt-m {} m", b.min[2])
        } else if p[2] < b.min[2] {
            "below the ground".to_string()
        } else if !b.contains(p) {
            format!(
                "outside the flight volume N {:.1}..{:.1}, E {:.1}..{:.1}, altitude {:.1}..{:.1} m",
                b.min[0], b.max[0], b.min[1], b.max[1], b.min[2], b.max[2]
            )
        } else {
            format!("within {safety_m} m of an obstacle")
        }
    };
    match solution.status {
        Status::Exact => {}
        Status::InvalidStart => {
            return Err(bad_input(format!(
                "start {} is {}",
                where_(start),
                why_invalid(start)
            )));
        }
        Status::InvalidGoal => {
            return Err(bad_input(format!(
                "goal {} is {}",
                where_(goal),
                why_invalid(goal)
            )));
        }
        Status::Timeout | Status::Approximate => {
            let nearest = match solution.status {
                Status::Approximate => format!(
                    "; the nearest point reached is {:.2} m from the goal",
                    solution.goal_gap_m
                ),
                _ => String::new(),
            };
            return Err(Failure {
                kind: Kind::NoPath,
                error: anyhow!(
                    "{}: no path from {} to {} within {time_limit_ms} ms ({} samples, {} vertices, status {}){nearest}",
                    planner_name,
                    where_(start),
                    where_(goal),
                    solution.iterations,
                    solution.vertices,
                    solution.status.name()
                ),
            });
        }
    }
    // The independent final check: every segment against every box.
    if let Some(k) = skyplan_world3::first_blocked_segment(&world.brute_force(), &solution.path) {
        return Err(Failure {
            kind: Kind::Runtime,
            error: anyhow!("internal error: segment {k} of the path failed the exact re-check"),
        });
    }
    let mission = Mission::from_points_nea(&frame, &solution.path, start_heading_rad)
        .or_exit(Kind::BadInput)?;
    let straight_line_m = distance_m(start, goal);
    let mut summary = json!({
        "map": map_name,
        "obstacles": map.boxes.len(),
        "home": { "lat_deg": map.home.lat_deg, "lon_deg": map.home.lon_deg },
        "planner": planner_name,
        "planner_status": solution.status.name(),
        "seed": seed,
        "time_limit_ms": time_limit_ms,
        "safety_m": safety_m,
        "flight_volume": { "min": world.bounds().min, "max": world.bounds().max },
        "start": { "north_m": start[0], "east_m": start[1], "alt_m": start[2] },
        "goal": { "north_m": goal[0], "east_m": goal[1], "alt_m": goal[2] },
        "cost_m": solution.cost_m,
        "straight_line_m": straight_line_m,
        "iterations": solution.iterations,
        "vertices": solution.vertices,
        "first_solution_us": solution.first_solution_us,
        "search_time_us": solution.elapsed_us,
        "world_build_us": world_us,
        "mission_length_m": mission.length_3d_m(),
        "outputs": { "waypoints": out.display().to_string(), "format": format.name() },
    });
    if !voxel_json.is_null() {
        summary["voxel"] = voxel_json.clone();
    }
    if !roadmap_json.is_null() {
        summary["roadmap"] = roadmap_json;
    }
    if let Some(p) = &args.plot {
        summary["outputs"]["plot"] = json!(p.display().to_string());
    }
    let bytes = skyplan_export::encode(format, &mission, &summary).or_exit(Kind::Runtime)?;
    write_atomic(&out, &bytes)?;
    if let (Some(path), Some(bytes)) = (&args.plan3d.save_roadmap, &roadmap_bytes) {
        write_atomic(path, bytes)?;
    }
    if let Some(plot_path) = &args.plot {
        let title = format!(
            "{map_name}: {planner_name}, {:.0} m, margin {safety_m} m",
            solution.cost_m
        );
        let edges_label = match kind {
            Some(PlannerKind::Prm) => "PRM roadmap",
            Some(PlannerKind::LazyPrm) => "lazy PRM roadmap (unchecked edges included)",
            Some(PlannerKind::RrtConnect) => "RRT-Connect trees",
            Some(PlannerKind::RrtStar) => "RRT* tree",
            _ => "",
        };
        let scene = skyplan_plot::Scene3d {
            title,
            obstacles: &map.boxes,
            safety_m,
            path: &solution.path,
            raw_path: &raw_path,
            raw_label: if voxel {
                "voxel path"
            } else {
                "before shortcutting"
            },
            edges: &plot_edges,
            edges_label,
        };
        let plot_format = skyplan_plot::PlotFormat::from_path(plot_path)
            .ok_or_else(|| bad_input("--plot: expected .png or .svg"))?;
        let bytes =
            skyplan_plot::render_plan3d(&scene, plot_format, 1500, 900).or_exit(Kind::Runtime)?;
        write_atomic(plot_path, &bytes)?;
    }
    if args.json {
        let mut full = summary;
        full["status"] = json!("ok");
        full["waypoints"] = json!(mission.rows());
        full["waypoints_lla"] = json!(
            mission
                .waypoints
                .iter()
                .map(|w| [w.lat_deg, w.lon_deg])
                .collect::<Vec<_>>()
        );
        full["wall_time_us"] = json!(t0.elapsed().as_micros() as u64);
        println!("{full}");
    } else {
        let ms = |us: u64| us as f64 / 1000.0;
        println!(
            "map        {map_name}: {} obstacles, boxes grown by {safety_m} m in all three axes, indexed in {:.2} ms",
            map.boxes.len(),
            ms(world_us)
        );
        println!("start      {}", where_(start));
        println!("goal       {}", where_(goal));
        if voxel {
            let v = &voxel_json;
            println!(
                "voxels     {} × {} × {} lattice ({} m, layers every {} m): {} voxels, {} blocked, built in {:.2} ms",
                v["dims"][0],
                v["dims"][1],
                v["dims"][2],
                v["cell_m"],
                v["layer_m"],
                v["voxels"],
                v["blocked"],
                ms(v["build_us"].as_u64().unwrap_or(0))
            );
            println!(
                "path       voxel A* (climb weight {}): {:.2} m ({:.3} × the straight line), climbs {:.1} m, cost {:.2} (lattice optimum {:.2}), {} expansions, {} segment tests, {:.2} ms",
                v["climb_weight"],
                solution.cost_m,
                solution.cost_m / straight_line_m.max(f64::MIN_POSITIVE),
                v["climb_m"].as_f64().unwrap_or(0.0),
                v["objective"].as_f64().unwrap_or(0.0),
                v["lattice_objective"].as_f64().unwrap_or(0.0),
                solution.iterations,
                v["edge_checks"],
                ms(solution.elapsed_us)
            );
        } else {
            println!(
                "path       {} (seed {seed}): {:.2} m ({:.3} × the straight line), first solution after {:.2} ms, {} samples, {} vertices, {:.2} ms",
                planner_name,
                solution.cost_m,
                solution.cost_m / straight_line_m.max(f64::MIN_POSITIVE),
                ms(solution.first_solution_us.unwrap_or(0)),
                solution.iterations,
                solution.vertices,
                ms(solution.elapsed_us)
            );
        }
        if let Some(r) = summary.get("roadmap") {
            let file = |k: &str, what: &str| {
                r[k].as_str()
                    .map(|p| format!(", {what} {p}"))
                    .unwrap_or_default()
            };
            println!(
                "roadmap    {} vertices, {} edges ({} unchecked), {} edge tests, {} edges removed{}{}",
                r["vertices"],
                r["edges"],
                r["unchecked_edges"],
                r["edges_tested"],
                r["edges_removed"],
                file("loaded_from", "loaded from"),
                file("saved_to", "saved to")
            );
        }
        println!(
            "waypoints  {} after exactly re-checked shortcutting; every segment re-checked against all {} boxes",
            mission.waypoints.len(),
            map.boxes.len()
        );
        let plot = args
            .plot
            .as_ref()
            .map(|p| format!(", {}", p.display()))
            .unwrap_or_default();
        println!("wrote      {} ({}){plot}", out.display(), format.name());
        println!(
            "time       {:.2} ms in all",
            t0.elapsed().as_secs_f64() * 1000.0
        );
    }
    Ok(())
}

/// `--planner prm|lazy-prm` keeping the roadmap: built and grown as in `skyplan_sampling::plan`,
/// or loaded from `--load-roadmap` (refused with exit 2 if built for another world or planner)
/// and grown from there.
fn run_prm(
    a: &Plan3dArgs,
    world: &BoxWorld3,
    kind: PlannerKind,
    seed: u64,
    start: Neu,
    goal: Neu,
    budget: Budget,
) -> Result<(skyplan_sampling::prm::Roadmap, skyplan_sampling::Solution)> {
    use skyplan_sampling::prm::{PrmConfig, Roadmap, solve, solve_from};
    let lazy = kind == PlannerKind::LazyPrm;
    let Some(path) = &a.load_roadmap else {
        let config = PrmConfig {
            seed,
            lazy,
            ..Default::default()
        };
        return Ok(solve(world, start, goal, &config, budget));
    };
    let text = read_text(path)?;
    let roadmap = Roadmap::from_json(text.as_bytes(), world)
        .map_err(|e| bad_input(format!("--load-roadmap {}: {e}", path.display())))?;
    if roadmap.is_lazy() != lazy {
        let built = if roadmap.is_lazy() { "lazy-prm" } else { "prm" };
        return Err(bad_input(format!(
            "--load-roadmap {}: the roadmap was built by --planner {built}; use that planner",
            path.display()
        )));
    }
    Ok(solve_from(world, roadmap, start, goal, 0, budget))
}

/// `--planner voxel`: the voxel grid over the world, one query; the result as a sampling
/// [`skyplan_sampling::Solution`] (iterations = expansions, vertices = voxels), the lattice path,
/// and the voxel details for the JSON summary.
fn run_voxel(
    a: &Plan3dArgs,
    world: &BoxWorld3,
    start: Neu,
    goal: Neu,
    safety_m: f64,
) -> Result<(skyplan_sampling::Solution, Vec<Neu>, serde_json::Value)> {
    use skyplan_voxel::{End, Query, VoxelError, VoxelGrid, VoxelSpec};
    let spec = VoxelSpec {
        cell_m: a.voxel_m.unwrap_or(5.0),
        layer_m: a.layer_m.unwrap_or(5.0),
    };
    let climb_weight = a.climb_weight.unwrap_or(1.0);
    if climb_weight < 0.0 {
        return Err(bad_input(format!(
            "--climb-weight {climb_weight}: expected a number ≥ 0"
        )));
    }
    let grid = VoxelGrid::build(world, &spec)
        .map_err(|e| bad_input(format!("--voxel-m/--layer-m: {e}")))?;
    let query = Query {
        start,
        goal,
        climb_weight,
        shortcut: true,
    };
    let at = |p: Neu| format!("N {:.2} m, E {:.2} m, altitude {:.2} m", p[0], p[1], p[2]);
    let route = match grid.plan(&query) {
        Ok(r) => r,
        Err(VoxelError::Invalid(end)) => {
            let p = if end == End::Start { start } else { goal };
            let b = world.bounds();
            let why = if p[2] < b.min[2] {
                format!("below the floor of the flight volume ({} m)", b.min[2])
            } else if !b.contains(p) {
                format!(
                    "outside the flight volume N {:.1}..{:.1}, E {:.1}..{:.1}, altitude {:.1}..{:.1} m",
                    b.min[0], b.max[0], b.min[1], b.max[1], b.min[2], b.max[2]
                )
            } else {
                format!("within {safety_m} m of an obstacle")
            };
            return Err(bad_input(format!("{} {} is {why}", end.name(), at(p))));
        }
        Err(e @ (VoxelError::NoConnector(_) | VoxelError::NoPath { .. })) => {
            return Err(Failure {
                kind: Kind::NoPath,
                error: anyhow!("voxel: no path from {} to {}: {e}", at(start), at(goal)),
            });
        }
        Err(e @ VoxelError::InvalidSpec(_)) => return Err(bad_input(format!("{e}"))),
        Err(e @ VoxelError::Internal(_)) => {
            return Err(Failure {
                kind: Kind::Runtime,
                error: anyhow!("{e}"),
            });
        }
    };
    let dims = grid.dims();
    let info = json!({
        "cell_m": spec.cell_m,
        "layer_m": spec.layer_m,
        "dims": dims,
        "voxels": grid.len(),
        "blocked": grid.blocked_count(),
        "build_us": grid.build_us(),
        "climb_weight": climb_weight,
        "climb_m": route.climb_m,
        "objective": route.cost,
        "lattice_objective": route.raw_cost,
        "lattice_waypoints": route.raw.len(),
        "expansions": route.expansions,
        "edge_checks": route.edge_checks,
    });
    let solution = skyplan_sampling::Solution {
        status: Status::Exact,
        cost_m: route.length_m,
        goal_gap_m: 0.0,
        iterations: route.expansions,
        vertices: grid.len(),
        first_solution_us: Some(route.search_us),
        elapsed_us: route.search_us,
        path: route.path,
    };
    Ok((solution, route.raw, info))
}
