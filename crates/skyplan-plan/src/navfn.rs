//! Navigation-function planners: the wavefront (distance field + gradient descent) and A\* over
//! an inflated cost map.

use crate::failure::{FailureKind, PlanFailure};
use crate::grid::{end_cell, grid_for, waypoint_points};
use crate::request::{FieldMode, in_range};
use crate::session::{Check, Query, Route, Session, micros};
use serde::{Deserialize, Serialize};
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

/// The inflated cost map's options (Nav2's inflation layer), for the `costmap` planner and
/// [`Session::ride`]; `None` takes the default in brackets.
///
/// ```
/// use skyplan_plan::{CostmapOptions, RideRequest, Session, World};
/// let mut session = Session::new(World::fcnd_city());
/// let mut request = RideRequest::new([0.0, 0.0], vec![[40.0, 30.0]]);
/// request.route = CostmapOptions { cost_weight: Some(4.0), ..Default::default() }.into_request();
/// let ride = session.ride(&request).unwrap();
/// assert_eq!(ride.costmap["cost_weight"], 4.0);
/// assert_eq!(ride.costmap["inflation_radius_m"], 10.0); // ten 1 m cells
/// request.route.cost_weight = Some(-1.0); // checked as a plan's options are
/// assert!(session.ride(&request).unwrap_err().message.contains("cost_weight -1"));
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields, default)]
pub struct CostmapOptions {
    /// Radius inscribed in the vehicle's footprint, metres: cells within it are lethal [default: 0].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = crate::cli::finite, allow_hyphen_values = true, help_heading = "Cost map"))]
    pub inscribed_radius_m: Option<f64>,
    /// Distance up to which costs are raised, metres [default: 10 cells].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = crate::cli::finite, allow_hyphen_values = true, help_heading = "Cost map"))]
    pub inflation_radius_m: Option<f64>,
    /// Decay k of 252·exp(−k·(d − r_inscribed)), per metre [default: 3 / inflation radius].
    #[cfg_attr(feature = "clap", arg(long, value_name = "K", value_parser = crate::cli::finite, allow_hyphen_values = true, help_heading = "Cost map"))]
    pub cost_scaling: Option<f64>,
    /// Weight of the cost in length + weight · cost [default: 2].
    #[cfg_attr(feature = "clap", arg(long, value_name = "W", value_parser = crate::cli::finite, allow_hyphen_values = true, help_heading = "Cost map"))]
    pub cost_weight: Option<f64>,
}

/// Cost-map options with the defaults filled in for the grid's cell size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CostmapParams {
    pub inflation: Inflation,
    pub weight: f64,
}

impl CostmapOptions {
    /// These options as a plan request's fields (the rest left to their defaults), to be
    /// combined with other fields: `PlanRequest { alt_m: Some(10.0), ..options.into_request() }`.
    pub fn into_request(self) -> crate::PlanRequest {
        crate::PlanRequest {
            inscribed_radius_m: self.inscribed_radius_m,
            inflation_radius_m: self.inflation_radius_m,
            cost_scaling: self.cost_scaling,
            cost_weight: self.cost_weight,
            ..Default::default()
        }
    }

    /// The same options if every one is a number from 0 to 10⁶, else a bad request naming it.
    pub(crate) fn checked(self) -> Result<Self, PlanFailure> {
        let check = |name: &str, v: Option<f64>| -> Result<Option<f64>, PlanFailure> {
            v.map(|v| in_range(name, v, 0.0, 1e6, "")).transpose()
        };
        Ok(CostmapOptions {
            inscribed_radius_m: check("inscribed_radius_m", self.inscribed_radius_m)?,
            inflation_radius_m: check("inflation_radius_m", self.inflation_radius_m)?,
            cost_scaling: check("cost_scaling", self.cost_scaling)?,
            cost_weight: check("cost_weight", self.cost_weight)?,
        })
    }

    /// Nav2-style inflation parameters with the defaults: ten cells of inflation, cost decaying
    /// to e⁻³ at its edge, weight 2.
    pub(crate) fn params(&self, cell_m: f64) -> CostmapParams {
        let inflation_radius_m = self.inflation_radius_m.unwrap_or(10.0 * cell_m);
        CostmapParams {
            inflation: Inflation {
                inscribed_radius_m: self.inscribed_radius_m.unwrap_or(0.0),
                inflation_radius_m,
                cost_scaling_factor: self.cost_scaling.unwrap_or(if inflation_radius_m > 0.0 {
                    3.0 / inflation_radius_m
                } else {
                    0.0
                }),
            },
            weight: self.cost_weight.unwrap_or(2.0),
        }
    }
}

impl CostmapParams {
    /// The parameters as reported (`costmap` in a ride, the planner's details in a plan).
    pub(crate) fn json(&self) -> Value {
        json!({
            "inscribed_radius_m": self.inflation.inscribed_radius_m,
            "inflation_radius_m": self.inflation.inflation_radius_m,
            "cost_scaling_factor": self.inflation.cost_scaling_factor,
            "cost_weight": self.weight,
        })
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
    route.timings.grid_build_us = build_us;
    route.timings.search_us = search_us;
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
    let params = r.costmap.params(cell_m);
    let t = Instant::now();
    let costmap = Costmap::inflate(&grid, params.inflation).map_err(|e| failure(e, &grid))?;
    let found = cost_search(&costmap, start, goal, r.model, params.weight, true)
        .map_err(|e| failure(e, &grid))?;
    let search_us = micros(t.elapsed());
    let min_clearance_m = found
        .cells
        .iter()
        .filter_map(|&c| costmap.clearance_m(c))
        .fold(f64::INFINITY, f64::min);
    let mut details = params.json();
    details["objective_m"] = json!(found.objective_cells * cell_m);
    details["min_clearance_m"] = finite_or_null(min_clearance_m);
    let field = if r.geometry {
        Some(
            cost_to_go(&costmap, goal, r.model, params.weight)
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
