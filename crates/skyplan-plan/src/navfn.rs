//! Navigation-function planners: the wavefront (distance field + gradient descent) and A\* over
//! an inflated cost map.

use crate::failure::{FailureKind, PlanFailure};
use crate::grid::{end_cell, grid_for, waypoint_points};
use crate::request::FieldMode;
use crate::session::{Check, Query, Route, Session, micros};
use serde_json::{Value, json};
use skyplan_cspace::{Cell, Grid2};
use skyplan_navfn::{
    Costmap, FieldMetric, Inflation, NavError, cost_search, cost_to_go, distance_field,
};
use skyplan_postprocess::{prune_collinear, touch_for};
use std::sync::Arc;
use std::time::Instant;

/// A navigation-function error as a failure: unreachable → no path, the rest → bad request.
pub(crate) fn failure(e: NavError, grid: &Grid2) -> PlanFailure {
    let at = |c: Cell| {
        let (n, e) = grid.center_ne(c);
        format!("N {n:.2} m, E {e:.2} m")
    };
    match &e {
        NavError::Unreachable {
            source_cell,
            destination_cell,
        } => PlanFailure::new(
            FailureKind::NoPath,
            format!(
                "{e}; the goal is at {}, the start at {}",
                at(*destination_cell),
                at(*source_cell)
            ),
        ),
        _ => PlanFailure::bad_request(e.to_string()),
    }
}

/// JSON has no infinity: a clearance on a map without obstacles is `null`.
pub(crate) fn finite_or_null(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// Nav2-style inflation parameters, with the defaults: ten cells of inflation, cost decaying to
/// e⁻³ at its edge.
pub(crate) fn inflation(
    cell_m: f64,
    inscribed_radius_m: f64,
    inflation_radius_m: Option<f64>,
    cost_scaling: Option<f64>,
) -> Inflation {
    let inflation_radius_m = inflation_radius_m.unwrap_or(10.0 * cell_m);
    Inflation {
        inscribed_radius_m,
        inflation_radius_m,
        cost_scaling_factor: cost_scaling.unwrap_or(if inflation_radius_m > 0.0 {
            3.0 / inflation_radius_m
        } else {
            0.0
        }),
    }
}

struct Found {
    cells: Vec<Cell>,
    straight: u64,
    diagonal: u64,
    expansions: u64,
}

fn finish(
    grid: Arc<Grid2>,
    q: &Query,
    start: Cell,
    goal: Cell,
    found: Found,
    build_us: u64,
    search_us: u64,
) -> Route {
    let touch = touch_for(q.r.model);
    let pruned = prune_collinear(&found.cells);
    let points = waypoint_points(&grid, &pruned, q.start_ne, q.goal_ne, touch, q.r.alt_m);
    let cost_m = skyplan_search::octile_cost(found.straight, found.diagonal) * grid.frame().cell_m;
    let mut route = Route::new(
        points,
        cost_m,
        Check::Grid {
            grid: Arc::clone(&grid),
            touch,
        },
    );
    let moves = (found.cells.len(), found.straight, found.diagonal);
    // No shortcut: the pruned cells are the waypoints.
    let waypoints = (pruned.len(), pruned.len());
    route.record_grid_search((start, goal), found.expansions, moves, waypoints);
    route.build_us = build_us;
    route.search_us = search_us;
    if q.r.geometry {
        route.geometry.raw_path = crate::grid::centres_at(&grid, &found.cells, q.r.alt_m);
    }
    route.grid = Some(grid);
    route
}

/// The wavefront: a distance field from the goal, then strictly decreasing descent.
pub(crate) fn wavefront(session: &mut Session, q: &Query) -> Result<Route, PlanFailure> {
    let (grid, build_us) = grid_for(session, q)?;
    let start = end_cell(&grid, q, "start", q.start_ne)?;
    let goal = end_cell(&grid, q, "goal", q.goal_ne)?;
    let metric = match q.r.field {
        FieldMode::Length => FieldMetric::Length,
        FieldMode::Steps => FieldMetric::Steps,
    };
    let t = Instant::now();
    let field = distance_field(&grid, goal, q.r.model, metric).map_err(|e| failure(e, &grid))?;
    let field_us = micros(t.elapsed());
    let descent = field.descend(start).map_err(|e| failure(e, &grid))?;
    let search_us = micros(t.elapsed());
    let found = Found {
        straight: descent.straight_moves,
        diagonal: descent.diagonal_moves,
        expansions: (grid.len() - field.unreachable_count()) as u64,
        cells: descent.cells,
    };
    let mut route = finish(
        Arc::clone(&grid),
        q,
        start,
        goal,
        found,
        build_us,
        search_us,
    );
    let name = match q.r.field {
        FieldMode::Length => "length",
        FieldMode::Steps => "steps",
    };
    route.details.insert("field".into(), json!(name));
    route
        .details
        .insert("field_time_us".into(), json!(field_us));
    if q.r.geometry {
        route.geometry.field = Some(field.values().to_vec());
    }
    Ok(route)
}

/// Nav2-style inflation, then A\* on length + weight · cost.
pub(crate) fn costmap(session: &mut Session, q: &Query) -> Result<Route, PlanFailure> {
    let r = q.r;
    let (grid, build_us) = grid_for(session, q)?;
    let start = end_cell(&grid, q, "start", q.start_ne)?;
    let goal = end_cell(&grid, q, "goal", q.goal_ne)?;
    let cell_m = grid.frame().cell_m;
    let params = inflation(
        cell_m,
        r.inscribed_radius_m,
        r.inflation_radius_m,
        r.cost_scaling,
    );
    let t = Instant::now();
    let costmap = Costmap::inflate(&grid, params).map_err(|e| failure(e, &grid))?;
    let found = cost_search(&costmap, start, goal, r.model, r.cost_weight, true)
        .map_err(|e| failure(e, &grid))?;
    let search_us = micros(t.elapsed());
    let min_clearance_m = found
        .cells
        .iter()
        .filter_map(|&c| costmap.clearance_m(c))
        .fold(f64::INFINITY, f64::min);
    let details = json!({
        "inscribed_radius_m": params.inscribed_radius_m,
        "inflation_radius_m": params.inflation_radius_m,
        "cost_scaling_factor": params.cost_scaling_factor,
        "cost_weight": r.cost_weight,
        "objective_m": found.objective_cells * cell_m,
        "min_clearance_m": finite_or_null(min_clearance_m),
    });
    let field = if r.geometry {
        Some(
            cost_to_go(&costmap, goal, r.model, r.cost_weight)
                .map_err(|e| failure(e, &grid))?
                .values()
                .to_vec(),
        )
    } else {
        None
    };
    let f = Found {
        straight: found.straight_moves,
        diagonal: found.diagonal_moves,
        expansions: found.expansions,
        cells: found.cells,
    };
    let mut route = finish(grid, q, start, goal, f, build_us, search_us);
    route.details.insert("costmap".into(), details);
    route.geometry.field = field;
    Ok(route)
}
