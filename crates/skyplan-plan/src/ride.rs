//! Rides on a navigation function (`skyplan navigate`): follow the inflated cost map's gradient
//! from a start through targets, which may change mid-ride (the workshop's navigation functions).

use crate::failure::PlanFailure;
use crate::navfn::{failure, finite_or_null};
use crate::planner_id::PlannerId;
use crate::request::{PlanRequest, Resolved};
use crate::session::{Session, micros};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use skyplan_cspace::{Cell, Grid2};
use skyplan_navfn::{Costmap, NavError, NavRequest, TargetChange, navigate};
use skyplan_search::MoveModel;
use std::sync::Arc;
use std::time::Instant;

/// A target that replaces the current one once the ride has taken `at_step` steps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RideChange {
    /// The step at which the target changes.
    pub at_step: u64,
    /// The new target, metres north and east of the map's origin.
    pub target_ne: [f64; 2],
}

/// What to ride: the start, the targets and their changes; the grid (altitude, margin, cell
/// size), the move model and the cost map are a [`PlanRequest`] for the `costmap` planner,
/// resolved and checked as a plan's are (one set of defaults and ranges for every door).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RideRequest {
    /// Where the ride starts, metres north and east.
    pub start_ne: [f64; 2],
    /// The targets in order, metres north and east.
    pub targets_ne: Vec<[f64; 2]>,
    /// Targets that change mid-ride.
    pub changes: Vec<RideChange>,
    /// The grid, the move model and the cost map: `alt_m`, `safety_m`, `cell_m`,
    /// `connectivity`, `corner_cutting` and the cost map's options (`None`: the planner's
    /// defaults). Its ends are the ride's own, so a start or goal given here is refused.
    pub route: PlanRequest,
}

impl RideRequest {
    /// A request with the planning API's defaults (5 m altitude and margin, 1 m cells,
    /// 8-connected).
    ///
    /// ```
    /// let r = skyplan_plan::RideRequest::new([0.0, 0.0], vec![[40.0, 30.0]]);
    /// assert_eq!(r.route.alt_m, None); // the planning API's default applies
    /// ```
    pub fn new(start_ne: [f64; 2], targets_ne: Vec<[f64; 2]>) -> Self {
        RideRequest {
            start_ne,
            targets_ne,
            changes: Vec::new(),
            route: PlanRequest::default(),
        }
    }

    /// The route options resolved as the `costmap` planner's.
    fn resolved(&self) -> Result<Resolved, PlanFailure> {
        let r = &self.route;
        if r.start_ne.is_some()
            || r.start_lla.is_some()
            || r.goal_ne.is_some()
            || r.goal_lla.is_some()
        {
            return Err(PlanFailure::bad_request(
                "a ride's ends are its start_ne and targets_ne, not the route's start or goal",
            ));
        }
        if r.no_fly.is_some() {
            return Err(PlanFailure::bad_request(
                "no_fly: rides on the cost map do not honour no-fly zones yet; plan with a grid planner instead",
            ));
        }
        Resolved::new(&PlanRequest {
            planner: Some(PlannerId::Costmap),
            ..r.clone()
        })
    }
}

/// A position on the ride, with its grid cell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RidePlace {
    /// Metres north of the map's origin.
    pub north_m: f64,
    /// Metres east of the map's origin.
    pub east_m: f64,
    /// Row and column.
    pub cell: [u32; 2],
}

/// One leg of the ride: towards one target.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RideLeg {
    /// The leg's target (a cell centre).
    pub target: RidePlace,
    /// First step of the leg.
    pub from_step: u64,
    /// Last step of the leg.
    pub to_step: u64,
    /// The target was reached.
    pub reached: bool,
    /// The target was replaced mid-leg.
    pub replaced: bool,
}

/// A finished ride: the `skyplan navigate --json` report, plus what pictures need.
#[derive(Debug, Clone, Serialize)]
pub struct Ride {
    /// `ok` when every target was reached, else `no_path`.
    pub status: &'static str,
    /// The map's name.
    pub map: String,
    /// The move model, in words.
    pub move_model: &'static str,
    /// Where the ride started.
    pub start: RidePlace,
    /// Every target was reached.
    pub reached: bool,
    /// Steps taken.
    pub steps: u64,
    /// Distance travelled, metres.
    pub distance_m: f64,
    /// Smallest clearance to an obstacle along the ride, metres (`null` without obstacles).
    pub min_clearance_m: Value,
    /// The legs.
    pub legs: Vec<RideLeg>,
    /// Changes that came after the ride had ended.
    pub ignored_changes: usize,
    /// Why the ride stopped short.
    pub failure: Option<String>,
    /// The ride's turning points, metres north and east.
    pub waypoints: Vec<[f64; 2]>,
    /// The cost map's parameters.
    pub costmap: Value,
    /// Time to inflate the cost map, microseconds.
    pub inflation_time_us: u64,
    /// Time to ride, microseconds.
    pub ride_time_us: u64,
    /// Every cell of the ride.
    #[serde(skip)]
    pub trace: Vec<Cell>,
    /// The start cell and the last target's cell.
    #[serde(skip)]
    pub ends: (Cell, Cell),
    /// The cost map's Nav2 costs (0 free to 254 lethal), row-major: the heat map's values, so
    /// its scale reads as the costs themselves.
    #[serde(skip)]
    pub costs: Vec<f64>,
    /// The move model.
    #[serde(skip)]
    pub model: MoveModel,
    /// The grid ridden.
    #[serde(skip)]
    pub grid: Arc<Grid2>,
    #[serde(skip)]
    stopped: Option<NavError>,
}

impl Ride {
    /// Why the ride stopped short, as a failure (`None` when every target was reached).
    pub fn stopped_short(&self) -> Option<PlanFailure> {
        match &self.stopped {
            Some(e) if !self.reached => Some(failure(e.clone(), &self.grid)),
            _ => None,
        }
    }
}

fn place(grid: &Grid2, c: Cell) -> RidePlace {
    let (north_m, east_m) = grid.center_ne(c);
    RidePlace {
        north_m,
        east_m,
        cell: [c.row, c.col],
    }
}

/// The cell of a position, or why it cannot be used (off the map or at an obstacle).
fn free_cell(grid: &Grid2, which: &str, [n, e]: [f64; 2]) -> Result<Cell, PlanFailure> {
    let f = grid.frame();
    let cell = grid.cell_at_ne(n, e).ok_or_else(|| {
        PlanFailure::bad_request(format!(
            "the {which} N {n} m, E {e} m is off the map (N {}..{} m, E {}..{} m)",
            f.origin_north_m,
            f.origin_north_m + f64::from(grid.rows()) * f.cell_m,
            f.origin_east_m,
            f.origin_east_m + f64::from(grid.cols()) * f.cell_m,
        ))
    })?;
    if grid.is_blocked(cell) {
        return Err(PlanFailure::bad_request(format!(
            "the {which} N {n} m, E {e} m (row {}, col {}) is at an obstacle",
            cell.row, cell.col
        )));
    }
    Ok(cell)
}

impl Session {
    /// Rides the navigation function of the inflated cost map through the request's targets.
    ///
    /// A ride that stops short is still a [`Ride`] (with [`Ride::stopped_short`]); a request that
    /// cannot start (an end off the map or at an obstacle, bad options) is a [`PlanFailure`].
    ///
    /// ```
    /// use skyplan_plan::{RideRequest, Session, World};
    /// let mut session = Session::new(World::fcnd_city());
    /// let ride = session.ride(&RideRequest::new([0.0, 0.0], vec![[40.0, 30.0]])).unwrap();
    /// assert!(ride.reached && ride.distance_m >= 50.0);
    /// ```
    pub fn ride(&mut self, r: &RideRequest) -> Result<Ride, PlanFailure> {
        let spec = r.resolved()?;
        let model = spec.model;
        let grid = self.grid(spec.alt_m, spec.safety_m, spec.cell_m)?;
        if r.targets_ne.is_empty() {
            return Err(PlanFailure::bad_request("no targets to ride to"));
        }
        let start = free_cell(&grid, "source", r.start_ne)?;
        let targets = r
            .targets_ne
            .iter()
            .enumerate()
            .map(|(k, &p)| free_cell(&grid, &format!("target {}", k + 1), p))
            .collect::<Result<Vec<_>, _>>()?;
        let changes = r
            .changes
            .iter()
            .map(|c| {
                let which = format!("target changed at step {}", c.at_step);
                Ok(TargetChange {
                    at_step: c.at_step,
                    target: free_cell(&grid, &which, c.target_ne)?,
                })
            })
            .collect::<Result<Vec<_>, PlanFailure>>()?;
        let cell_m = grid.frame().cell_m;
        let params = spec.costmap.params(cell_m);
        let t0 = Instant::now();
        let costmap = Costmap::inflate(&grid, params.inflation).map_err(|e| failure(e, &grid))?;
        let inflation_time_us = micros(t0.elapsed());
        let request = NavRequest {
            source: start,
            targets,
            changes,
            model,
            weight: params.weight,
        };
        let run = navigate(&costmap, &request).map_err(|e| failure(e, &grid))?;
        let ride_time_us = micros(t0.elapsed()).saturating_sub(inflation_time_us);
        let waypoints = skyplan_postprocess::prune_collinear(&run.trace)
            .iter()
            .map(|&c| {
                let (n, e) = grid.center_ne(c);
                [n, e]
            })
            .collect();
        let goal = run.legs.last().map_or(start, |l| l.target);
        Ok(Ride {
            status: if run.reached { "ok" } else { "no_path" },
            map: self.world().name().to_string(),
            move_model: crate::session::model_name(model),
            start: RidePlace {
                cell: [start.row, start.col],
                north_m: r.start_ne[0],
                east_m: r.start_ne[1],
            },
            reached: run.reached,
            steps: run.steps,
            distance_m: run.distance_cells * cell_m,
            min_clearance_m: finite_or_null(run.min_clearance_cells * cell_m),
            legs: run
                .legs
                .iter()
                .map(|l| RideLeg {
                    target: place(&grid, l.target),
                    from_step: l.from_step,
                    to_step: l.to_step,
                    reached: l.reached,
                    replaced: l.replaced,
                })
                .collect(),
            ignored_changes: run.ignored_changes,
            failure: run.failure.as_ref().map(|e| e.to_string()),
            waypoints,
            costmap: params.json(),
            inflation_time_us,
            ride_time_us,
            costs: costmap.costs().iter().map(|&c| f64::from(c)).collect(),
            ends: (start, goal),
            trace: run.trace,
            model,
            grid,
            stopped: run.failure,
        })
    }
}
