//! The human-readable summary of a plan (`skyplan plan` without `--json`): `Display for Plan`.

use crate::plan::Plan;
use serde_json::Value;
use std::fmt;

fn ms(us: u64) -> f64 {
    us as f64 / 1000.0
}

impl Plan {
    /// The summary's `no-fly` line: how many zones the request gave, how many apply, which do
    /// not and why (`None` without zones).
    pub fn no_fly_line(&self) -> Option<String> {
        self.details
            .get("no_fly")
            .and_then(crate::zone_times::summary_line)
    }
}

impl fmt::Display for Plan {
    /// The human summary, a line per aspect (map, grid, ends, path, details, waypoints).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        summary(self, f)
    }
}

fn summary(plan: &Plan, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    match (plan.obstacles, &plan.home) {
        (Some(n), Some(h)) => writeln!(
            f,
            "map        {}: {n} obstacles, home lat {:.6}, lon {:.6}",
            plan.map, h.lat_deg, h.lon_deg
        ),
        _ => writeln!(f, "map        {}", plan.map),
    }?;
    for note in plan
        .details
        .get("map_notes")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
    {
        writeln!(f, "           {note}")?;
    }
    if let Some(g) = &plan.grid {
        let at = match plan.obstacles {
            Some(_) => format!(" at {} m altitude, {} m margin", g.alt_m, g.safety_m),
            None => String::new(),
        };
        writeln!(
            f,
            "grid       {} × {} cells of {} m{at}: {} blocked ({:.1} %), built in {:.2} ms",
            g.rows,
            g.cols,
            g.cell_m,
            g.blocked_cells,
            100.0 * g.blocked_cells as f64 / (f64::from(g.rows) * f64::from(g.cols)).max(1.0),
            ms(plan.timings_us.grid_build_us)
        )?;
    }
    if let Some(v) = plan.details.get("flight_volume") {
        let (lo, hi) = (&v["min"], &v["max"]);
        let num = |x: &Value| x.as_f64().unwrap_or(f64::NAN);
        writeln!(
            f,
            "volume     N {:.1}..{:.1} m, E {:.1}..{:.1} m, altitude {:.1}..{:.1} m, {} m margin around every obstacle",
            num(&lo[0]),
            num(&hi[0]),
            num(&lo[1]),
            num(&hi[1]),
            num(&lo[2]),
            num(&hi[2]),
            plan.spec.safety_m
        )?;
    }
    if let Some(t) = plan.details.get("terrain") {
        let num = |k: &str| t[k].as_f64().unwrap_or(f64::NAN);
        writeln!(
            f,
            "terrain    {} m above the ground everywhere along the route (ground under home {:.1} m above sea level): altitude {:.1} to {:.1} m above home, {:.0} m of climbing",
            num("alt_agl_m"),
            num("home_ground_amsl_m"),
            num("lowest_alt_m"),
            num("highest_alt_m"),
            num("climb_m")
        )?;
    }
    if let Some(line) = plan.no_fly_line() {
        writeln!(f, "{line}")?;
    }
    writeln!(
        f,
        "start      {}{}",
        plan.start,
        altitude(plan, plan.start.alt_m)
    )?;
    writeln!(
        f,
        "goal       {}{}",
        plan.goal,
        altitude(plan, plan.goal.alt_m)
    )?;
    path_line(plan, f)?;
    if let Some(octile_m) = plan.octile_optimum_m {
        writeln!(
            f,
            "any-angle  {:.2} m: {:.1} % shorter than the octile optimum {octile_m:.2} m; straight line {:.2} m",
            plan.cost_m,
            100.0 * (1.0 - plan.cost_m / octile_m),
            plan.straight_line_m
        )?;
    }
    details(plan, f)?;
    match (
        plan.grid_path.map(|g| g.waypoint_counts),
        plan.planner.is_cell_search(),
    ) {
        (Some(c), true) => writeln!(
            f,
            "waypoints  {} → {} after pruning → {} after line-of-sight shortcut; mission of {} waypoints, {:.2} m flown",
            c.grid_path, c.after_pruning, c.after_shortcut, c.mission, plan.mission_length_m
        ),
        (Some(c), _) => writeln!(
            f,
            "waypoints  {} → {} after pruning (cell centres); {} waypoints, {:.2} m flown",
            c.grid_path, c.after_pruning, c.mission, plan.mission_length_m
        ),
        (None, _) => writeln!(
            f,
            "waypoints  {}, {:.2} m flown; every segment re-checked against the map",
            plan.waypoints.len(),
            plan.mission_length_m
        ),
    }?;
    if let Some(t) = &plan.trajectory {
        trajectory_lines(t, f)?;
    }
    Ok(())
}

fn trajectory_lines(t: &crate::TrajectoryReport, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    let tr = &t.trajectory;
    let (b, l) = (&tr.bounds, &tr.limits);
    let how = match &tr.fallback_reason {
        None => format!(
            "minimum jerk in a corridor of {} free boxes",
            tr.pieces.len()
        ),
        Some(why) => format!("stopping at each waypoint, because {why}"),
    };
    writeln!(
        f,
        "trajectory {:.1} s, {:.1} m ({how}), made in {:.2} ms; stopping at each waypoint takes {:.1} s, the route at {} m/s {:.1} s",
        t.duration_s,
        t.length_m,
        ms(tr.compute_us),
        t.stop_at_waypoints_s,
        l.max_speed_m_s,
        t.length_over_max_speed_s
    )?;
    writeln!(
        f,
        "           proven: speed ≤ {:.2} of {} m/s, acceleration ≤ {:.2} of {} m/s², jerk ≤ {:.2} of {} m/s³, climb ≤ {:.2} of {} m/s, descent ≤ {:.2} of {} m/s, yaw rate ≤ {:.1} of {} °/s; inside free space",
        b.speed_m_s,
        l.max_speed_m_s,
        b.accel_m_s2,
        l.max_accel_m_s2,
        b.jerk_m_s3,
        l.max_jerk_m_s3,
        b.climb_m_s,
        l.max_climb_m_s,
        b.descent_m_s,
        l.max_descent_m_s,
        b.yaw_rate_deg_s,
        l.max_yaw_rate_deg_s
    )
}

fn altitude(plan: &Plan, alt_m: f64) -> String {
    if plan.planner.info().dims == 3 {
        format!(", altitude {alt_m:.2} m")
    } else {
        String::new()
    }
}

fn path_line(plan: &Plan, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    let info = plan.planner.info();
    let model = plan.move_model.map(|m| format!(" {m}")).unwrap_or_default();
    let shape = match plan.grid_path {
        Some(g) if plan.octile_optimum_m.is_some() => format!("{} turning points", g.path_cells),
        Some(g) => format!(
            "{} cells ({} straight, {} diagonal)",
            g.path_cells, g.straight_moves, g.diagonal_moves
        ),
        None => format!("{} waypoints", plan.waypoints.len()),
    };
    let unit = plan.planner.algorithm().work_unit();
    writeln!(
        f,
        "path       {}{model}: {:.2} m, {shape}, {} {unit}, {:.2} ms",
        info.label,
        plan.cost_m,
        plan.expansions,
        ms(plan.search_time_us)
    )
}

fn details(plan: &Plan, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    let d = &plan.details;
    if let Some(a) = d.get("auto") {
        let label = (a["planner"].as_str())
            .and_then(|p| p.parse::<crate::PlannerId>().ok())
            .map_or("?", |p| p.info().label);
        writeln!(
            f,
            "auto       picked {label}: {}",
            a["why"].as_str().unwrap_or("")
        )?;
    }
    if let Some(c) = d.get("costmap") {
        writeln!(
            f,
            "costmap    objective {:.2} m (length + {} · cost), min clearance {}",
            c["objective_m"].as_f64().unwrap_or(f64::NAN),
            c["cost_weight"],
            c["min_clearance_m"]
                .as_f64()
                .map_or("none within range".to_string(), |m| format!("{m:.2} m"))
        )?;
    }
    if let Some(n) = d.get("nodes") {
        let fallback = match d.get("fallback").and_then(Value::as_str) {
            Some(why) => format!("; grid fallback: {why}"),
            None => String::new(),
        };
        writeln!(
            f,
            "roadmap    Voronoi of {} boundary samples: {n} nodes, {} exactly free edges, {} components (largest {}), {:.2} ms{fallback}",
            d["sites"],
            d["edges"],
            d["components"],
            d["largest_component"],
            d["build_time_us"].as_f64().unwrap_or(0.0) / 1000.0
        )?;
    }
    if let Some(r) = d.get("roadmap") {
        let file = |k: &str, label: &str| {
            r[k].as_str()
                .map(|p| format!(", {label} {p}"))
                .unwrap_or_default()
        };
        writeln!(
            f,
            "roadmap    {} vertices, {} edges ({} unchecked), {} edge tests, {} edges removed{}",
            r["vertices"],
            r["edges"],
            r["unchecked_edges"],
            r["edges_tested"],
            r["edges_removed"],
            file("loaded_from", "loaded from")
        )?;
    }
    if let Some(v) = d.get("voxel") {
        writeln!(
            f,
            "voxels     {} of {} m × {} m layers ({} blocked), built in {:.2} ms; climbed {:.1} m, climb weight {}",
            v["voxels"],
            v["cell_m"],
            v["layer_m"],
            v["blocked"],
            v["build_us"].as_f64().unwrap_or(0.0) / 1000.0,
            v["climb_m"].as_f64().unwrap_or(0.0),
            v["climb_weight"]
        )?;
    }
    Ok(())
}

impl fmt::Display for crate::ride::Ride {
    /// The human summary of a ride (`skyplan navigate` without `--json`): the map, a line per
    /// leg, the ride.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let grid = &self.grid;
        writeln!(
            f,
            "map        {}: {} × {} cells of {} m",
            self.map,
            grid.rows(),
            grid.cols(),
            grid.frame().cell_m
        )?;
        for (k, l) in self.legs.iter().enumerate() {
            let (n, e) = (l.target.north_m, l.target.east_m);
            let how = match (l.reached, l.replaced) {
                (true, _) => "reached",
                (false, true) => "replaced",
                (false, false) => "not reached",
            };
            writeln!(
                f,
                "leg {:<6} N {n:.2} m, E {e:.2} m: steps {}..{}, {how}",
                k + 1,
                l.from_step,
                l.to_step
            )?;
        }
        writeln!(
            f,
            "ride       {}: {} steps, {:.2} m travelled, min clearance {}",
            if self.reached { "reached" } else { "stopped" },
            self.steps,
            self.distance_m,
            self.min_clearance_m
                .as_f64()
                .map_or("unbounded (no obstacles)".to_string(), |m| format!(
                    "{m:.2} m"
                ))
        )
    }
}
