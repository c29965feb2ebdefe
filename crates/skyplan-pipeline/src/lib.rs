//! The skyplan planning pipeline, without I/O:
//!
//! ```text
//! CollidersMap ─► Grid2 at altitude ─► start/goal cells ─► A*/Dijkstra ─► prune ─► shortcut ─► Mission
//! ```
//!
//! [`plan`] runs it and returns a [`PlanOutcome`] holding every intermediate product (for files,
//! pictures and reports) or a [`PlanError`] that says what is wrong and what to do about it.
//!
//! ```
//! use skyplan_pipeline::{plan, PlanRequest, Position};
//! let text = "lat0 37.792480, lon0 -122.397450\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n\
//!             0,0,10,2,20,10\n30,30,1,1,1,1\n-30,-30,1,1,1,1\n";
//! let map = skyplan_map::colliders::parse_colliders(text)?;
//! let request = PlanRequest {
//!     start: Position::Ne { north_m: -15.0, east_m: 0.0 },
//!     goal: Position::Ne { north_m: 15.0, east_m: 0.0 },
//!     ..PlanRequest::default()
//! };
//! let outcome = plan(&map, &request)?;
//! assert!(outcome.cost_m > 30.0); // it has to go around the wall
//! assert_eq!(outcome.mission.waypoints.first().map(|w| (w.north_m, w.east_m)), Some((-15.0, 0.0)));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use serde::Serialize;
use skyplan_cspace::{Cell, Grid2, GridError, GridSpec};
use skyplan_frames::{FrameError, Lla, LocalFrame, Ned};
use skyplan_map::colliders::{CollidersMap, ObstacleBox};
use skyplan_mission::Mission;
use skyplan_postprocess::{prune_collinear, prune_collinear_eps, shortcut, touch_for};
use skyplan_search::{Components, GridPath, GridSearch, MoveModel, Planner, SearchError};
use std::fmt;
use std::time::{Duration, Instant};

/// A start or goal position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Position {
    /// Local metres north and east of the map's home.
    Ne {
        /// Metres north of home.
        north_m: f64,
        /// Metres east of home.
        east_m: f64,
    },
    /// Geodetic latitude and longitude (WGS84 degrees).
    Lla {
        /// Latitude, degrees.
        lat_deg: f64,
        /// Longitude, degrees.
        lon_deg: f64,
    },
}

/// Collinearity pruning.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub enum Prune {
    /// Keep every cell.
    None,
    /// Exact integer collinearity on grid cells. The default.
    #[default]
    Collinear,
    /// The FCND determinant test with this tolerance (cells²), removals line-of-sight checked.
    Epsilon(f64),
}

/// Everything a plan needs besides the map.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    /// Altitude, margin and cell size of the grid.
    pub spec: GridSpec,
    /// Where the vehicle is.
    pub start: Position,
    /// Where it should go.
    pub goal: Position,
    /// How it moves between cells.
    pub model: MoveModel,
    /// Which search runs.
    pub planner: Planner,
    /// Collinearity pruning pass.
    pub prune: Prune,
    /// Run the line-of-sight shortcut pass.
    pub shortcut: bool,
    /// Heading of the first waypoint, radians.
    pub start_heading_rad: f64,
}

impl Default for PlanRequest {
    fn default() -> Self {
        Self {
            spec: GridSpec::default(),
            start: Position::Ne {
                north_m: 0.0,
                east_m: 0.0,
            },
            goal: Position::Ne {
                north_m: 0.0,
                east_m: 0.0,
            },
            model: MoveModel::Octile,
            planner: Planner::Jps,
            prune: Prune::Collinear,
            shortcut: true,
            start_heading_rad: 0.0,
        }
    }
}

/// Which end of the route an error concerns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Endpoint {
    /// The start.
    Start,
    /// The goal.
    Goal,
}

impl fmt::Display for Endpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Endpoint::Start => "start",
            Endpoint::Goal => "goal",
        })
    }
}

/// A local point with its geodetic coordinates, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Place {
    /// Metres north of home.
    pub north_m: f64,
    /// Metres east of home.
    pub east_m: f64,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "N {:.2} m, E {:.2} m (lat {:.7}, lon {:.7})",
            self.north_m, self.east_m, self.lat_deg, self.lon_deg
        )
    }
}

fn nearest_hint(nearest: &Option<Place>) -> String {
    match nearest {
        Some(p) => format!("the nearest free cell centre is {p}"),
        None => "the grid has no free cell at all".to_string(),
    }
}

/// Why no plan was made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// The grid parameters are invalid.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// A position cannot be expressed in the map's local frame.
    #[error("{which}: {source}")]
    Frame {
        /// Which end.
        which: Endpoint,
        /// The frame error.
        source: FrameError,
    },
    /// The start or goal is outside the grid.
    #[error("{which} {at} is off the map (north {north_min_m} … {north_max_m} m, east {east_min_m} … {east_max_m} m); {}", nearest_hint(.nearest_free))]
    OffMap {
        /// Which end.
        which: Endpoint,
        /// Where it is.
        at: Place,
        /// Southern edge of the grid, m.
        north_min_m: f64,
        /// Northern edge of the grid, m.
        north_max_m: f64,
        /// Western edge of the grid, m.
        east_min_m: f64,
        /// Eastern edge of the grid, m.
        east_max_m: f64,
        /// The nearest free cell centre.
        nearest_free: Option<Place>,
    },
    /// The start or goal is inside an obstacle or its safety margin.
    #[error("{which} {at} is inside an obstacle or its {safety_m} m safety margin at {alt_m} m altitude; {}", nearest_hint(.nearest_free))]
    Blocked {
        /// Which end.
        which: Endpoint,
        /// Where it is.
        at: Place,
        /// The margin in force.
        safety_m: f64,
        /// The altitude in force.
        alt_m: f64,
        /// The nearest free cell centre.
        nearest_free: Option<Place>,
    },
    /// The goal lies in a free region that the start's region does not reach.
    #[error(
        "goal is unreachable from start at {alt_m} m altitude with a {safety_m} m margin: the start's free region has {start_region_cells} cells, the goal's {goal_region_cells} cells, and obstacles separate them (searched {expansions} cells); the reachable point nearest the goal is {nearest_reachable}; try a lower margin, another altitude or --corner-cutting"
    )]
    Unreachable {
        /// The altitude in force.
        alt_m: f64,
        /// The margin in force.
        safety_m: f64,
        /// Cells in the start's region.
        start_region_cells: u64,
        /// Cells in the goal's region.
        goal_region_cells: u64,
        /// Cells the search expanded.
        expansions: u64,
        /// The cell centre reachable from the start nearest to the goal.
        nearest_reachable: Place,
    },
    /// A post-condition failed: a bug, reported rather than flown.
    #[error("internal check failed: {0}; please report this with the command line")]
    Internal(String),
}

impl PlanError {
    /// True for errors that mean "valid input, but there is no path".
    pub fn is_no_path(&self) -> bool {
        matches!(self, PlanError::Unreachable { .. })
    }
}

/// Wall-clock time of each stage.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Timings {
    /// Building the grid, µs.
    pub grid_build_us: u64,
    /// The search alone, µs.
    pub search_us: u64,
    /// Pruning and shortcutting, µs.
    pub postprocess_us: u64,
    /// Everything in [`plan`], µs.
    pub total_us: u64,
}

/// The products of a successful plan.
#[derive(Debug, Clone)]
pub struct PlanOutcome {
    /// The configuration space.
    pub grid: Grid2,
    /// The obstacles that count at the flight altitude.
    pub active_obstacles: Vec<ObstacleBox>,
    /// The local frame about the map's home.
    pub frame: LocalFrame,
    /// Start, local metres and lat/lon.
    pub start: Place,
    /// Goal, local metres and lat/lon.
    pub goal: Place,
    /// Start cell.
    pub start_cell: Cell,
    /// Goal cell.
    pub goal_cell: Cell,
    /// The optimal grid path.
    pub path: GridPath,
    /// Cost of the path, metres (`cost_cells × cell_m`): the octile cost of a grid path, the
    /// Euclidean length of an any-angle (Theta\*) path.
    pub cost_m: f64,
    /// For any-angle planners: the octile optimum between the same cells, metres, for comparison.
    pub octile_optimum_m: Option<f64>,
    /// Straight-line distance between the start and goal cell centres, metres (a lower bound).
    pub straight_line_m: f64,
    /// Cells after collinearity pruning.
    pub pruned: Vec<Cell>,
    /// Cells after shortcutting (equal to `pruned` when shortcutting is off).
    pub shortcut: Vec<Cell>,
    /// The mission flown: waypoints from the exact start to the exact goal.
    pub mission: Mission,
    /// Stage timings.
    pub timings: Timings,
}

fn micros(d: Duration) -> u64 {
    u64::try_from(d.as_micros()).unwrap_or(u64::MAX)
}

/// Plans a route on a colliders map (see the crate docs for the stages).
pub fn plan(map: &CollidersMap, request: &PlanRequest) -> Result<PlanOutcome, PlanError> {
    let t_start = Instant::now();
    let frame = LocalFrame::new(Lla {
        lat_deg: map.home.lat_deg,
        lon_deg: map.home.lon_deg,
        alt_m: 0.0,
    })
    .map_err(|source| PlanError::Frame {
        which: Endpoint::Start,
        source,
    })?;
    let grid = Grid2::from_colliders(map, request.spec)?;
    let grid_build_us = micros(t_start.elapsed());
    let spec = request.spec;
    let place = |north_m: f64, east_m: f64, which: Endpoint| -> Result<Place, PlanError> {
        let lla = frame
            .lla_from_ned(Ned {
                north_m,
                east_m,
                down_m: -spec.alt_m,
            })
            .map_err(|source| PlanError::Frame { which, source })?;
        Ok(Place {
            north_m,
            east_m,
            lat_deg: lla.lat_deg,
            lon_deg: lla.lon_deg,
        })
    };
    let resolve = |pos: Position, which: Endpoint| -> Result<(Place, Cell), PlanError> {
        let at = match pos {
            Position::Ne { north_m, east_m } => place(north_m, east_m, which)?,
            Position::Lla { lat_deg, lon_deg } => {
                let ned = frame
                    .ned_from_lla(Lla {
                        lat_deg,
                        lon_deg,
                        alt_m: spec.alt_m,
                    })
                    .map_err(|source| PlanError::Frame { which, source })?;
                Place {
                    north_m: ned.north_m,
                    east_m: ned.east_m,
                    lat_deg,
                    lon_deg,
                }
            }
        };
        let nearest_free = || -> Result<Option<Place>, PlanError> {
            grid.nearest_free_ne(at.north_m, at.east_m)
                .map(|c| {
                    let (n, e) = grid.center_ne(c);
                    place(n, e, which)
                })
                .transpose()
        };
        let Some(cell) = grid.cell_at_ne(at.north_m, at.east_m) else {
            let f = grid.frame();
            return Err(PlanError::OffMap {
                which,
                at,
                north_min_m: f.origin_north_m,
                north_max_m: f.origin_north_m + f64::from(grid.rows()) * f.cell_m,
                east_min_m: f.origin_east_m,
                east_max_m: f.origin_east_m + f64::from(grid.cols()) * f.cell_m,
                nearest_free: nearest_free()?,
            });
        };
        if grid.is_blocked(cell) {
            return Err(PlanError::Blocked {
                which,
                at,
                safety_m: spec.safety_m,
                alt_m: spec.alt_m,
                nearest_free: nearest_free()?,
            });
        }
        Ok((at, cell))
    };
    let (start, start_cell) = resolve(request.start, Endpoint::Start)?;
    let (goal, goal_cell) = resolve(request.goal, Endpoint::Goal)?;

    let t_search = Instant::now();
    let searched =
        GridSearch::new().search(&grid, start_cell, goal_cell, request.model, request.planner);
    let search_us = micros(t_search.elapsed());
    let path = match searched {
        Ok(path) => path,
        Err(SearchError::Unreachable { expansions }) => {
            return Err(explain_unreachable(
                &grid, request, start_cell, goal_cell, expansions, &place,
            ));
        }
        Err(other) => {
            return Err(PlanError::Internal(format!(
                "search refused checked endpoints: {other}"
            )));
        }
    };

    let t_post = Instant::now();
    let touch = touch_for(request.model);
    let pruned = match request.prune {
        Prune::None => path.cells.clone(),
        Prune::Collinear => prune_collinear(&path.cells),
        Prune::Epsilon(eps) => prune_collinear_eps(&grid, &path.cells, eps, touch),
    };
    let shortcut_cells = if request.shortcut {
        shortcut(&grid, &pruned, touch)
    } else {
        pruned.clone()
    };
    let points = waypoint_points(&grid, &shortcut_cells, &start, &goal, touch);
    let postprocess_us = micros(t_post.elapsed());

    // Never hand out a route through an obstacle: re-check every segment independently.
    if let Some(w) = points
        .windows(2)
        .find(|w| !grid.segment_is_free_ne(w[0], w[1], touch))
    {
        return Err(PlanError::Internal(format!(
            "segment {:?} → {:?} meets a blocked cell",
            w[0], w[1]
        )));
    }
    let mission = Mission::from_points_ne(&frame, &points, spec.alt_m, request.start_heading_rad)
        .map_err(|source| PlanError::Frame {
        which: Endpoint::Goal,
        source,
    })?;
    let active_obstacles = map
        .boxes
        .iter()
        .filter(|b| {
            b.top_m() + spec.safety_m > spec.alt_m && b.bottom_m() - spec.safety_m < spec.alt_m
        })
        .copied()
        .collect();
    let cost_m = path.cost_cells() * spec.cell_m;
    let octile_optimum_m = match request.planner {
        Planner::ThetaStar => GridSearch::new()
            .search(&grid, start_cell, goal_cell, request.model, Planner::Jps)
            .ok()
            .map(|p| p.cost_cells() * spec.cell_m),
        _ => None,
    };
    let straight_line_m = {
        let ((a_n, a_e), (b_n, b_e)) = (grid.center_ne(start_cell), grid.center_ne(goal_cell));
        (a_n - b_n).hypot(a_e - b_e)
    };
    Ok(PlanOutcome {
        active_obstacles,
        frame,
        start,
        goal,
        start_cell,
        goal_cell,
        cost_m,
        octile_optimum_m,
        straight_line_m,
        pruned,
        shortcut: shortcut_cells,
        mission,
        timings: Timings {
            grid_build_us,
            search_us,
            postprocess_us,
            total_us: micros(t_start.elapsed()),
        },
        path,
        grid,
    })
}

/// Local points of the mission: the exact start, the centres of the kept cells, the exact goal.
/// The exact start replaces its cell's centre when the first segment stays free from there
/// (likewise the goal); otherwise it is added as a short hop inside its own free cell.
fn waypoint_points(
    grid: &Grid2,
    cells: &[Cell],
    start: &Place,
    goal: &Place,
    touch: skyplan_cspace::Touch,
) -> Vec<(f64, f64)> {
    let mut points: Vec<(f64, f64)> = cells.iter().map(|&c| grid.center_ne(c)).collect();
    let exact_start = (start.north_m, start.east_m);
    let exact_goal = (goal.north_m, goal.east_m);
    if points.len() == 1 {
        points = vec![exact_start, exact_goal];
        points.dedup();
        return points;
    }
    if grid.segment_is_free_ne(exact_start, points[1], touch) {
        points[0] = exact_start;
    } else {
        points.insert(0, exact_start);
    }
    let n = points.len();
    if grid.segment_is_free_ne(points[n - 2], exact_goal, touch) {
        points[n - 1] = exact_goal;
    } else {
        points.push(exact_goal);
    }
    points.dedup();
    points
}

fn explain_unreachable(
    grid: &Grid2,
    request: &PlanRequest,
    start_cell: Cell,
    goal_cell: Cell,
    expansions: u64,
    place: &dyn Fn(f64, f64, Endpoint) -> Result<Place, PlanError>,
) -> PlanError {
    let components = Components::new(grid, request.model);
    let size = |c: Cell| components.label(c).map_or(0, |l| components.size(l));
    let start_label = components.label(start_cell);
    let (goal_n, goal_e) = grid.center_ne(goal_cell);
    let nearest = (0..grid.len())
        .map(|i| grid.cell(i))
        .filter(|&c| components.label(c) == start_label)
        .min_by(|&a, &b| {
            let d = |c: Cell| {
                let (n, e) = grid.center_ne(c);
                (n - goal_n).hypot(e - goal_e)
            };
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(start_cell);
    let (n, e) = grid.center_ne(nearest);
    match place(n, e, Endpoint::Goal) {
        Ok(nearest_reachable) => PlanError::Unreachable {
            alt_m: request.spec.alt_m,
            safety_m: request.spec.safety_m,
            start_region_cells: size(start_cell),
            goal_region_cells: size(goal_cell),
            expansions,
            nearest_reachable,
        },
        Err(e) => e,
    }
}
