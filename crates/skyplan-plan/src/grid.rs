//! Grid search planners (A\*, Dijkstra, JPS, JPS+, Theta\*) on the grid at the altitude, then
//! collinearity pruning and the line-of-sight shortcut (the FCND pipeline, made exact).

use crate::algorithm::CellPlanner;
use crate::failure::{FailureKind, PlanFailure};
use crate::request::Prune;
use crate::session::{Check, Query, Route, Session, micros};
use crate::world::grid_bounds;
use skyplan_cspace::{Cell, Grid2, Touch};
use skyplan_postprocess::{prune_collinear, prune_collinear_eps, shortcut, touch_for};
use skyplan_search::{Components, GridPath, GridSearch, MoveModel, Planner, SearchError};
use std::sync::Arc;
use std::time::Instant;

fn describe(grid: &Grid2, ne: [f64; 2]) -> String {
    match grid.cell_at_ne(ne[0], ne[1]) {
        Some(c) => format!(
            "N {:.2} m, E {:.2} m (row {}, col {})",
            ne[0], ne[1], c.row, c.col
        ),
        None => format!("N {:.2} m, E {:.2} m", ne[0], ne[1]),
    }
}

fn nearest_hint(grid: &Grid2, ne: [f64; 2]) -> String {
    match grid.nearest_free_ne(ne[0], ne[1]) {
        Some(c) => {
            let (n, e) = grid.center_ne(c);
            format!("the nearest free cell centre is N {n:.2} m, E {e:.2} m")
        }
        None => "the grid has no free cell at all".to_string(),
    }
}

/// The free cell of an end of the route, or why it cannot be used.
pub(crate) fn end_cell(
    grid: &Grid2,
    q: &Query,
    which: &str,
    ne: [f64; 2],
) -> Result<Cell, PlanFailure> {
    let kind = if which == "start" {
        FailureKind::InvalidStart
    } else {
        FailureKind::InvalidGoal
    };
    let lla = q
        .world
        .frame()
        .and_then(|f| {
            f.lla_from_ned(skyplan_frames::Ned {
                north_m: ne[0],
                east_m: ne[1],
                down_m: -q.r.alt_m,
            })
            .ok()
        })
        .map(|l| format!(" (lat {:.7}, lon {:.7})", l.lat_deg, l.lon_deg))
        .unwrap_or_default();
    let Some(cell) = grid.cell_at_ne(ne[0], ne[1]) else {
        return Err(PlanFailure::new(
            kind,
            format!(
                "{which} {}{lla} is off the map ({}); {}",
                describe(grid, ne),
                grid_bounds(grid),
                nearest_hint(grid, ne)
            ),
        ));
    };
    if grid.is_blocked(cell) {
        let why = if q.world.colliders().is_some() || q.world.footprints().is_some() {
            format!(
                "inside an obstacle or its {} m safety margin at {} m altitude",
                q.r.safety_m, q.r.alt_m
            )
        } else {
            "at an obstacle".to_string()
        };
        return Err(PlanFailure::new(
            kind,
            format!(
                "{which} {}{lla} is {why}; {}",
                describe(grid, ne),
                nearest_hint(grid, ne)
            ),
        ));
    }
    // On a side or corner its free cell shares with a blocked one: the final re-check counts
    // the blocked cell as touched (closed cells), so no route could leave from there.
    if !grid.segment_is_free_ne((ne[0], ne[1]), (ne[0], ne[1]), q.r.model.touch()) {
        return Err(PlanFailure::new(
            kind,
            format!(
                "{which} {}{lla} is on the edge of a blocked cell (an obstacle's {} m safety margin at {} m altitude, in cells of {} m); {}",
                describe(grid, ne),
                q.r.safety_m,
                q.r.alt_m,
                grid.frame().cell_m,
                nearest_hint(grid, ne)
            ),
        ));
    }
    Ok(cell)
}

/// The grid for a 2D request, with the time it took (0 when cached): the map's grid at the
/// altitude, with the request's no-fly zones blocked on a copy.
pub(crate) fn grid_for(session: &mut Session, q: &Query) -> Result<(Arc<Grid2>, u64), PlanFailure> {
    let t = Instant::now();
    let grid = session.grid(q.r.alt_m, q.r.safety_m, q.r.cell_m)?;
    let spec = skyplan_cspace::GridSpec {
        alt_m: q.r.alt_m,
        safety_m: q.r.safety_m,
        cell_m: q.r.cell_m,
    };
    Ok((with_zones(grid, q.zones, spec)?, micros(t.elapsed())))
}

/// `grid` with `zones` blocked at `spec`'s altitude and margin, on a copy (the same grid when
/// there are none).
pub(crate) fn with_zones(
    grid: Arc<Grid2>,
    zones: &[skyplan_map::nofly::Zone],
    spec: skyplan_cspace::GridSpec,
) -> Result<Arc<Grid2>, PlanFailure> {
    if zones.is_empty() {
        return Ok(grid);
    }
    let mut zoned = grid.as_ref().clone();
    zoned
        .block_zones(zones, spec)
        .map_err(|e| PlanFailure::bad_request(format!("no_fly: {e}")))?;
    Ok(Arc::new(zoned))
}

/// Why the goal cannot be reached: both regions' sizes and the reachable point nearest the goal.
pub(crate) fn unreachable(
    grid: &Grid2,
    q: &Query,
    model: MoveModel,
    start: Cell,
    goal: Cell,
    expansions: u64,
) -> PlanFailure {
    let components = Components::new(grid, model);
    let size = |c: Cell| components.label(c).map_or(0, |l| components.size(l));
    let start_label = components.label(start);
    let (gn, ge) = grid.center_ne(goal);
    let d = |c: Cell| {
        let (n, e) = grid.center_ne(c);
        (n - gn).hypot(e - ge)
    };
    let nearest = (0..grid.len())
        .map(|i| grid.cell(i))
        .filter(|&c| components.label(c) == start_label)
        .min_by(|&a, &b| d(a).total_cmp(&d(b)))
        .unwrap_or(start);
    let (n, e) = grid.center_ne(nearest);
    let at = if q.world.colliders().is_some() || q.world.footprints().is_some() {
        format!(
            " at {} m altitude with a {} m margin",
            q.r.alt_m, q.r.safety_m
        )
    } else {
        String::new()
    };
    PlanFailure::new(
        FailureKind::NoPath,
        format!(
            "goal is unreachable from start{at}: the start's free region has {} cells, the goal's {} cells, and obstacles separate them (searched {expansions} cells); the reachable point nearest the goal is N {n:.2} m, E {e:.2} m; try a lower margin, another altitude or corner cutting",
            size(start),
            size(goal)
        ),
    )
}

/// Local points of the route: the exact start, the centres of the kept cells, the exact goal.
/// The exact start replaces its cell's centre when the first segment stays free from there
/// (likewise the goal); otherwise it is added as a short hop inside its own free cell.
///
/// Public so that replanning in flight turns its cell paths into waypoints the same way.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2, Touch};
/// let grid = Grid2::from_ascii("...\n...")?;
/// let cells = [Cell::new(0, 0), Cell::new(0, 2)];
/// let points = skyplan_plan::waypoint_points(&grid, &cells, [0.2, 0.3], [0.5, 2.9], Touch::Closed, 5.0);
/// assert_eq!(points, vec![[0.2, 0.3, 5.0], [0.5, 2.9, 5.0]]);
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn waypoint_points(
    grid: &Grid2,
    cells: &[Cell],
    start: [f64; 2],
    goal: [f64; 2],
    touch: Touch,
    alt_m: f64,
) -> Vec<[f64; 3]> {
    let mut points: Vec<(f64, f64)> = cells.iter().map(|&c| grid.center_ne(c)).collect();
    let (s, g) = ((start[0], start[1]), (goal[0], goal[1]));
    if points.len() <= 1 {
        points = vec![s, g];
    } else {
        if grid.segment_is_free_ne(s, points[1], touch) {
            points[0] = s;
        } else {
            points.insert(0, s);
        }
        let n = points.len();
        if grid.segment_is_free_ne(points[n - 2], g, touch) {
            points[n - 1] = g;
        } else {
            points.push(g);
        }
    }
    points.dedup();
    if points.len() == 1 {
        points.push(points[0]);
    }
    points.into_iter().map(|(n, e)| [n, e, alt_m]).collect()
}

/// The centres of `cells` at an altitude, as route points.
pub(crate) fn centres_at(grid: &Grid2, cells: &[Cell], alt_m: f64) -> Vec<[f64; 3]> {
    cells
        .iter()
        .map(|&c| {
            let (n, e) = grid.center_ne(c);
            [n, e, alt_m]
        })
        .collect()
}

/// A cell-to-cell search on the grid (prepared through the session's caches), then the passes.
pub(crate) fn plan<P: CellPlanner + ?Sized>(
    session: &mut Session,
    q: &Query,
    planner: &P,
) -> Result<Route, PlanFailure> {
    let r = q.r;
    let (grid, grid_us) = grid_for(session, q)?;
    let start = end_cell(&grid, q, "start", q.start_ne)?;
    let goal = end_cell(&grid, q, "goal", q.goal_ne)?;
    let prepared = planner.prepare(session, &grid, r)?;
    let t = Instant::now();
    let searched = prepared
        .engine
        .search(&mut session.workspace, &grid, (start, goal), r.model);
    let search_us = micros(t.elapsed());
    let path = match searched {
        Ok(p) => p,
        Err(SearchError::Unreachable { expansions }) => {
            return Err(unreachable(&grid, q, r.model, start, goal, expansions));
        }
        Err(e @ SearchError::Damaged(_)) => return Err(PlanFailure::internal(e.to_string())),
        Err(other) => {
            return Err(PlanFailure::internal(format!(
                "search refused checked endpoints: {other}"
            )));
        }
    };
    let (mut route, waypoints) = passes(&grid, q, &path);
    route.octile_optimum_m = planner
        .any_angle()
        .then(|| {
            GridSearch::new()
                .search(&grid, start, goal, r.model, Planner::Jps)
                .ok()
                .map(|p| p.cost_cells() * grid.frame().cell_m)
        })
        .flatten();
    if let Some(what) = prepared.detail {
        // Whether this request built the table or hierarchy, or used the session's (kept or loaded).
        let how = if prepared.built_us.is_some() {
            "built"
        } else {
            "reused"
        };
        route.details.insert(what.into(), how.into());
    }
    if let Some(pick) = &prepared.auto {
        route.details.insert("auto".into(), serde_json::json!(pick));
    }
    let moves = (path.cells.len(), path.straight_moves, path.diagonal_moves);
    route.record_grid_search((start, goal), path.expansions, moves, waypoints);
    route.timings.grid_build_us = grid_us + prepared.built_us.unwrap_or(0);
    route.timings.search_us = search_us;
    if r.geometry {
        route.geometry.raw_path = centres_at(&grid, &path.cells, r.alt_m);
    }
    route.grid = Some(grid);
    Ok(route)
}

/// Pruning and the line-of-sight shortcut of a cell path, as a route re-checked on `grid`, and
/// the waypoints left after pruning and after the shortcut.
fn passes(grid: &Arc<Grid2>, q: &Query, path: &GridPath) -> (Route, (usize, usize)) {
    let r = q.r;
    let t_post = Instant::now();
    let touch = touch_for(r.model);
    let pruned = match r.prune {
        Prune::None => path.cells.clone(),
        Prune::Collinear => prune_collinear(&path.cells),
        Prune::Epsilon(eps) => prune_collinear_eps(grid, &path.cells, eps, touch),
    };
    let kept = if r.shortcut {
        shortcut(grid, &pruned, touch)
    } else {
        pruned.clone()
    };
    let points = waypoint_points(grid, &kept, q.start_ne, q.goal_ne, touch, r.alt_m);
    let mut route = Route::new(
        points,
        path.cost_cells() * grid.frame().cell_m,
        Check::Grid {
            grid: Arc::clone(grid),
            touch,
        },
    );
    route.timings.postprocess_us = micros(t_post.elapsed());
    (route, (pruned.len(), kept.len()))
}
