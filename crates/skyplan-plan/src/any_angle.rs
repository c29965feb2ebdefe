//! Exact any-angle shortest paths (`skyplan-anyangle`): the Euclidean-shortest route through the
//! free cells, turning at obstacle corners; the visibility graph is built once per grid in a
//! session.

use crate::failure::{FailureKind, PlanFailure};
use crate::grid::{end_cell, grid_for};
use crate::session::{Check, Query, Route, Session, micros};
use skyplan_anyangle::{AnyAngle, AnyAngleError};
use skyplan_search::{GridSearch, Planner};
use std::sync::Arc;
use std::time::Instant;

pub(crate) fn plan(session: &mut Session, q: &Query) -> Result<Route, PlanFailure> {
    let r = q.r;
    let (grid, grid_us) = grid_for(session, q)?;
    let start = end_cell(&grid, q, "start", q.start_ne)?;
    let goal = end_cell(&grid, q, "goal", q.goal_ne)?;
    let t_build = Instant::now();
    let k = [r.alt_m, r.safety_m, r.cell_m, 0.0, 0.0].map(f64::to_bits);
    let graph = match session.any_angle.get(&k) {
        Some(g) => Arc::clone(g),
        None => {
            let g = Arc::new(AnyAngle::new(&grid));
            if session.any_angle.len() >= 8 {
                session.any_angle.clear();
            }
            session.any_angle.insert(k, Arc::clone(&g));
            g
        }
    };
    let build_us = grid_us + micros(t_build.elapsed());
    let t = Instant::now();
    let found = graph.plan_ne((q.start_ne[0], q.start_ne[1]), (q.goal_ne[0], q.goal_ne[1]));
    let search_us = micros(t.elapsed());
    let path = match found {
        Ok(p) => p,
        Err(e @ AnyAngleError::NoPath { .. }) => {
            return Err(PlanFailure::new(
                FailureKind::NoPath,
                format!("any-angle: {e}"),
            ));
        }
        Err(e @ AnyAngleError::Recheck { .. }) => return Err(PlanFailure::internal(e.to_string())),
        Err(e) => return Err(PlanFailure::bad_request(e.to_string())),
    };
    let points = path
        .points_ne
        .iter()
        .map(|&(n, e)| [n, e, r.alt_m])
        .collect();
    let mut route = Route::new(points, path.length_m, Check::AnyAngle(Arc::clone(&grid)));
    route.start_cell = Some(start);
    route.goal_cell = Some(goal);
    route.expansions = path.expansions;
    route.timings.grid_build_us = build_us;
    route.timings.search_us = search_us;
    route.octile_optimum_m = GridSearch::new()
        .search(&grid, start, goal, r.model, Planner::Jps)
        .ok()
        .map(|p| p.cost_cells() * grid.frame().cell_m);
    route
        .details
        .insert("corners".into(), serde_json::json!(graph.corner_count()));
    route
        .details
        .insert("graph_edges".into(), serde_json::json!(graph.edge_count()));
    if r.geometry {
        route.geometry.raw_path = route.points.clone();
    }
    route.grid = Some(grid);
    Ok(route)
}
