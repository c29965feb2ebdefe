//! Gradient navigation: a vehicle stepping down cost-to-go fields through a list of targets.

use crate::cost_search::{CostToGo, cost_to_go};
use crate::field::check_endpoint;
use crate::{Costmap, Endpoint, NavError};
use skyplan_cspace::Cell;
use skyplan_search::MoveModel;
use std::f64::consts::SQRT_2;

/// "At step `at_step`, head for `target` instead": the current target is replaced and the vehicle
/// replans from where it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TargetChange {
    /// The number of steps taken when the change happens.
    pub at_step: u64,
    /// The new target.
    pub target: Cell,
}

/// A navigation run to perform.
#[derive(Debug, Clone, PartialEq)]
pub struct NavRequest {
    /// Where the vehicle starts.
    pub source: Cell,
    /// Targets to visit in order.
    pub targets: Vec<Cell>,
    /// Target changes during the ride (any order; applied by step).
    pub changes: Vec<TargetChange>,
    /// How the vehicle moves.
    pub model: MoveModel,
    /// Weight of the cost in length + weight · cost.
    pub weight: f64,
}

/// One leg of a ride: from where the vehicle was to one target.
#[derive(Debug, Clone, PartialEq)]
pub struct NavLeg {
    /// The target of this leg.
    pub target: Cell,
    /// Step count when the leg began.
    pub from_step: u64,
    /// Step count when it ended (reached, replaced or failed).
    pub to_step: u64,
    /// True if the vehicle reached the target.
    pub reached: bool,
    /// True if a [`TargetChange`] ended the leg.
    pub replaced: bool,
}

/// What happened on a ride.
#[derive(Debug, Clone, PartialEq)]
pub struct NavRun {
    /// Every cell the vehicle occupied, source first.
    pub trace: Vec<Cell>,
    /// True if the final target was reached.
    pub reached: bool,
    /// Moves made.
    pub steps: u64,
    /// Distance travelled, cells (straight moves 1, diagonals √2).
    pub distance_cells: f64,
    /// The smallest clearance (distance from the vehicle's cell centre to the nearest obstacle
    /// cell centre) along the trace, cells; `f64::INFINITY` on a map without obstacles.
    pub min_clearance_cells: f64,
    /// The legs, in order.
    pub legs: Vec<NavLeg>,
    /// Target changes that came after the ride had ended, and so were not applied.
    pub ignored_changes: usize,
    /// Why the ride stopped short, if it did (an unreachable target).
    pub failure: Option<NavError>,
}

/// Rides from `request.source` through its targets on `costmap`, one gradient step of the current
/// target's [`CostToGo`] field at a time (the field is grown once per target, and again after a
/// change). Each step strictly lowers the field, so no leg oscillates or runs forever.
///
/// Errors before the ride: the source or a target off the grid or at an obstacle, a bad weight.
/// An unreachable target ends the ride with `reached = false` and the reason in `failure`.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_navfn::{navigate, Costmap, Inflation, MoveModel, NavRequest, TargetChange};
/// let grid = Grid2::from_ascii(".......\n.......\n.......")?;
/// let costmap = Costmap::inflate(&grid, Inflation::default())?;
/// let request = NavRequest {
///     source: Cell::new(1, 0),
///     targets: vec![Cell::new(1, 6)],
///     changes: vec![TargetChange { at_step: 3, target: Cell::new(1, 0) }],
///     model: MoveModel::Octile,
///     weight: 0.0,
/// };
/// let run = navigate(&costmap, &request)?;
/// assert!(run.reached);
/// assert_eq!(run.steps, 6); // 3 steps out, 3 back after the change
/// assert_eq!(run.trace.last(), Some(&Cell::new(1, 0)));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn navigate(costmap: &Costmap, request: &NavRequest) -> Result<NavRun, NavError> {
    let grid = costmap.passable_grid();
    check_endpoint(&grid, request.source, Endpoint::Source)?;
    for &t in request
        .targets
        .iter()
        .chain(request.changes.iter().map(|c| &c.target))
    {
        check_endpoint(&grid, t, Endpoint::Destination)?;
    }
    let mut changes = request.changes.clone();
    changes.sort_by_key(|c| c.at_step);
    let mut changes = changes.into_iter().peekable();

    let clearance = |c: Cell| costmap.clearance_cells()[grid.index(c)];
    let mut run = NavRun {
        trace: vec![request.source],
        reached: request.targets.is_empty(),
        steps: 0,
        distance_cells: 0.0,
        min_clearance_cells: clearance(request.source),
        legs: Vec::new(),
        ignored_changes: 0,
        failure: None,
    };
    let mut pending = request.targets.iter().copied();
    let mut current = pending.next();
    let mut here = request.source;
    let mut field: Option<CostToGo> = None;
    while let Some(target) = current {
        if field.as_ref().is_none_or(|f| f.goal() != target) {
            field = Some(cost_to_go(costmap, target, request.model, request.weight)?);
            run.legs.push(NavLeg {
                target,
                from_step: run.steps,
                to_step: run.steps,
                reached: false,
                replaced: false,
            });
        }
        let Some(f) = field.as_ref() else { break };
        let leg_index = run.legs.len() - 1;
        if here == target {
            run.legs[leg_index].reached = true;
            run.legs[leg_index].to_step = run.steps;
            current = pending.next();
            if current.is_none() {
                run.reached = true;
            }
            continue;
        }
        if changes.peek().is_some_and(|c| c.at_step <= run.steps) {
            if let Some(change) = changes.next() {
                run.legs[leg_index].replaced = true;
                run.legs[leg_index].to_step = run.steps;
                current = Some(change.target);
                field = None;
            }
            continue;
        }
        let Some((next, diagonal, _)) = f.step(here) else {
            run.legs[leg_index].to_step = run.steps;
            run.failure = Some(NavError::Unreachable {
                source_cell: here,
                destination_cell: target,
            });
            break;
        };
        run.steps += 1;
        run.distance_cells += if diagonal { SQRT_2 } else { 1.0 };
        run.min_clearance_cells = run.min_clearance_cells.min(clearance(next));
        run.trace.push(next);
        here = next;
    }
    run.ignored_changes = changes.count();
    Ok(run)
}
