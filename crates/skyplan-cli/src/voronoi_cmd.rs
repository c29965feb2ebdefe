//! `skyplan plan --planner voronoi`: the Voronoi roadmap of the obstacles' grown footprints at
//! the flight altitude (skyplan-roadmap), checked connectors, graph A\*, and the grid (JPS) as
//! the fallback. Every segment is re-checked on the grid before anything is written.

use crate::args::{PlanArgs, PlannerArg};
use crate::exit::{Classify, Failure, Kind, Result, bad_input};
use crate::files::write_atomic;
use anyhow::anyhow;
use serde_json::json;
use skyplan_cspace::{Grid2, GridSpec};
use skyplan_mission::Mission;
use skyplan_roadmap::{Roadmap, RoadmapError, RoadmapSpec};
use std::time::Instant;

/// True if `plan` runs here.
pub fn handles(args: &PlanArgs) -> bool {
    args.planner == Some(PlannerArg::Voronoi)
}

/// Runs the Voronoi planner.
pub fn run(args: PlanArgs) -> Result<()> {
    let t0 = Instant::now();
    if args.grid.random.is_some()
        || args
            .map
            .as_ref()
            .is_some_and(|p| p.extension().is_none_or(|e| e != "csv"))
    {
        return Err(bad_input(
            "--planner voronoi needs an FCND colliders map (--map FILE.csv, or the bundled map)",
        ));
    }
    let plot_format = match &args.plot {
        Some(path) => Some(skyplan_plot::PlotFormat::from_path(path).ok_or_else(|| {
            bad_input(format!("--plot {}: expected .png or .svg", path.display()))
        })?),
        None => None,
    };
    let crate::colliders_query::CollidersQuery {
        map_name,
        map,
        frame,
        cfg,
        alt_m,
        safety_m,
        start_ne: start,
        goal_ne: goal,
    } = crate::colliders_query::resolve(&args)?;
    let cell_m = args.cell_m.or(cfg.cell_m).unwrap_or(1.0);
    let start_heading_rad = args
        .start_heading_deg
        .or(cfg.start_heading_deg)
        .unwrap_or(0.0)
        .to_radians();
    let (out, format) = crate::plan_cmd::output_file(
        args.out.clone().or(cfg.out.clone()),
        args.format.clone().or(cfg.format.clone()),
    )?;

    let spec = GridSpec {
        alt_m,
        safety_m,
        cell_m,
    };
    let grid =
        Grid2::from_colliders(&map, spec).map_err(|e| bad_input(format!("{map_name}: {e}")))?;
    let roadmap = Roadmap::build(&map, &grid, alt_m, safety_m, &RoadmapSpec::default());
    let t_query = Instant::now();
    let route = match roadmap.query(&grid, [start.0, start.1], [goal.0, goal.1]) {
        Ok(r) => r,
        Err(e @ (RoadmapError::StartBlocked(..) | RoadmapError::GoalBlocked(..))) => {
            return Err(bad_input(format!(
                "{e} at {alt_m} m with a {safety_m} m margin"
            )));
        }
        Err(e @ RoadmapError::NoPath) => {
            return Err(Failure {
                kind: Kind::NoPath,
                error: anyhow!(
                    "voronoi: {e} (the graph has {} components)",
                    roadmap.component_count()
                ),
            });
        }
    };
    let query_us = t_query.elapsed().as_micros() as u64;
    // The independent final check on the grid.
    if let Some(k) = skyplan_roadmap::first_blocked_segment(&grid, &route.points_ne) {
        return Err(Failure {
            kind: Kind::Runtime,
            error: anyhow!("internal error: segment {k} of the route failed the exact re-check"),
        });
    }
    let points: Vec<[f64; 3]> = route
        .points_ne
        .iter()
        .map(|p| [p[0], p[1], alt_m])
        .collect();
    let mission =
        Mission::from_points_nea(&frame, &points, start_heading_rad).or_exit(Kind::BadInput)?;
    let stats = roadmap.stats();
    let mut summary = json!({
        "map": map_name,
        "obstacles": map.boxes.len(),
        "home": { "lat_deg": map.home.lat_deg, "lon_deg": map.home.lon_deg },
        "planner": "voronoi",
        "alt_m": alt_m,
        "safety_m": safety_m,
        "cell_m": cell_m,
        "start": { "north_m": start.0, "east_m": start.1 },
        "goal": { "north_m": goal.0, "east_m": goal.1 },
        "cost_m": route.cost_m,
        "graph_cost_m": route.graph_cost_m,
        "components": roadmap.component_count(),
        "largest_component": roadmap.largest_component(),
        "nodes": roadmap.nodes().len(),
        "edges": roadmap.edge_count(),
        "sites": stats.sites,
        "fallback": route.fallback,
        "connectors": [route.connectors.0, route.connectors.1],
        "expansions": route.expansions,
        "build_time_us": stats.build_us,
        "search_time_us": query_us,
        "outputs": { "waypoints": out.display().to_string(), "format": format.name() },
    });
    if let Some(p) = &args.plot {
        summary["outputs"]["plot"] = json!(p.display().to_string());
    }
    let bytes = skyplan_export::encode(format, &mission, &summary).or_exit(Kind::Runtime)?;
    write_atomic(&out, &bytes)?;
    if let (Some(path), Some(plot_format)) = (&args.plot, plot_format) {
        let picture = Picture {
            map: &map,
            grid: &grid,
            roadmap: &roadmap,
            route: &route,
            start,
            goal,
            spec,
            map_name: &map_name,
        };
        write_atomic(path, &picture.render(plot_format)?)?;
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
        println!(
            "map        {map_name}: {} obstacles at {alt_m} m, {safety_m} m margin",
            map.boxes.len()
        );
        println!(
            "roadmap    Voronoi of {} boundary samples: {} nodes, {} exactly free edges, {} components (largest {}), {:.2} ms",
            stats.sites,
            roadmap.nodes().len(),
            roadmap.edge_count(),
            roadmap.component_count(),
            roadmap.largest_component(),
            stats.build_us as f64 / 1000.0
        );
        println!("start      N {:.2} m, E {:.2} m", start.0, start.1);
        println!("goal       N {:.2} m, E {:.2} m", goal.0, goal.1);
        match &route.fallback {
            None => println!(
                "path       voronoi graph A*: {:.2} m ({:.2} m on the graph), {} connectors from the start, {} to the goal, {:.2} ms",
                route.cost_m,
                route.graph_cost_m,
                route.connectors.0,
                route.connectors.1,
                query_us as f64 / 1000.0
            ),
            Some(why) => println!("path       fallback: {why}: {:.2} m", route.cost_m),
        }
        println!(
            "waypoints  {} after the checked shortcut; every segment re-checked on the grid",
            mission.waypoints.len()
        );
        println!("wrote      {} ({})", out.display(), format.name());
        if let Some(path) = &args.plot {
            println!("wrote      {} (picture)", path.display());
        }
    }
    Ok(())
}

/// What `--plot` draws: the grid, the footprints, the Voronoi graph, the connectors, the graph
/// route before the shortcut and the waypoints.
struct Picture<'a> {
    map: &'a skyplan_map::colliders::CollidersMap,
    grid: &'a Grid2,
    roadmap: &'a Roadmap,
    route: &'a skyplan_roadmap::Route,
    start: (f64, f64),
    goal: (f64, f64),
    spec: GridSpec,
    map_name: &'a str,
}

impl Picture<'_> {
    fn render(&self, format: skyplan_plot::PlotFormat) -> Result<Vec<u8>> {
        let spec = self.spec;
        let obstacles: Vec<_> = self
            .map
            .boxes
            .iter()
            .filter(|b| {
                b.top_m() + spec.safety_m > spec.alt_m && b.bottom_m() - spec.safety_m < spec.alt_m
            })
            .copied()
            .collect();
        let seg = |a: [f64; 2], b: [f64; 2]| ((a[0], a[1]), (b[0], b[1]));
        let graph: Vec<_> = self.roadmap.edges().map(|(a, b)| seg(a, b)).collect();
        let mut connectors = Vec::new();
        for end in [self.start, self.goal] {
            let p = [end.0, end.1];
            for q in self.roadmap.connector_nodes(self.grid, p) {
                connectors.push(seg(p, q));
            }
        }
        let raw: Vec<_> = self.route.raw_ne.iter().map(|p| (p[0], p[1])).collect();
        let waypoints: Vec<_> = self.route.points_ne.iter().map(|p| (p[0], p[1])).collect();
        let how = if self.route.fallback.is_some() {
            "grid fallback"
        } else {
            "Voronoi roadmap"
        };
        let scene = skyplan_plot::Scene {
            title: format!(
                "{}, {how} at {} m, {} m margin: {:.1} m, {} waypoints",
                crate::plan_cmd::short_name(self.map_name),
                spec.alt_m,
                spec.safety_m,
                self.route.cost_m,
                waypoints.len()
            ),
            grid: self.grid,
            obstacles: &obstacles,
            raw_path_ne: &raw,
            pruned_path_ne: &waypoints,
            start_ne: Some(self.start),
            goal_ne: Some(self.goal),
            graph_ne: &graph,
            connectors_ne: &connectors,
        };
        skyplan_plot::render(&scene, format, 1000, 1000).or_exit(Kind::Runtime)
    }
}
