//! [`Plan`]: a planned route with its statistics and the geometry pictures need.

use crate::planner_id::PlannerId;
use serde::Serialize;
use serde_json::{Map, Value};
use skyplan_cspace::Grid2;
use skyplan_mission::Mission;
use std::sync::Arc;

/// A resolved start or goal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Place {
    /// Metres north of the map's origin.
    pub north_m: f64,
    /// Metres east of the map's origin.
    pub east_m: f64,
    /// Altitude above home, metres.
    pub alt_m: f64,
    /// Latitude, degrees (maps with a geodetic home).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lat_deg: Option<f64>,
    /// Longitude, degrees (maps with a geodetic home).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lon_deg: Option<f64>,
    /// The grid cell `[row, col]` (grid planners).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cell: Option<[u32; 2]>,
}

impl std::fmt::Display for Place {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "N {:.2} m, E {:.2} m", self.north_m, self.east_m)?;
        if let (Some(lat), Some(lon)) = (self.lat_deg, self.lon_deg) {
            write!(f, " (lat {lat:.7}, lon {lon:.7})")?;
        }
        Ok(())
    }
}

/// The grid a 2D planner ran on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GridInfo {
    /// Rows (north).
    pub rows: u32,
    /// Columns (east).
    pub cols: u32,
    /// Cell size, metres.
    pub cell_m: f64,
    /// Southern edge, metres north of the origin.
    pub origin_north_m: f64,
    /// Western edge, metres east of the origin.
    pub origin_east_m: f64,
    /// Altitude of the slice, metres.
    pub alt_m: f64,
    /// Margin grown around obstacles, metres.
    pub safety_m: f64,
    /// Blocked cells.
    pub blocked_cells: usize,
}

impl GridInfo {
    /// The facts of `grid`, a slice at `alt_m` with obstacles grown by `safety_m`.
    ///
    /// ```
    /// use skyplan_cspace::{Grid2, GridFrame};
    /// let frame = GridFrame { origin_north_m: -2.0, origin_east_m: 0.0, cell_m: 0.5 };
    /// let grid = Grid2::new(2, 3, vec![false, true, false, false, false, true], frame)?;
    /// let info = skyplan_plan::GridInfo::of(&grid, 5.0, 3.0);
    /// assert_eq!((info.rows, info.cols, info.blocked_cells), (2, 3, 2));
    /// assert_eq!((info.origin_north_m, info.cell_m, info.alt_m), (-2.0, 0.5, 5.0));
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn of(grid: &skyplan_cspace::Grid2, alt_m: f64, safety_m: f64) -> Self {
        let f = grid.frame();
        GridInfo {
            rows: grid.rows(),
            cols: grid.cols(),
            cell_m: f.cell_m,
            origin_north_m: f.origin_north_m,
            origin_east_m: f.origin_east_m,
            alt_m,
            safety_m,
            blocked_cells: grid.blocked_count(),
        }
    }
}

/// Latitude and longitude of the map's home.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Home {
    /// Degrees.
    pub lat_deg: f64,
    /// Degrees.
    pub lon_deg: f64,
}

/// A grid path's moves and what post-processing made of it (grid planners).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct GridPathStats {
    /// Cells of the grid path.
    pub path_cells: usize,
    /// Orthogonal moves of the grid path.
    pub straight_moves: u64,
    /// Diagonal moves of the grid path.
    pub diagonal_moves: u64,
    /// Waypoint counts through the passes.
    pub waypoint_counts: WaypointCounts,
}

/// Waypoint counts through the post-processing passes (grid planners).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct WaypointCounts {
    /// Cells of the raw grid path.
    pub grid_path: usize,
    /// After collinearity pruning.
    pub after_pruning: usize,
    /// After the line-of-sight shortcut.
    pub after_shortcut: usize,
    /// Waypoints of the mission (with the exact start and goal).
    pub mission: usize,
}

/// Wall time of each stage, microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Timings {
    /// Building (or fetching from the session) the grid / world / roadmap.
    pub grid_build_us: u64,
    /// The search alone.
    pub search_us: u64,
    /// Pruning and shortcutting.
    pub postprocess_us: u64,
    /// The whole request.
    pub total_us: u64,
}

/// A segment in north/east/altitude metres.
pub type Segment3 = [[f64; 3]; 2];

/// What pictures draw besides the route (only when the request asks for `geometry`).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Geometry {
    /// The route before post-processing: the grid path's cell centres, the voxel lattice path,
    /// the roadmap route before shortcutting.
    pub raw_path: Vec<[f64; 3]>,
    /// Roadmap edges or tree edges.
    pub edges: Vec<Segment3>,
    /// What `edges` are (`PRM roadmap`, `RRT* tree`, `Voronoi graph`, …).
    pub edges_label: String,
    /// Connectors from the start and goal to a roadmap.
    pub connectors: Vec<Segment3>,
    /// A field over the grid's cells, row-major from the southern row (distance or
    /// cost-to-go, cells; `inf` where unreachable).
    #[serde(skip)]
    pub field: Option<Vec<f64>>,
    /// The obstacles that count at the altitude (2D planners on colliders maps).
    #[serde(skip)]
    pub active_boxes: Vec<skyplan_map::colliders::ObstacleBox>,
    /// The building footprints that count at the altitude (2D planners on footprint maps).
    #[serde(skip)]
    pub active_footprints: Vec<skyplan_map::footprints::Footprint>,
}

/// The request as it was planned: every default applied and every value checked, so that
/// pictures, benchmarks, the replanner and the flight read one margin, altitude and move model.
///
/// ```
/// use skyplan_plan::PlanRequest;
/// let spec = PlanRequest { alt_m: Some(12.0), ..Default::default() }.spec()?;
/// assert_eq!((spec.alt_m, spec.safety_m, spec.cell_m), (12.0, 5.0, 1.0));
/// assert!(PlanRequest { safety_m: Some(-1.0), ..Default::default() }.spec().is_err());
/// # Ok::<(), skyplan_plan::PlanFailure>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlanSpec {
    /// Flight altitude above home, metres (the 2D planners' slice).
    pub alt_m: f64,
    /// Safety margin grown around every obstacle, metres.
    pub safety_m: f64,
    /// Grid cell size of colliders maps, metres.
    pub cell_m: f64,
    /// How grid paths move.
    #[serde(serialize_with = "serialize_model")]
    pub move_model: skyplan_search::MoveModel,
    /// Floor of the flight volume (3D planners), metres.
    pub min_alt_m: f64,
    /// Ceiling of the flight volume (3D planners), metres.
    pub max_alt_m: f64,
}

fn serialize_model<S: serde::Serializer>(
    model: &skyplan_search::MoveModel,
    s: S,
) -> Result<S::Ok, S::Error> {
    s.serialize_str(crate::model_name(*model))
}

impl PlanSpec {
    /// The slice of a colliders map this spec plans on.
    pub fn grid_spec(&self) -> skyplan_cspace::GridSpec {
        skyplan_cspace::GridSpec {
            alt_m: self.alt_m,
            safety_m: self.safety_m,
            cell_m: self.cell_m,
        }
    }
}

/// A planned route: waypoints from the exact start to the exact goal, every segment re-checked.
#[derive(Debug, Clone, Serialize)]
pub struct Plan {
    /// Always `"ok"` (failures are `PlanFailure`s); kept so JSON readers can test one field.
    pub status: &'static str,
    /// The map's name.
    pub map: String,
    /// Obstacles: boxes of a colliders map, polygons of a footprint (GeoJSON) map.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub obstacles: Option<usize>,
    /// The geodetic home.
    pub home: Option<Home>,
    /// The planner, by its CLI spelling.
    pub planner: PlannerId,
    /// The request as planned (defaults applied).
    pub spec: PlanSpec,
    /// The grid (2D planners).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grid: Option<GridInfo>,
    /// The move model (grid planners): `8-connected, no corner cutting`, …
    #[serde(skip_serializing_if = "Option::is_none")]
    pub move_model: Option<&'static str>,
    /// Where the route starts.
    pub start: Place,
    /// Where it ends.
    pub goal: Place,
    /// Length of the planner's route, metres (the octile cost of a grid path; the Euclidean
    /// length of any-angle, roadmap and 3D routes).
    pub cost_m: f64,
    /// Length of the waypoints actually flown (after post-processing), metres, in 3D.
    pub mission_length_m: f64,
    /// Straight-line distance from start to goal, metres (a lower bound).
    pub straight_line_m: f64,
    /// Any-angle planners: the octile optimum between the same cells, for comparison.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub octile_optimum_m: Option<f64>,
    /// Nodes the search expanded (samples for the sampling planners).
    pub expansions: u64,
    /// The grid path's moves and waypoint counts (grid planners), flattened into the JSON
    /// object.
    #[serde(flatten)]
    pub grid_path: Option<GridPathStats>,
    /// The search's wall time, microseconds.
    pub search_time_us: u64,
    /// Stage timings.
    pub timings_us: Timings,
    /// Waypoints `[north_m, east_m, alt_m, heading_rad]` (FCND's layout).
    pub waypoints: Vec<[f64; 4]>,
    /// Waypoints' `[lat_deg, lon_deg]` (maps with a geodetic home); over terrain
    /// `[lat_deg, lon_deg, alt_amsl_m]`, the height above mean sea level.
    pub waypoints_lla: Option<Vec<Vec<f64>>>,
    /// Planner-specific details (`roadmap`, `voxel`, `costmap`, `fallback`, …), flattened into
    /// the JSON object.
    #[serde(flatten)]
    pub details: Map<String, Value>,
    /// Pictures' geometry, when asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub geometry: Option<Geometry>,
    /// The trajectory, when asked for (`trajectory`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<TrajectoryReport>,
    /// The mission (maps with a geodetic home): waypoints with lat/lon and headings.
    #[serde(skip)]
    pub mission: Option<Mission>,
    /// The grid the route was planned and checked on (2D planners).
    #[serde(skip)]
    pub grid_used: Option<Arc<Grid2>>,
    /// The PRM roadmap as bytes, when the request asked to save it.
    #[serde(skip)]
    pub saved_roadmap: Option<Vec<u8>>,
}

/// The columns of a trajectory's samples.
pub const TRAJECTORY_COLUMNS: [&str; 11] = [
    "t_s", "north_m", "east_m", "alt_m", "v_north", "v_east", "v_up", "a_north", "a_east", "a_up",
    "yaw_deg",
];

/// A plan's trajectory with its samples and the two times it is measured against.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrajectoryReport {
    /// Total duration, seconds.
    pub duration_s: f64,
    /// Samples per second.
    pub sample_hz: f64,
    /// The samples' columns ([`TRAJECTORY_COLUMNS`]).
    pub columns: [&'static str; 11],
    /// Rows `[t_s, north_m, east_m, alt_m, v_north, v_east, v_up, a_north, a_east, a_up,
    /// yaw_deg]`, from 0 to the end.
    pub samples: Vec<[f64; 11]>,
    /// Length of the flown curve, metres.
    pub length_m: f64,
    /// Duration of the jerk-limited stop-at-each-waypoint profile of the same route, seconds.
    pub stop_at_waypoints_s: f64,
    /// The route's length over the speed limit, seconds (no trajectory is faster).
    pub length_over_max_speed_s: f64,
    /// The trajectory: method, pieces, proven bounds, limits.
    #[serde(flatten)]
    pub trajectory: skyplan_trajectory::Trajectory,
}

impl Plan {
    /// The raw path's cells on the grid used, for a text picture: empty unless a cell planner
    /// (grid search, wavefront, costmap) planned on a grid and kept its geometry.
    pub fn path_cells(&self) -> Vec<skyplan_cspace::Cell> {
        let cell_planner = self.planner.is_cell_planner();
        match (&self.grid_used, &self.geometry) {
            (Some(grid), Some(g)) if cell_planner => g
                .raw_path
                .iter()
                .filter_map(|p| grid.cell_at_ne(p[0], p[1]))
                .collect(),
            _ => Vec::new(),
        }
    }

    /// The waypoints as `[north_m, east_m, alt_m]` points.
    pub fn points_nea(&self) -> Vec<[f64; 3]> {
        self.waypoints.iter().map(|w| [w[0], w[1], w[2]]).collect()
    }
}
