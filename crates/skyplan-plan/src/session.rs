//! [`Session`]: one world loaded once, many requests answered; caches what requests share
//! (grids per altitude/margin/cell size, 3D box worlds, Voronoi and PRM roadmaps).

use crate::algorithm::Workspace;
use crate::auto::{AutoPick, MapStats};
use crate::failure::{FailureKind, PlanFailure};
use crate::plan::{
    Geometry, GridInfo, GridPathStats, Home, Place, Plan, TRAJECTORY_COLUMNS, Timings,
    TrajectoryReport, WaypointCounts,
};
use crate::planner_id::{MapKinds, PlannerId};
use crate::request::{PlanRequest, Position, Resolved, RoadmapIo, TrajectorySpec};
use crate::world::{Limits, Source, World, check_memory};
use crate::zone_times::{ZoneReport, meets_window};
use serde_json::{Map, Value};
use skyplan_cspace::{Cell, Grid2, GridSpec, Touch};
use skyplan_frames::{Lla, Ned};
use skyplan_map::nofly::{Zone, ZoneShape};
use skyplan_mission::Mission;
use skyplan_search::ch_file::ChFileError;
use skyplan_search::first_move_file::FirstMoveFileError;
use skyplan_search::subgoal_file::SubgoalFileError;
use skyplan_search::table_file::{TableFileError, read_header_from};
use skyplan_search::{
    ContractionHierarchy, FirstMoveError, FirstMoveTable, JpsPlusTable, MoveModel, SubgoalError,
    SubgoalGraph,
};
use skyplan_world3::{Aabb, BoxWorld3, Prism, WorldSpec};
use std::collections::HashMap;
use std::io::{Read, Write};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Bytes per cell of a colliders grid while it is built and kept.
const GRID_BYTES_PER_CELL: u64 = 2;

/// Most entries kept per cache (a server asked for many altitudes does not grow without bound).
const CACHE_ENTRIES: usize = 8;

pub(crate) type Key = [u64; 5];

pub(crate) fn key(values: [f64; 5]) -> Key {
    values.map(f64::to_bits)
}

fn put<V: Clone>(cache: &mut HashMap<Key, V>, k: Key, v: V) -> V {
    if cache.len() >= CACHE_ENTRIES {
        cache.clear();
    }
    cache.insert(k, v.clone());
    v
}

/// Preprocessing kept across requests (a JPS+ table, a hierarchy, a graph, a table of first
/// moves): the most recent few ([`CACHE_ENTRIES`] by default), each found by what it was built
/// for.
pub(crate) struct Kept<T>(Vec<Arc<T>>, usize);

impl<T> Default for Kept<T> {
    fn default() -> Self {
        Self(Vec::new(), CACHE_ENTRIES)
    }
}

impl<T> Kept<T> {
    /// Keeping at most `most` (at least one).
    pub(crate) fn at_most(most: usize) -> Self {
        Self(Vec::new(), most.max(1))
    }

    /// The kept one `hit` matches.
    pub(crate) fn find(&self, hit: impl Fn(&T) -> bool) -> Option<&Arc<T>> {
        self.0.iter().find(|t| hit(t))
    }

    /// Whether one is kept that `hit` matches.
    pub(crate) fn any(&self, hit: impl Fn(&T) -> bool) -> bool {
        self.find(hit).is_some()
    }

    /// Drops the ones `hit` matches (before one replacing them is read, so the two are never
    /// held at once).
    pub(crate) fn drop_where(&mut self, hit: impl Fn(&T) -> bool) {
        self.0.retain(|t| !hit(t));
    }

    /// Keeps `item`, dropping the oldest past the most it keeps.
    pub(crate) fn keep(&mut self, item: Arc<T>) {
        if self.0.len() >= self.1 {
            self.0.remove(0);
        }
        self.0.push(item);
    }

    /// The kept one `hit` matches, or else `build`'s, kept, with its build time in µs.
    pub(crate) fn get_or_build<E>(
        &mut self,
        hit: impl Fn(&T) -> bool,
        build: impl FnOnce() -> Result<T, E>,
    ) -> Result<(Arc<T>, Option<u64>), E> {
        if let Some(t) = self.find(hit) {
            return Ok((Arc::clone(t), None));
        }
        let t0 = Instant::now();
        let item = Arc::new(build()?);
        let us = micros(t0.elapsed());
        self.keep(Arc::clone(&item));
        Ok((item, Some(us)))
    }
}

/// Subgoal graphs are for 8-connected moves without corner cutting: a request with another
/// move model (which `subgoal` answers with a contraction hierarchy) neither saves nor loads one.
fn octile_only(r: &Resolved) -> Result<(), PlanFailure> {
    if r.model == MoveModel::Octile {
        return Ok(());
    }
    Err(PlanFailure::bad_request(
        "a subgoal graph is for 8-connected moves without corner cutting (connectivity 8, corner_cutting false); with this request's moves subgoal plans with a contraction hierarchy: save that with planner ch",
    ))
}

pub(crate) fn micros(d: Duration) -> u64 {
    u64::try_from(d.as_micros()).unwrap_or(u64::MAX)
}

/// A preprocessing build that failed: past its time limit (a timeout, naming the planners that
/// answer at once), or refused (a bad request).
fn preprocessing_failure(planner: &str, late: bool, e: impl std::fmt::Display) -> PlanFailure {
    if late {
        PlanFailure::new(
            crate::FailureKind::Timeout,
            format!(
                "planner {planner}: {e}: its preprocessing takes long on this map; jps-plus or jps answer at once"
            ),
        )
    } else {
        PlanFailure::bad_request(format!("planner {planner}: {e}"))
    }
}

/// How the final re-check runs.
pub(crate) enum Check {
    /// Every segment against the grid, with the move model's corner rule.
    Grid { grid: Arc<Grid2>, touch: Touch },
    /// Every segment against every grown box (brute force).
    Boxes(Arc<BoxWorld3>),
    /// Every segment under the any-angle rule: along blocked cells' boundaries, never through
    /// their interiors nor between two blocked cells that touch only at a corner.
    AnyAngle(Arc<Grid2>),
}

/// What a planner family hands back to the session.
pub(crate) struct Route {
    /// Waypoints, exactly the start first and exactly the goal last.
    pub points: Vec<[f64; 3]>,
    pub cost_m: f64,
    pub check: Check,
    pub start_cell: Option<Cell>,
    pub goal_cell: Option<Cell>,
    pub expansions: u64,
    /// Build, search and post-processing times (the session fills in the total).
    pub timings: Timings,
    /// Grid planners: path cells, straight moves, diagonal moves, waypoint counts.
    pub grid_path: Option<GridPathStats>,
    pub octile_optimum_m: Option<f64>,
    pub details: Map<String, Value>,
    pub geometry: Geometry,
    pub grid: Option<Arc<Grid2>>,
    pub saved_roadmap: Option<Vec<u8>>,
}

impl Route {
    pub(crate) fn new(points: Vec<[f64; 3]>, cost_m: f64, check: Check) -> Self {
        Self {
            points,
            cost_m,
            check,
            start_cell: None,
            goal_cell: None,
            expansions: 0,
            timings: Timings::default(),
            grid_path: None,
            octile_optimum_m: None,
            details: Map::new(),
            geometry: Geometry::default(),
            grid: None,
            saved_roadmap: None,
        }
    }

    /// Records a grid search: its end cells and expansions, then `moves` (path cells, straight
    /// moves, diagonal moves) and the waypoints left (after pruning, after the shortcut).
    pub(crate) fn record_grid_search(
        &mut self,
        (start, goal): (Cell, Cell),
        expansions: u64,
        moves: (usize, u64, u64),
        (after_pruning, after_shortcut): (usize, usize),
    ) {
        self.start_cell = Some(start);
        self.goal_cell = Some(goal);
        self.expansions = expansions;
        self.grid_path = Some(GridPathStats {
            path_cells: moves.0,
            straight_moves: moves.1,
            diagonal_moves: moves.2,
            waypoint_counts: WaypointCounts {
                grid_path: moves.0,
                after_pruning,
                after_shortcut,
                mission: 0,
            },
        });
    }
}

/// What every planner family gets: the request, resolved, and both ends in local metres.
pub(crate) struct Query<'a> {
    pub r: &'a Resolved,
    pub start_ne: [f64; 2],
    pub goal_ne: [f64; 2],
    pub world: &'a World,
    /// A PRM roadmap to start from, and whether to return it.
    pub roadmap: &'a RoadmapIo,
    /// The request's no-fly zones in the map's frame (empty: none).
    pub zones: &'a [skyplan_map::nofly::Zone],
}

/// A world loaded once and the caches its requests share.
///
/// ```
/// use skyplan_plan::{PlanRequest, PlannerId, Session, World};
/// let mut session = Session::new(World::fcnd_city());
/// // The default request: JPS from the home to the default goal at 5 m with a 5 m margin.
/// let plan = session.plan(&PlanRequest::default())?;
/// assert_eq!(plan.planner, PlannerId::Jps);
/// assert!((plan.cost_m - 1097.94).abs() < 0.01);
/// // The same world, another planner: the grid is reused.
/// let theta = session.plan(&PlanRequest { planner: Some(PlannerId::Theta), ..Default::default() })?;
/// assert!(theta.cost_m < plan.cost_m);
/// # Ok::<(), skyplan_plan::PlanFailure>(())
/// ```
pub struct Session {
    world: World,
    limits: Limits,
    grids: HashMap<Key, Arc<Grid2>>,
    boxes: HashMap<Key, Arc<BoxWorld3>>,
    pub(crate) voronoi: HashMap<Key, Arc<skyplan_roadmap::Roadmap>>,
    pub(crate) prm: HashMap<Key, skyplan_sampling::prm::Roadmap>,
    pub(crate) any_angle: HashMap<Key, Arc<skyplan_anyangle::AnyAngle>>,
    /// The cell searches' buffers, reused between queries.
    pub(crate) workspace: Workspace,
    /// JPS+ preprocessing kept across requests (built on first use or loaded from a file).
    jps_plus: Kept<JpsPlusTable>,
    /// Contraction hierarchies kept across requests (built on first use per grid and model).
    ch: Kept<ContractionHierarchy>,
    /// Subgoal graphs kept across requests (built on first use per grid).
    subgoal: Kept<SubgoalGraph>,
    /// First-move tables kept across requests (built on first use per grid and model): two at
    /// most, each up to [`crate::auto::FIRST_MOVE_MAX_BYTES`].
    first_move: Kept<FirstMoveTable>,
    /// When long preprocessing (a contraction hierarchy) must give up, if ever.
    deadline: Option<Instant>,
    /// `auto`'s statistics per grid and the `auto` queries on it so far.
    auto: Vec<(Arc<Grid2>, MapStats, u64)>,
}

impl Session {
    /// A session over `world`.
    pub fn new(world: World) -> Self {
        Self {
            world,
            limits: Limits::default(),
            grids: HashMap::new(),
            boxes: HashMap::new(),
            voronoi: HashMap::new(),
            prm: HashMap::new(),
            any_angle: HashMap::new(),
            workspace: Workspace::default(),
            jps_plus: Kept::default(),
            ch: Kept::default(),
            subgoal: Kept::default(),
            first_move: Kept::at_most(2),
            deadline: None,
            auto: Vec::new(),
        }
    }

    /// The same session with other resource limits.
    pub fn with_limits(mut self, limits: Limits) -> Self {
        self.limits = limits;
        self
    }

    /// Until when preprocessing that can take minutes (the `ch` planner's contraction hierarchy
    /// on an open map) may run; past it the request fails with kind `timeout`. `None` (the
    /// default): no limit. A server sets it from its time budget before each request.
    pub fn set_deadline(&mut self, deadline: Option<Instant>) {
        self.deadline = deadline;
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The grid at an altitude, margin and cell size (built once per session; the fixed grid
    /// of image, MovingAI and random maps whatever the arguments). An altitude outside
    /// 0..=[`MAX_ALT_M`](crate::MAX_ALT_M) is a bad request, as in a [`PlanRequest`](crate::PlanRequest).
    pub fn grid(
        &mut self,
        alt_m: f64,
        safety_m: f64,
        cell_m: f64,
    ) -> Result<Arc<Grid2>, PlanFailure> {
        enum Obstacles {
            Boxes(Arc<skyplan_map::colliders::CollidersMap>),
            Footprints(Arc<crate::world::Footprints>),
        }
        let map = match &self.world.source {
            Source::Grid(g) => return Ok(Arc::clone(g)),
            Source::Colliders(m) => Obstacles::Boxes(Arc::clone(m)),
            Source::Footprints(f) => Obstacles::Footprints(Arc::clone(f)),
        };
        crate::request::in_range("alt_m", alt_m, 0.0, crate::MAX_ALT_M, " m").map_err(|f| {
            PlanFailure::bad_request(format!("{}: {}", self.world.name(), f.message))
        })?;
        let k = key([alt_m, safety_m, cell_m, 0.0, 0.0]);
        if let Some(g) = self.grids.get(&k) {
            return Ok(Arc::clone(g));
        }
        let cells = self.world.cells_at(cell_m);
        check_memory(
            cells.saturating_mul(GRID_BYTES_PER_CELL),
            &self.limits,
            &format!(
                "{}: a grid of {cells} cells of {cell_m} m",
                self.world.name()
            ),
            "use a larger cell_m",
        )?;
        let spec = GridSpec {
            alt_m,
            safety_m,
            cell_m,
        };
        let grid = match &map {
            Obstacles::Boxes(m) => Grid2::from_colliders(m, spec),
            Obstacles::Footprints(f) => Grid2::from_footprints(&f.local, spec),
        }
        .map_err(|e| PlanFailure::bad_request(format!("{}: {e}", self.world.name())))?;
        Ok(put(&mut self.grids, k, Arc::new(grid)))
    }

    // ---- JPS+ preprocessing kept by the session, saved and loaded (issue 14) ----

    /// The JPS+ table of `grid` under `model`: kept from an earlier request or a loaded file,
    /// or built now (then also the build time in microseconds).
    pub(crate) fn jps_plus_table(
        &mut self,
        grid: &Arc<Grid2>,
        model: MoveModel,
    ) -> (Arc<JpsPlusTable>, Option<u64>) {
        let model = if model == MoveModel::OctileCornerCutting {
            model
        } else {
            MoveModel::Octile
        };
        let Ok(kept) = self.jps_plus.get_or_build(
            |t| t.model() == model && Arc::ptr_eq(t.grid(), grid),
            || Ok::<_, std::convert::Infallible>(JpsPlusTable::build(Arc::clone(grid), model)),
        );
        kept
    }

    /// Writes the JPS+ table for `request`'s grid and corner rule (built unless the session
    /// has it) to `out` as a table file, for [`Session::load_jps_plus`] in a later run; the
    /// bytes written. The table is streamed from its own memory (no copy is made).
    pub fn save_jps_plus(
        &mut self,
        request: &PlanRequest,
        out: impl Write,
    ) -> Result<u64, PlanFailure> {
        let r = Resolved::new(&PlanRequest {
            planner: Some(PlannerId::JpsPlus),
            ..request.clone()
        })?;
        self.check_request_memory(&r)?;
        let grid = self.grid(r.alt_m, r.safety_m, r.cell_m)?;
        // A saved table serves many later queries: it keeps landmarks for them (built once;
        // this session's later queries use them too): 4 bytes per cell and landmark more.
        let landmarks = skyplan_search::landmarks_for(grid.len());
        check_memory(
            (grid.len() as u64).saturating_mul(8 + 4 * landmarks as u64),
            &self.limits,
            &format!(
                "a saved JPS+ table with {landmarks} landmarks on {} ({} cells)",
                self.world.name(),
                grid.len()
            ),
            "use a larger cell_m",
        )?;
        let (table, _) = self.jps_plus_table(&grid, r.model);
        table.add_landmarks(landmarks);
        let spec = match self.world.source {
            Source::Grid(_) => [f64::NAN; 3],
            Source::Colliders(_) | Source::Footprints(_) => [r.alt_m, r.safety_m, r.cell_m],
        };
        table
            .write_to(out, spec)
            .map_err(|e| PlanFailure::internal(format!("writing the JPS+ table: {e}")))?;
        Ok(table.file_bytes())
    }

    /// Loads a JPS+ table file saved by [`Session::save_jps_plus`] from `input` (read in
    /// chunks straight into the table: the load needs the table's memory once): later
    /// `jps-plus` requests on its grid use it instead of building one. Refused (bad request,
    /// saying why) unless it was built for this world's grid at the altitude, margin and cell
    /// size it records.
    pub fn load_jps_plus(&mut self, mut input: impl Read) -> Result<(), PlanFailure> {
        let refuse = |e: TableFileError, name: &str| match e {
            TableFileError::Io(_) => PlanFailure::internal(e.to_string()),
            _ => PlanFailure::bad_request(format!("{e}; this session's map is {name}")),
        };
        let header = read_header_from(&mut input).map_err(|e| match e {
            TableFileError::Io(_) => PlanFailure::internal(e.to_string()),
            _ => PlanFailure::bad_request(e.to_string()),
        })?;
        let [alt_m, safety_m, cell_m] = header.spec;
        let fixed = matches!(self.world.source, Source::Grid(_));
        let spec_ok = alt_m.is_finite() && safety_m.is_finite() && cell_m > 0.0;
        if !fixed && !spec_ok {
            return Err(PlanFailure::bad_request(format!(
                "JPS+ table was saved for a fixed grid (an image, MovingAI or random map), not for {}",
                self.world.name()
            )));
        }
        let grid = self.grid(alt_m, safety_m, cell_m)?;
        // Drop a table this one replaces before reading: the two are never held at once.
        self.jps_plus
            .drop_where(|t| t.model() == header.model && Arc::ptr_eq(t.grid(), &grid));
        let table = JpsPlusTable::read_after_header(&header, input, grid)
            .map_err(|e| refuse(e, self.world.name()))?;
        self.jps_plus.keep(Arc::new(table));
        Ok(())
    }

    // ---- end of JPS+ preprocessing ----

    /// The contraction hierarchy of `grid` under `model`: kept from an earlier request, or built
    /// now within `limit` and the session's deadline (then also the build time in microseconds).
    pub(crate) fn contraction_hierarchy(
        &mut self,
        grid: &Arc<Grid2>,
        model: MoveModel,
        limit: Option<Duration>,
    ) -> Result<(Arc<ContractionHierarchy>, Option<u64>), PlanFailure> {
        let deadline = self.preprocessing_deadline(Instant::now(), limit);
        self.ch.get_or_build(
            |c| c.model() == model && Arc::ptr_eq(c.grid(), grid),
            || {
                ContractionHierarchy::build_until(Arc::clone(grid), model, deadline).map_err(|e| {
                    let late = matches!(e, skyplan_search::ContractionError::Deadline { .. });
                    preprocessing_failure("ch", late, e)
                })
            },
        )
    }

    /// When preprocessing started at `t0` must give up: the sooner of the session's deadline and
    /// `t0` + `limit` (the request's time limit), if either.
    fn preprocessing_deadline(&self, t0: Instant, limit: Option<Duration>) -> Option<Instant> {
        match (self.deadline, limit.map(|l| t0 + l)) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// The subgoal graph of `grid` (8-connected, no corner cutting): kept from an earlier
    /// request, or built now within `limit` and the session's deadline (then also the build
    /// time in microseconds).
    pub(crate) fn subgoal_graph(
        &mut self,
        grid: &Arc<Grid2>,
        limit: Option<Duration>,
    ) -> Result<(Arc<SubgoalGraph>, Option<u64>), PlanFailure> {
        let deadline = self.preprocessing_deadline(Instant::now(), limit);
        self.subgoal.get_or_build(
            |g| Arc::ptr_eq(g.grid(), grid),
            || {
                SubgoalGraph::build_until(Arc::clone(grid), MoveModel::Octile, deadline).map_err(
                    |e| {
                        let late = matches!(e, SubgoalError::Deadline { .. });
                        preprocessing_failure("subgoal", late, e)
                    },
                )
            },
        )
    }

    /// The first-move table of `grid` under `model`: kept from an earlier request (built or
    /// loaded), or built now within `limit`, the session's deadline and its memory limit (then
    /// also the build time in microseconds).
    pub(crate) fn first_move_table(
        &mut self,
        grid: &Arc<Grid2>,
        model: MoveModel,
        limit: Option<Duration>,
    ) -> Result<(Arc<FirstMoveTable>, Option<u64>), PlanFailure> {
        let deadline = self.preprocessing_deadline(Instant::now(), limit);
        let max_bytes = self
            .limits
            .max_memory_bytes
            .min(crate::auto::FIRST_MOVE_MAX_BYTES);
        self.first_move.get_or_build(
            |t| t.model() == model && Arc::ptr_eq(t.grid(), grid),
            || {
                FirstMoveTable::build_until(Arc::clone(grid), model, max_bytes, deadline).map_err(
                    |e| {
                        let late = matches!(e, FirstMoveError::Deadline { .. });
                        preprocessing_failure("first-move", late, e)
                    },
                )
            },
        )
    }

    /// Writes the contraction hierarchy for `request`'s grid and move model (built unless the
    /// session has it, within the request's `time_limit_ms` and the session's deadline) to
    /// `out` as a hierarchy file ([`skyplan_search::ch_file`]), for [`Session::load_ch`] in a
    /// later run; the bytes written.
    pub fn save_ch(&mut self, request: &PlanRequest, out: impl Write) -> Result<u64, PlanFailure> {
        let (r, grid) = self.preprocessing_grid(request, PlannerId::Ch)?;
        self.check_request_memory(&r)?;
        let (ch, _) = self.contraction_hierarchy(&grid, r.model, r.preprocess_limit)?;
        ch.write_to(out).map_err(|e| {
            PlanFailure::internal(format!("writing the contraction hierarchy: {e}"))
        })?;
        Ok(ch.file_bytes())
    }

    /// The request as `planner` resolves it, and its grid: what saved preprocessing is for.
    fn preprocessing_grid(
        &mut self,
        request: &PlanRequest,
        planner: PlannerId,
    ) -> Result<(Resolved, Arc<Grid2>), PlanFailure> {
        let r = Resolved::new(&PlanRequest {
            planner: Some(planner),
            ..request.clone()
        })?;
        let grid = self.grid(r.alt_m, r.safety_m, r.cell_m)?;
        Ok((r, grid))
    }

    /// A file's error: the reader's failure is internal, anything else a bad request naming this
    /// session's map.
    fn file_failure(&self, e: impl std::fmt::Display, io: bool) -> PlanFailure {
        if io {
            PlanFailure::internal(e.to_string())
        } else {
            PlanFailure::bad_request(format!("{e}; this session's map is {}", self.world.name()))
        }
    }

    /// Loads a hierarchy file saved by [`Session::save_ch`] for `request`'s grid and move
    /// model: later `ch` requests on that grid, and `auto` on maps where a hierarchy is the
    /// fastest (ARCHITECTURE "How `auto` decides"), use it instead of building one. Refused
    /// (bad request, naming what is wrong: not a hierarchy, another version, truncated,
    /// damaged, another grid or move model) otherwise.
    pub fn load_ch(&mut self, request: &PlanRequest, input: impl Read) -> Result<(), PlanFailure> {
        let (r, grid) = self.preprocessing_grid(request, PlannerId::Ch)?;
        let ch = ContractionHierarchy::read_from(input, Arc::clone(&grid), r.model)
            .map_err(|e| self.file_failure(&e, matches!(e, ChFileError::Io(_))))?;
        self.ch
            .drop_where(|c| c.model() == r.model && Arc::ptr_eq(c.grid(), &grid));
        self.ch.keep(Arc::new(ch));
        Ok(())
    }

    /// Writes the subgoal graph for `request`'s grid (8-connected, no corner cutting; built
    /// unless the session has it, within the request's `time_limit_ms` and the session's
    /// deadline) to `out` as a subgoal graph file ([`skyplan_search::subgoal_file`]), for
    /// [`Session::load_subgoal`] in a later run; the bytes written.
    pub fn save_subgoal(
        &mut self,
        request: &PlanRequest,
        out: impl Write,
    ) -> Result<u64, PlanFailure> {
        let (r, grid) = self.preprocessing_grid(request, PlannerId::Subgoal)?;
        octile_only(&r)?;
        self.check_request_memory(&r)?;
        let (graph, _) = self.subgoal_graph(&grid, r.preprocess_limit)?;
        graph
            .write_to(out)
            .map_err(|e| PlanFailure::internal(format!("writing the subgoal graph: {e}")))?;
        Ok(graph.file_bytes())
    }

    /// Loads a subgoal graph file saved by [`Session::save_subgoal`] for `request`'s grid:
    /// later `subgoal` requests on that grid, and `auto` where a subgoal graph at hand is the
    /// fastest ([`crate::auto::pick_with_subgoal_graph`]), use it instead of building one.
    /// Refused (bad request, naming what is wrong) otherwise.
    pub fn load_subgoal(
        &mut self,
        request: &PlanRequest,
        input: impl Read,
    ) -> Result<(), PlanFailure> {
        let (r, grid) = self.preprocessing_grid(request, PlannerId::Subgoal)?;
        octile_only(&r)?;
        let graph = SubgoalGraph::read_from(input, Arc::clone(&grid)).map_err(|e| {
            let io = matches!(e, SubgoalFileError::Hierarchy(ChFileError::Io(_)));
            self.file_failure(&e, io)
        })?;
        self.subgoal.drop_where(|g| Arc::ptr_eq(g.grid(), &grid));
        self.subgoal.keep(Arc::new(graph));
        Ok(())
    }

    /// Writes the first-move table for `request`'s grid and move model (built unless the
    /// session has it, within the request's `time_limit_ms`, the session's deadline and memory
    /// limit) to `out` as a table file ([`skyplan_search::first_move_file`]), for
    /// [`Session::load_first_move`] in a later run; the bytes written.
    pub fn save_first_move(
        &mut self,
        request: &PlanRequest,
        out: impl Write,
    ) -> Result<u64, PlanFailure> {
        let (r, grid) = self.preprocessing_grid(request, PlannerId::FirstMove)?;
        let (table, _) = self.first_move_table(&grid, r.model, r.preprocess_limit)?;
        table
            .write_to(out)
            .map_err(|e| PlanFailure::internal(format!("writing the first-move table: {e}")))?;
        Ok(table.file_bytes())
    }

    /// Loads a table file saved by [`Session::save_first_move`] for `request`'s grid and move
    /// model: later `first-move` and `auto` requests on that grid use it from the first query.
    /// Refused (bad request, naming what is wrong: not a table, another version, truncated,
    /// damaged, another grid or move model) otherwise.
    pub fn load_first_move(
        &mut self,
        request: &PlanRequest,
        input: impl Read,
    ) -> Result<(), PlanFailure> {
        let (r, grid) = self.preprocessing_grid(request, PlannerId::FirstMove)?;
        // Drop a table this one replaces before reading: the two are never held at once.
        self.first_move
            .drop_where(|t| t.model() == r.model && Arc::ptr_eq(t.grid(), &grid));
        let table = FirstMoveTable::read_from(input, Arc::clone(&grid), r.model)
            .map_err(|e| self.file_failure(&e, matches!(e, FirstMoveFileError::Io(_))))?;
        self.first_move.keep(Arc::new(table));
        Ok(())
    }

    /// `auto`'s pick for one more query on `grid` under `model`: preprocessing the session
    /// keeps for the grid (built or loaded) when the rule would use it, else
    /// [`crate::auto::pick`] for the `auto` queries on the grid so far (the grid's statistics
    /// are measured once).
    pub(crate) fn auto_pick(&mut self, grid: &Arc<Grid2>, model: MoveModel) -> AutoPick {
        let at = match self.auto.iter().position(|(g, ..)| Arc::ptr_eq(g, grid)) {
            Some(at) => at,
            None => {
                if self.auto.len() >= CACHE_ENTRIES {
                    self.auto.remove(0);
                }
                self.auto.push((Arc::clone(grid), MapStats::of(grid), 0));
                self.auto.len() - 1
            }
        };
        let (_, stats, queries) = &mut self.auto[at];
        *queries += 1;
        let (stats, queries) = (*stats, *queries);
        let mut rule = crate::auto::pick_for(&stats, queries, model);
        // A hierarchy the memory limit would refuse: JPS+ (8 bytes per cell) instead.
        let ch_bytes = stats.cells.saturating_mul(
            PlannerId::Ch
                .algorithm()
                .cells()
                .map_or(u64::MAX, |c| c.bytes_per_cell()),
        );
        if rule.planner == PlannerId::Ch && ch_bytes > self.limits.max_memory_bytes {
            rule.planner = PlannerId::JpsPlus;
            rule.why = format!(
                "{}, but a hierarchy would need more memory than the limit: JPS+ instead",
                rule.why
            );
        }
        if rule.planner == PlannerId::FirstMove
            && FirstMoveTable::bytes_for(stats.cells as usize, stats.free as usize)
                > self.limits.max_memory_bytes
        {
            rule.planner = PlannerId::JpsPlus;
            rule.why = format!(
                "{}, but the table would need more memory than the limit: JPS+ instead",
                rule.why
            );
        }
        // A first-move table at hand answers fastest of all, whatever the rule.
        if (self.first_move).any(|t| t.model() == model && Arc::ptr_eq(t.grid(), grid)) {
            return crate::auto::pick_with_first_move_table(&stats, queries);
        }
        let kept = |planner: PlannerId, what: &str| AutoPick {
            planner,
            stats,
            queries,
            why: format!("{what} kept for this grid (built or loaded) answers fastest"),
        };
        // What the rule picks (kept preprocessing is reused by it), unless something faster is
        // kept already: a contraction hierarchy on corridors, else a JPS+ table.
        let corridors = stats.mean_run <= crate::auto::CH_MAX_RUN;
        if matches!(
            rule.planner,
            PlannerId::Ch | PlannerId::Subgoal | PlannerId::FirstMove
        ) {
            return rule;
        }
        if corridors && (self.ch).any(|c| c.model() == model && Arc::ptr_eq(c.grid(), grid)) {
            return kept(PlannerId::Ch, "the contraction hierarchy");
        }
        if model == MoveModel::Octile
            && let Some(g) = self.subgoal.find(|g| Arc::ptr_eq(g.grid(), grid))
            && let Some(pick) = crate::auto::pick_with_subgoal_graph(&stats, queries, g.labelled())
        {
            return pick;
        }
        if rule.planner == PlannerId::JpsPlus {
            return rule;
        }
        let table_model = if model == MoveModel::OctileCornerCutting {
            model
        } else {
            MoveModel::Octile
        };
        if model.has_diagonals()
            && (self.jps_plus).any(|t| t.model() == table_model && Arc::ptr_eq(t.grid(), grid))
        {
            return kept(PlannerId::JpsPlus, "the JPS+ table");
        }
        rule
    }

    /// The 3D world for a request: the map's boxes or footprint prisms grown by the margin,
    /// the no-fly `zones` as prisms grown by it (a circle by its radius plus the margin), the
    /// ground, the altitude band, and horizontal bounds that cover the grid's (so every planner
    /// takes the same points). Kept per volume when there are no zones.
    pub(crate) fn boxes(
        &mut self,
        r: &Resolved,
        zones: &[Zone],
    ) -> Result<Arc<BoxWorld3>, PlanFailure> {
        let (boxes, footprints) = match (self.world.colliders(), self.world.footprints()) {
            (Some(map), _) => (&map.boxes[..], &[][..]),
            (None, Some(f)) => (&[][..], &f.footprints[..]),
            (None, None) => {
                return Err(PlanFailure::bad_request(format!(
                    "planner {}: needs a map of obstacles (FCND colliders, GeoJSON or OpenStreetMap footprints)",
                    r.planner
                )));
            }
        };
        let terrain = self.world.terrain();
        let k = key([
            r.safety_m,
            r.min_alt_m,
            r.max_alt_m,
            r.cell_m,
            terrain.map_or(-1.0, |_| r.alt_m),
        ]);
        if zones.is_empty()
            && let Some(w) = self.boxes.get(&k)
        {
            return Ok(Arc::clone(w));
        }
        let b = self.world.bounds_ne(r.cell_m);
        let (on_ground, standing);
        let (obstacles, footprints) = match terrain {
            None => (boxes, footprints),
            Some(t) => {
                on_ground = boxes_over_terrain(t, boxes, r, &b)?;
                standing = footprints_over_terrain(t, footprints)?;
                (&on_ground[..], &standing[..])
            }
        };
        let spec = WorldSpec {
            safety_m: r.safety_m,
            min_alt_m: r.min_alt_m,
            max_alt_m: r.max_alt_m,
            margin_bounds_m: 0.0,
        };
        let bounds = Aabb {
            min: [b.north_min_m, b.east_min_m, r.min_alt_m],
            max: [b.north_max_m, b.east_max_m, r.max_alt_m],
        };
        let m = r.safety_m;
        let prisms = (footprints.iter())
            .map(|f| Prism::from_footprint(f, m))
            .chain(zones.iter().map(|z| match &z.shape {
                ZoneShape::Polygon(rings) => {
                    Prism::with_growth(rings.clone(), z.floor_m, z.ceiling_m, m, m)
                }
                ZoneShape::Circle { centre, radius_m } => {
                    Prism::with_growth(vec![vec![*centre]], z.floor_m, z.ceiling_m, radius_m + m, m)
                }
            }))
            .collect();
        let world = BoxWorld3::with_prisms(obstacles, prisms, &spec, bounds)
            .map_err(|e| PlanFailure::bad_request(format!("{}: {e}", self.world.name())))?;
        if !zones.is_empty() {
            return Ok(Arc::new(world));
        }
        Ok(put(&mut self.boxes, k, Arc::new(world)))
    }

    /// The memory a request needs, estimated by its planner before anything is allocated.
    fn check_request_memory(&self, r: &Resolved) -> Result<(), PlanFailure> {
        let Some(m) = r.planner.algorithm().memory(&self.world, r) else {
            return Ok(());
        };
        check_memory(
            m.units.saturating_mul(m.bytes_per_unit),
            &self.limits,
            &format!(
                "planner {} on {} ({} {})",
                r.planner,
                self.world.name(),
                m.units,
                m.what
            ),
            m.change,
        )
    }

    /// Plans one request with any planner; the route is re-checked before it is returned.
    pub fn plan(&mut self, request: &PlanRequest) -> Result<Plan, PlanFailure> {
        let t0 = Instant::now();
        let mut r = Resolved::new(request)?;
        self.check_request_memory(&r)?;
        let info = r.planner.info();
        if info.maps == MapKinds::Obstacles
            && self.world.colliders().is_none()
            && self.world.footprints().is_none()
        {
            return Err(PlanFailure::bad_request(format!(
                "planner {}: needs a map of obstacles (FCND colliders, GeoJSON or OpenStreetMap footprints), not a fixed grid; on {} use one of {}",
                r.planner,
                self.world.name(),
                PlannerId::for_maps(false)
                    .map(|p| p.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        if self.world.terrain().is_some() {
            check_terrain_request(&r)?;
        } else if r.alt_agl_m.is_some() {
            return Err(PlanFailure::bad_request(format!(
                "alt_agl_m keeps a height above the ground, and {} has no terrain (a DEM: World::with_terrain, the CLI's --terrain FILE)",
                self.world.name()
            )));
        }
        let zones = self.zones(&r)?;
        let (start_ne, start_lla) =
            self.endpoint(r.start.at, self.world.default_start_ne, "start")?;
        let (goal_ne, goal_lla) = self.endpoint(r.goal.at, self.world.default_goal_ne, "goal")?;
        let three_d = info.dims == 3;
        if let (Some(t), true) = (self.world.terrain(), three_d) {
            let b = self.world.bounds_ne(r.cell_m);
            terrain_volume(t, &mut r, request, &b, [start_ne, goal_ne])?;
        }
        let r = r;
        let world = self.world.clone();
        let q = Query {
            r: &r,
            start_ne,
            goal_ne,
            world: &world,
            roadmap: &request.roadmap,
            zones: &zones,
        };
        let (mut route, zone_report) = self.route_among_zones(&q, &request.trajectory_limits())?;
        if let Some(terrain) = world.terrain() {
            follow_terrain(terrain, &r, &mut route, !three_d)?;
            check_inclusion_bands(&self.projected_zones(&r)?, &route.points, r.safety_m)?;
        }
        let mut plan = assemble(&world, &r, route, [start_lla, goal_lla], t0)?;
        if let Some(report) = zone_report {
            plan.details.insert("no_fly".into(), report.json());
        }
        if let (Some(terrain), Some(rows)) = (world.terrain(), plan.waypoints_lla.as_mut()) {
            for (row, w) in rows.iter_mut().zip(&plan.waypoints) {
                row.push(terrain.amsl_m(w[2]));
            }
        }
        if let Some(spec) = r.trajectory {
            plan.trajectory = Some(self.trajectory(&r, &plan, spec)?);
            plan.timings_us.total_us = micros(t0.elapsed());
        }
        Ok(plan)
    }

    /// The route of `q` (re-checked), planned among the zones that apply to its flight (see
    /// [`crate::zone_times`]), and what the plan says about its zones (`None` without zones).
    fn route_among_zones(
        &mut self,
        q: &Query,
        limits: &crate::TrajectoryLimits,
    ) -> Result<(Route, Option<ZoneReport>), PlanFailure> {
        let route_with = |session: &mut Self, zones: &[Zone]| {
            let route =
                q.r.planner
                    .algorithm()
                    .plan(session, &Query { zones, ..*q })?;
            recheck(&route)?;
            Ok::<_, PlanFailure>(route)
        };
        // The altitudes the route may take: the flight altitude, or a 3D planner's volume.
        let alts = if q.r.planner.info().dims == 3 {
            [q.r.min_alt_m, q.r.max_alt_m]
        } else {
            [q.r.alt_m, q.r.alt_m]
        };
        let report = |applied: &[Zone]| ZoneReport::new(q.zones, applied, alts, q.r.safety_m);
        if q.r.no_fly.is_none() {
            return Ok((route_with(self, q.zones)?, None));
        }
        let Some(departure) = q.r.departure_unix_s else {
            let mut r = report(q.zones);
            r.timed_always = (q.zones.iter())
                .filter(|z| z.start_unix_s.is_some() || z.end_unix_s.is_some())
                .map(|z| z.feature)
                .collect();
            return Ok((route_with(self, q.zones)?, Some(r)));
        };
        let arrival = |route: &Route| -> Result<i64, PlanFailure> {
            let stop = skyplan_trajectory::stop_at_waypoints(&route.points, limits)
                .map_err(|e| PlanFailure::internal(format!("the flight's latest arrival: {e}")))?;
            Ok(departure.saturating_add(crate::latest_arrival_s(stop.duration_s()).ceil() as i64))
        };
        let open: Vec<Zone> = (q.zones.iter())
            .filter(|z| meets_window(z, departure, i64::MAX))
            .cloned()
            .collect();
        let during = |zones: &[Zone], until: i64| -> Vec<Zone> {
            (zones.iter())
                .filter(|z| meets_window(z, departure, until))
                .cloned()
                .collect()
        };
        let first = match route_with(self, &open) {
            Ok(route) => route,
            // A zone that opens only later may be what blocks every way (or covers an end):
            // among the zones active at the departure alone, kept if no other opens before
            // that route's latest arrival.
            Err(e)
                if matches!(
                    e.kind,
                    FailureKind::NoPath | FailureKind::InvalidStart | FailureKind::InvalidGoal
                ) =>
            {
                let now = during(&open, departure.saturating_add(1));
                if now.len() == open.len() {
                    return Err(e);
                }
                let Ok(route) = route_with(self, &now) else {
                    return Err(e);
                };
                let until = arrival(&route)?;
                if during(&open, until).len() > now.len() {
                    return Err(e);
                }
                let mut r = report(&now);
                r.window = Some((departure, until));
                return Ok((route, Some(r)));
            }
            Err(e) => return Err(e),
        };
        let first_arrival = arrival(&first)?;
        let fewer = during(&open, first_arrival);
        if fewer.len() < open.len()
            && let Ok(second) = route_with(self, &fewer)
        {
            let second_arrival = arrival(&second)?;
            // The zones open during a flight only grow with its length.
            if during(&open, second_arrival).len() <= fewer.len() {
                let mut r = report(&fewer);
                r.window = Some((departure, second_arrival));
                return Ok((second, Some(r)));
            }
        }
        let mut r = report(&open);
        r.window = Some((departure, first_arrival));
        Ok((first, Some(r)))
    }

    /// The request's no-fly zones in the map's frame, or a bad request: zones need a map whose
    /// grid is at an altitude (colliders or footprints) and a 2D planner; all of them, whatever
    /// their times ([`Session::route_among_zones`] picks those that apply).
    fn zones(&self, r: &Resolved) -> Result<Vec<skyplan_map::nofly::Zone>, PlanFailure> {
        if r.no_fly.is_none() {
            return Ok(Vec::new());
        }
        let name = self.world.name();
        if !matches!(
            self.world.source,
            Source::Colliders(_) | Source::Footprints(_)
        ) {
            return Err(PlanFailure::bad_request(format!(
                "no_fly: {name} is a fixed grid, not a map at an altitude; no-fly zones need a colliders or footprint map"
            )));
        }
        let info = r.planner.info();
        if info.dims == 2 && info.maps == MapKinds::Obstacles {
            return Err(PlanFailure::bad_request(format!(
                "no_fly: planner {} does not honour no-fly zones (the grid planners and the 3D planners do); use one of {}",
                r.planner,
                PlannerId::for_maps(false)
                    .map(|p| p.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        let zones = self.projected_zones(r)?;
        if info.dims == 3 {
            // The 3D planners' altitudes are above home, as the zones' bands: each zone is a
            // prism in their world (over terrain too).
            if let Some(z) = zones.iter().find(|z| z.inclusion) {
                return Err(PlanFailure::bad_request(format!(
                    "no_fly: feature {} is an inclusion boundary (stay inside); the 3D planners keep out of exclusion zones only; a 2D grid planner keeps inside it",
                    z.feature
                )));
            }
            return Ok(zones);
        }
        match self.world.terrain() {
            None => Ok(zones),
            Some(t) => zones_over_terrain(t, zones, r.alt_m, r.safety_m),
        }
    }

    /// The request's zones placed about the map's home, as the file gives their bands (AMSL
    /// bands with the DEM's height at home over terrain).
    fn projected_zones(&self, r: &Resolved) -> Result<Vec<skyplan_map::nofly::Zone>, PlanFailure> {
        let Some(geo) = &r.no_fly else {
            return Ok(Vec::new());
        };
        let name = self.world.name();
        let home = self.world.frame().map(|f| f.home()).ok_or_else(|| {
            PlanFailure::bad_request(format!(
                "no_fly: {name} has no geodetic home to place the zones at"
            ))
        })?;
        let terrain = self.world.terrain();
        geo.project(
            skyplan_map::colliders::GeodeticHome {
                lat_deg: home.lat_deg,
                lon_deg: home.lon_deg,
            },
            terrain.map(|t| t.home_ground_amsl_m()),
        )
        .map_err(|e| PlanFailure::bad_request(format!("no_fly: {e}")))
    }

    /// The trajectory of a plan's waypoints, in the free space the plan was checked in: the 3D
    /// boxes grown by the margin on colliders maps, the grid used (at the flight altitude)
    /// on the others.
    fn trajectory(
        &mut self,
        r: &Resolved,
        plan: &Plan,
        spec: TrajectorySpec,
    ) -> Result<TrajectoryReport, PlanFailure> {
        use skyplan_trajectory as tj;
        let route = plan.points_nea();
        let free = self.free_space(r, plan)?;
        let traj = tj::plan(&route, free.as_ref(), &spec.limits, &tj::Options::default()).map_err(
            |e| match e {
                tj::TrajectoryError::Corridor { .. } => {
                    PlanFailure::new(FailureKind::NoCorridor, format!("trajectory: {e}"))
                }
                tj::TrajectoryError::Limit { .. } => PlanFailure::bad_request(e.to_string()),
                // Start and goal in the same place: nothing to fly, the request's to change.
                tj::TrajectoryError::Route(_) => {
                    PlanFailure::bad_request(format!("trajectory: {e}"))
                }
                _ => PlanFailure::internal(format!("trajectory: {e}")),
            },
        )?;
        let samples = traj.samples(spec.sample_hz);
        if let Some(t) = self.world.terrain() {
            // The corridor's boxes stand on the ground's columns; the samples (centimetres
            // off the curve at 10 Hz) are checked against the ground itself.
            let path: Vec<[f64; 3]> = samples.iter().map(|s| [s[1], s[2], s[3]]).collect();
            t.check_clearance(&path, r.alt_m - 0.05).map_err(|e| {
                PlanFailure::internal(format!(
                    "internal check failed: trajectory: {e}; please report this with the request"
                ))
            })?;
        }
        let stop = tj::stop_at_waypoints(&route, &spec.limits)
            .map_err(|e| PlanFailure::internal(format!("trajectory: {e}")))?;
        let length: f64 = skyplan_world3::path_length_m(&route);
        Ok(TrajectoryReport {
            duration_s: traj.duration_s(),
            sample_hz: spec.sample_hz,
            columns: TRAJECTORY_COLUMNS,
            samples,
            length_m: traj.length_m(),
            stop_at_waypoints_s: stop.duration_s(),
            length_over_max_speed_s: length / spec.limits.max_speed_m_s,
            trajectory: traj,
        })
    }

    /// The grid a 2D flight of `request` keeps to at `alt_m` (the replanner's layers): the
    /// map's grid at that altitude with the request's margin and cell size, less every no-fly
    /// zone of the request that applies there — whatever its time window, but for those that
    /// end before the request's departure, since a flight replanned in the air has no arrival
    /// known in advance.
    ///
    /// ```
    /// use skyplan_plan::{PlanRequest, Session, World};
    /// let zones = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/no-fly-sample.geojson"))?;
    /// let request = PlanRequest { no_fly: Some(zones), ..Default::default() };
    /// let mut session = Session::new(World::fcnd_city());
    /// let plain = session.grid(5.0, 5.0, 1.0)?;
    /// let zoned = session.zoned_grid(&request, 5.0)?;
    /// // The stadium's disc and the helipad are blocked too; the approach path (60 m up) is not.
    /// assert!(zoned.blocked_count() > plain.blocked_count() + 3000);
    /// // 60 m up, in the approach path's band: more still.
    /// let high = session.zoned_grid(&request, 60.0)?;
    /// assert!(high.blocked_count() > session.grid(60.0, 5.0, 1.0)?.blocked_count() + 3000);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn zoned_grid(
        &mut self,
        request: &PlanRequest,
        alt_m: f64,
    ) -> Result<Arc<Grid2>, PlanFailure> {
        let r = Resolved::new(request)?;
        let grid = self.grid(alt_m, r.safety_m, r.cell_m)?;
        if r.no_fly.is_none() {
            return Ok(grid);
        }
        let mut zones = self.zones(&r)?;
        if let Some(departure) = r.departure_unix_s {
            zones.retain(|z| meets_window(z, departure, i64::MAX));
        }
        let spec = GridSpec {
            alt_m,
            safety_m: r.safety_m,
            cell_m: r.cell_m,
        };
        crate::grid::with_zones(grid, &zones, spec)
    }

    /// The request's no-fly zones in the map's frame (bands above home), all of them whatever
    /// their bands and times; empty without `no_fly`. Refused as a plan would refuse them (a
    /// map without a home or an altitude, a planner that does not honour zones).
    pub fn zones_for(&self, request: &PlanRequest) -> Result<Vec<Zone>, PlanFailure> {
        self.zones(&Resolved::new(request)?)
    }

    /// The free space a plan's trajectory is made in: a 3D planner's world (boxes or footprint
    /// prisms and no-fly zones, grown by the margin), the 3D boxes of a colliders map for a 2D
    /// route without zones, else the plan's grid at its altitude — what a trajectory replanned
    /// in flight must keep to as well.
    pub fn trajectory_space(
        &mut self,
        request: &PlanRequest,
        plan: &Plan,
    ) -> Result<Arc<dyn skyplan_trajectory::FreeSpace + Send + Sync>, PlanFailure> {
        let r = Resolved::new(request)?;
        self.free_space(&r, plan)
    }

    fn free_space(
        &mut self,
        r: &Resolved,
        plan: &Plan,
    ) -> Result<Arc<dyn skyplan_trajectory::FreeSpace + Send + Sync>, PlanFailure> {
        let three_d = r.planner.info().dims == 3;
        if three_d {
            // The 3D world the route was planned in: boxes or footprints, and the zones.
            let zones = self.zones(r)?;
            Ok(self.boxes(r, &zones)?)
        } else if self.world.colliders().is_some() && r.no_fly.is_none() {
            Ok(self.boxes(r, &[])?)
        } else if let Some(grid) = &plan.grid_used {
            Ok(Arc::new(skyplan_trajectory::GridLayer::new(
                grid.as_ref().clone(),
                r.alt_m,
            )))
        } else {
            Err(PlanFailure::bad_request(format!(
                "trajectory: planner {} gives no grid on {} to build a corridor in",
                r.planner,
                self.world.name()
            )))
        }
    }

    /// Plans `request` again from another start (where the vehicle is now), reusing the caches.
    pub fn replan_from(
        &mut self,
        request: &PlanRequest,
        north_m: f64,
        east_m: f64,
    ) -> Result<Plan, PlanFailure> {
        self.plan(&request.from_start_ne(north_m, east_m))
    }

    /// A position in local metres (and the lat/lon it was given as).
    fn endpoint(
        &self,
        given: Option<Position>,
        default: Option<[f64; 2]>,
        which: &str,
    ) -> Result<([f64; 2], Option<[f64; 2]>), PlanFailure> {
        let kind = if which == "start" {
            FailureKind::InvalidStart
        } else {
            FailureKind::InvalidGoal
        };
        match given {
            Some(Position::Ne(n, e)) => Ok(([n, e], None)),
            Some(Position::Lla(lat_deg, lon_deg)) => {
                let Some(frame) = self.world.frame() else {
                    return Err(PlanFailure::bad_request(format!(
                        "{which}_lla: {} has no geodetic home; give {which}_ne (metres north,east of the map's origin) or a home",
                        self.world.name()
                    )));
                };
                let ned = frame
                    .ned_from_lla(Lla { lat_deg, lon_deg, alt_m: 0.0 })
                    .map_err(|e| PlanFailure::new(kind, format!("{which}: {e}")))?;
                Ok(([ned.north_m, ned.east_m], Some([lat_deg, lon_deg])))
            }
            None => default.map(|ne| (ne, None)).ok_or_else(|| {
                PlanFailure::bad_request(format!(
                    "missing {which}: give {which}_ne N,E (metres north,east of the map's origin; {})",
                    self.world.bounds_ne(1.0)
                ))
            }),
        }
    }
}

/// A route's end as a [`Place`]: its lat/lon as given, else from the map's frame (if any).
fn place_of(
    world: &World,
    p: [f64; 3],
    cell: Option<Cell>,
    given: Option<[f64; 2]>,
) -> Result<Place, PlanFailure> {
    let lla = match (given, world.frame()) {
        (Some(ll), _) => Some(ll),
        (None, Some(frame)) => {
            let l = frame
                .lla_from_ned(Ned {
                    north_m: p[0],
                    east_m: p[1],
                    down_m: -p[2],
                })
                .map_err(|e| PlanFailure::bad_request(format!("waypoints: {e}")))?;
            Some([l.lat_deg, l.lon_deg])
        }
        (None, None) => None,
    };
    Ok(Place {
        north_m: p[0],
        east_m: p[1],
        alt_m: p[2],
        lat_deg: lla.map(|l| l[0]),
        lon_deg: lla.map(|l| l[1]),
        cell: cell.map(|c| [c.row, c.col]),
    })
}

/// The mission of a route's points (maps with a geodetic home), its rows
/// `[north, east, alt, heading]` and their lat/lon.
type MissionRows = (Option<Mission>, Vec<[f64; 4]>, Option<Vec<Vec<f64>>>);

fn mission_rows(
    world: &World,
    points: &[[f64; 3]],
    start_heading_rad: f64,
) -> Result<MissionRows, PlanFailure> {
    Ok(match world.frame() {
        Some(frame) => {
            let m = Mission::from_points_nea(frame, points, start_heading_rad)
                .map_err(|e| PlanFailure::bad_request(format!("waypoints: {e}")))?;
            let rows = m.rows();
            let lla = m
                .waypoints
                .iter()
                .map(|w| vec![w.lat_deg, w.lon_deg])
                .collect();
            (Some(m), rows, Some(lla))
        }
        None => (None, rows_without_frame(points, start_heading_rad), None),
    })
}

/// The plan from a re-checked route: places with lat/lon, the mission, statistics.
fn assemble(
    world: &World,
    r: &Resolved,
    mut route: Route,
    [start_lla, goal_lla]: [Option<[f64; 2]>; 2],
    t0: Instant,
) -> Result<Plan, PlanFailure> {
    let info = r.planner.info();
    let (Some(&first), Some(&last)) = (route.points.first(), route.points.last()) else {
        return Err(PlanFailure::internal("empty route"));
    };
    let start = place_of(world, first, route.start_cell, start_lla)?;
    let goal = place_of(world, last, route.goal_cell, goal_lla)?;
    let (mission, waypoints, waypoints_lla) =
        mission_rows(world, &route.points, r.start_heading_rad)?;
    let mission_length_m = route
        .points
        .windows(2)
        .map(|w| skyplan_world3::distance_m(w[0], w[1]))
        .sum();
    let straight_line_m = skyplan_world3::distance_m(first, last);
    let grid_info = route
        .grid
        .as_ref()
        .filter(|_| info.dims == 2)
        .map(|g| GridInfo::of(g, r.alt_m, r.safety_m));
    let grid_planner = r.planner.is_cell_planner();
    let mut grid_path = route.grid_path;
    if let Some(g) = grid_path.as_mut() {
        g.waypoint_counts.mission = waypoints.len();
    }
    if r.geometry && info.dims == 2 {
        if let Some(map) = world.colliders() {
            route.geometry.active_boxes = map
                .boxes
                .iter()
                .filter(|b| b.meets_altitude(r.alt_m, r.safety_m))
                .copied()
                .collect();
        }
        if let Some(map) = world.footprints() {
            route.geometry.active_footprints = map
                .footprints
                .iter()
                .filter(|f| f.meets_altitude(r.alt_m, r.safety_m))
                .cloned()
                .collect();
        }
    }
    let notes = world.notes();
    if !notes.is_empty() {
        route
            .details
            .insert("map_notes".into(), serde_json::Value::from(notes));
    }
    Ok(Plan {
        status: "ok",
        map: world.name().to_string(),
        obstacles: world.obstacle_count(),
        home: world.frame().map(|f| Home {
            lat_deg: f.home().lat_deg,
            lon_deg: f.home().lon_deg,
        }),
        planner: r.planner,
        spec: r.spec(),
        grid: grid_info,
        move_model: grid_planner.then(|| model_name(r.model)),
        start,
        goal,
        cost_m: route.cost_m,
        mission_length_m,
        straight_line_m,
        octile_optimum_m: route.octile_optimum_m,
        expansions: route.expansions,
        grid_path,
        search_time_us: route.timings.search_us,
        timings_us: Timings {
            total_us: micros(t0.elapsed()),
            ..route.timings
        },
        waypoints,
        waypoints_lla,
        details: std::mem::take(&mut route.details),
        geometry: r.geometry.then(|| std::mem::take(&mut route.geometry)),
        trajectory: None,
        mission,
        grid_used: route.grid.take(),
        saved_roadmap: route.saved_roadmap.take(),
    })
}

/// Headings as FCND computes them, for maps without a geodetic home.
fn rows_without_frame(points: &[[f64; 3]], start_heading_rad: f64) -> Vec<[f64; 4]> {
    let mut heading = start_heading_rad;
    points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            if k > 0 {
                let q = points[k - 1];
                if (q[0], q[1]) != (p[0], p[1]) {
                    heading = skyplan_mission::heading_rad((q[0], q[1]), (p[0], p[1]));
                }
            }
            [p[0], p[1], p[2], heading]
        })
        .collect()
}

/// The move model as users read it.
pub fn model_name(model: MoveModel) -> &'static str {
    match model {
        MoveModel::FourConnected => "4-connected",
        MoveModel::Octile => "8-connected, no corner cutting",
        MoveModel::OctileCornerCutting => "8-connected, corner cutting",
    }
}

/// The session's final re-check of a 2D grid route, for routes made outside a session (replanning
/// in flight): every segment of `points` (north, east, alt) against `grid` under `touch`.
///
/// ```
/// use skyplan_cspace::{Grid2, Touch};
/// let grid = Grid2::from_ascii("...\n.#.\n...")?;
/// assert!(skyplan_plan::recheck_grid_route(&grid, &[[0.5, 0.5, 5.0], [0.5, 2.5, 5.0]], Touch::Closed).is_ok());
/// assert!(skyplan_plan::recheck_grid_route(&grid, &[[0.5, 0.5, 5.0], [2.5, 2.5, 5.0]], Touch::Closed).is_err());
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn recheck_grid_route(
    grid: &Grid2,
    points: &[[f64; 3]],
    touch: Touch,
) -> Result<(), PlanFailure> {
    verdict(points, first_blocked_grid_segment(grid, points, touch))
}

/// The first segment of `p` that `grid` blocks under `touch`.
fn first_blocked_grid_segment(grid: &Grid2, p: &[[f64; 3]], touch: Touch) -> Option<usize> {
    p.windows(2)
        .position(|w| !grid.segment_is_free_ne((w[0][0], w[0][1]), (w[1][0], w[1][1]), touch))
}

/// How wide the columns of ground the 3D planners see are, about, metres (DEM cells split to
/// this; the columns are as high as the ground gets in them, so narrower hugs the ground closer).
const COLUMN_M: f64 = 10.0;

/// The obstacles of a 3D plan over terrain: the map's boxes standing on the ground (each
/// reaches from its floor above the lowest ground under it to its top above the highest,
/// both found exactly), and
/// the ground itself as columns ([`skyplan_map::terrain::Terrain::columns`]) over the map's
/// bounds, each topped so that, grown by the margin like every box, it keeps the route
/// `alt_agl_m` above the cell's highest sample.
fn boxes_over_terrain(
    t: &skyplan_map::terrain::Terrain,
    boxes: &[skyplan_map::colliders::ObstacleBox],
    r: &Resolved,
    b: &crate::world::BoundsNe,
) -> Result<Vec<skyplan_map::colliders::ObstacleBox>, PlanFailure> {
    use skyplan_map::colliders::ObstacleBox;
    let mut out = standing_boxes(t, boxes)?;
    let columns = t
        .columns(
            [b.north_min_m, b.north_max_m],
            [b.east_min_m, b.east_max_m],
            COLUMN_M,
        )
        .map_err(|e| PlanFailure::bad_request(format!("terrain: {e}")))?;
    let bottom = r.min_alt_m - r.safety_m - 1.0;
    for c in columns {
        let top = c.top_m + r.alt_m - r.safety_m;
        if top <= bottom {
            continue;
        }
        out.push(ObstacleBox {
            north_m: (c.north_m[0] + c.north_m[1]) / 2.0,
            east_m: (c.east_m[0] + c.east_m[1]) / 2.0,
            up_m: (bottom + top) / 2.0,
            half_north_m: (c.north_m[1] - c.north_m[0]) / 2.0,
            half_east_m: (c.east_m[1] - c.east_m[0]) / 2.0,
            half_up_m: (top - bottom) / 2.0,
        });
    }
    Ok(out)
}

/// Boxes standing on the ground: each reaches from its floor above the lowest ground under it
/// to its top above the highest.
fn standing_boxes(
    t: &skyplan_map::terrain::Terrain,
    boxes: &[skyplan_map::colliders::ObstacleBox],
) -> Result<Vec<skyplan_map::colliders::ObstacleBox>, PlanFailure> {
    (boxes.iter().enumerate())
        .map(|(k, o)| {
            let north = [o.north_m - o.half_north_m, o.north_m + o.half_north_m];
            let east = [o.east_m - o.half_east_m, o.east_m + o.half_east_m];
            let [lo, hi] = t.ground_extremes_m_in(north, east).map_err(|e| {
                PlanFailure::bad_request(format!(
                    "terrain: under obstacle {} (N {:.1} m, E {:.1} m): {e}",
                    k + 1,
                    o.north_m,
                    o.east_m
                ))
            })?;
            let (floor, top) = (o.up_m - o.half_up_m + lo, o.up_m + o.half_up_m + hi);
            Ok(skyplan_map::colliders::ObstacleBox {
                up_m: (floor + top) / 2.0,
                half_up_m: (top - floor) / 2.0,
                ..*o
            })
        })
        .collect()
}

impl World {
    /// The map's boxes and building footprints as they stand: over terrain each is raised by
    /// the ground under it, from its floor above the lowest ground under it to its top above
    /// the highest (as the planners see them); without terrain, as loaded. Errors name the
    /// obstacle the DEM does not cover.
    ///
    /// ```
    /// use skyplan_plan::World;
    /// let world = World::from_colliders_csv("colliders.csv", "lat0 37.79, lon0 -122.39\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n10,0,5,2,2,5\n")?;
    /// let (boxes, footprints) = world.standing_obstacles()?;
    /// assert_eq!((boxes.len(), footprints.len()), (1, 0));
    /// assert_eq!(boxes[0].up_m + boxes[0].half_up_m, 10.0);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn standing_obstacles(
        &self,
    ) -> Result<
        (
            Vec<skyplan_map::colliders::ObstacleBox>,
            Vec<skyplan_map::footprints::Footprint>,
        ),
        PlanFailure,
    > {
        let boxes = self.colliders().map_or(&[][..], |m| &m.boxes[..]);
        let footprints = self.footprints().map_or(&[][..], |m| &m.footprints[..]);
        match self.terrain() {
            Some(t) => Ok((
                standing_boxes(t, boxes)?,
                footprints_over_terrain(t, footprints)?,
            )),
            None => Ok((boxes.to_vec(), footprints.to_vec())),
        }
    }
}

/// The footprints of a 3D plan over terrain, standing on the ground: each reaches from its
/// floor above the lowest ground under its bounding box to its top above the highest.
fn footprints_over_terrain(
    t: &skyplan_map::terrain::Terrain,
    footprints: &[skyplan_map::footprints::Footprint],
) -> Result<Vec<skyplan_map::footprints::Footprint>, PlanFailure> {
    (footprints.iter())
        .map(|f| {
            let (lo, hi) = f.bbox_ne();
            let [low, high] = t
                .ground_extremes_m_in([lo[0], hi[0]], [lo[1], hi[1]])
                .map_err(|e| {
                    PlanFailure::bad_request(format!(
                        "terrain: under the footprint of feature {} (N {:.1} m, E {:.1} m): {e}",
                        f.feature + 1,
                        (lo[0] + hi[0]) / 2.0,
                        (lo[1] + hi[1]) / 2.0
                    ))
                })?;
            Ok(skyplan_map::footprints::Footprint {
                min_height_m: f.min_height_m + low,
                height_m: f.height_m + high,
                ..f.clone()
            })
        })
        .collect()
}

/// A 3D request over terrain: the flight volume from the lowest ground under the map to
/// `alt_agl_m` + 20 m over the highest (where not given), and start and goal `alt_agl_m`
/// above the highest ground column within the margin of them (the lowest the planners can
/// start: the columns are no lower than the ground, and as high as a DEM cell's highest
/// sample).
fn terrain_volume(
    t: &skyplan_map::terrain::Terrain,
    r: &mut Resolved,
    request: &PlanRequest,
    b: &crate::world::BoundsNe,
    [start_ne, goal_ne]: [[f64; 2]; 2],
) -> Result<(), PlanFailure> {
    if let Some(which) = [
        ("start_alt_m", request.start_alt_m.is_some()),
        ("goal_alt_m", request.goal_alt_m.is_some()),
    ]
    .iter()
    .find_map(|(name, given)| given.then_some(name))
    {
        return Err(PlanFailure::bad_request(format!(
            "{which}: over terrain the ends are alt_agl_m above the ground; leave {which} out"
        )));
    }
    let [low, high] = t
        .ground_range_m_in([b.north_min_m, b.north_max_m], [b.east_min_m, b.east_max_m])
        .ok_or_else(|| PlanFailure::bad_request("terrain: the DEM has no ground under the map"))?;
    let h = r.alt_m;
    if request.min_alt_m.is_none() {
        r.min_alt_m = low;
    }
    if request.max_alt_m.is_none() {
        r.max_alt_m = high + h + 20.0;
    }
    let reach = r.safety_m;
    for (end, ne, which) in [
        (&mut r.start, start_ne, "start"),
        (&mut r.goal, goal_ne, "goal"),
    ] {
        let top = t
            .columns(
                [ne[0] - reach, ne[0] + reach],
                [ne[1] - reach, ne[1] + reach],
                COLUMN_M,
            )
            .map_err(|e| PlanFailure::bad_request(format!("terrain: at the {which}: {e}")))?
            .iter()
            .map(|c| c.top_m)
            .fold(f64::NEG_INFINITY, f64::max);
        end.alt_m = top + h + 0.05;
    }
    if r.min_alt_m >= r.max_alt_m {
        return Err(PlanFailure::bad_request(format!(
            "min_alt_m {} and max_alt_m {}: the floor of the flight volume must be below its ceiling",
            r.min_alt_m, r.max_alt_m
        )));
    }
    Ok(())
}

/// No-fly zones for a route that keeps `agl_m` above the ground: the route over a zone is never
/// lower than the lowest ground under it plus `agl_m`, so a zone whose ceiling (grown by the
/// margin) is below that is left out; every other zone blocks at every altitude (the route's
/// height over it is only known after planning: the safe side). Inclusion boundaries hold
/// the route inside them at every altitude; their bands are checked once the route is lifted.
fn zones_over_terrain(
    terrain: &skyplan_map::terrain::Terrain,
    zones: Vec<skyplan_map::nofly::Zone>,
    agl_m: f64,
    margin_m: f64,
) -> Result<Vec<skyplan_map::nofly::Zone>, PlanFailure> {
    use skyplan_map::nofly::ZoneShape;
    let mut out = Vec::with_capacity(zones.len());
    for mut z in zones {
        if z.inclusion {
            // Stay inside at every altitude; the band is checked on the lifted route
            // (`check_inclusion_bands`).
            (z.floor_m, z.ceiling_m) = (f64::NEG_INFINITY, f64::INFINITY);
            out.push(z);
            continue;
        }
        let (north, east) = match &z.shape {
            ZoneShape::Circle { centre, radius_m } => {
                let r = radius_m + margin_m;
                (
                    [centre[0] - r, centre[0] + r],
                    [centre[1] - r, centre[1] + r],
                )
            }
            ZoneShape::Polygon(rings) => {
                let pts = rings.iter().flatten();
                let f = |i: usize, min: bool| {
                    pts.clone().map(|p| p[i]).fold(
                        if min {
                            f64::INFINITY
                        } else {
                            f64::NEG_INFINITY
                        },
                        |a, b| if min { a.min(b) } else { a.max(b) },
                    )
                };
                (
                    [f(0, true) - margin_m, f(0, false) + margin_m],
                    [f(1, true) - margin_m, f(1, false) + margin_m],
                )
            }
        };
        let lowest_route_m = terrain
            .min_ground_m_in(north, east)
            .map_or(f64::NEG_INFINITY, |g| g + agl_m);
        if z.ceiling_m + margin_m <= lowest_route_m {
            continue; // under the route wherever the route can be
        }
        (z.floor_m, z.ceiling_m) = (f64::NEG_INFINITY, f64::INFINITY);
        out.push(z);
    }
    Ok(out)
}

/// Over terrain, whether the lifted route stays within the band of every inclusion boundary
/// (shrunk by the margin): the route is straight between its points, so its highest and lowest
/// are at points. A route that must climb above the ceiling (or stay under the floor) to keep
/// its height above the ground is no path, naming the boundary and where.
fn check_inclusion_bands(
    zones: &[skyplan_map::nofly::Zone],
    route: &[[f64; 3]],
    margin_m: f64,
) -> Result<(), PlanFailure> {
    for z in zones.iter().filter(|z| z.inclusion) {
        let (low, high) = (z.floor_m + margin_m, z.ceiling_m - margin_m);
        if let Some(p) = route
            .iter()
            .find(|p| p[2] > high + 1e-6 || p[2] < low - 1e-6)
        {
            return Err(PlanFailure::new(
                FailureKind::NoPath,
                format!(
                    "no_fly: feature {}: the inclusion boundary's band less the {margin_m} m margin is {low:.1} to {high:.1} m above home, and keeping the height above the ground takes the route to {:.1} m at N {:.1} m, E {:.1} m; lower alt_agl_m or widen the band",
                    z.feature, p[2], p[0], p[1]
                ),
            ));
        }
    }
    Ok(())
}

/// Whether a request can be planned over terrain (before planning it).
fn check_terrain_request(r: &Resolved) -> Result<(), PlanFailure> {
    if r.trajectory.is_some() && r.planner.info().dims == 2 {
        return Err(PlanFailure::bad_request(format!(
            "trajectory: over terrain only with a 3D planner ({}), whose corridor stands on the ground's columns; planner {} lifts its route after planning",
            PlannerId::for_maps(true)
                .filter(|p| p.info().dims == 3)
                .map(|p| p.name())
                .collect::<Vec<_>>()
                .join(", "),
            r.planner
        )));
    }
    let slopes = r.terrain_slopes;
    if !slopes.iter().all(|s| s.is_finite() && *s > 0.0) {
        return Err(PlanFailure::bad_request(format!(
            "max_climb_m_s, max_descent_m_s, max_speed_m_s: over terrain the climb and descent rates over the speed must be positive (they are {:.3} and {:.3})",
            slopes[0], slopes[1]
        )));
    }
    Ok(())
}

/// Lifts a 2D route over the terrain (`lift`): `alt_m` above the ground everywhere along it,
/// within the climb and descent slopes; re-checks the route (a 3D planner's as it is) against
/// the ground exactly and says what it did in the plan's `terrain` detail.
fn follow_terrain(
    terrain: &skyplan_map::terrain::Terrain,
    r: &Resolved,
    route: &mut Route,
    lift: bool,
) -> Result<(), PlanFailure> {
    let slopes = r.terrain_slopes;
    let agl_m = r.alt_m;
    let lifted = if lift {
        let ne: Vec<[f64; 2]> = route.points.iter().map(|p| [p[0], p[1]]).collect();
        terrain
            .follow(&ne, agl_m, slopes)
            .map_err(|e| PlanFailure::bad_request(format!("terrain: {e}")))?
    } else {
        route.points.clone()
    };
    terrain.check_clearance(&lifted, agl_m).map_err(|e| {
        PlanFailure::internal(format!(
            "internal check failed: {e}; please report this with the request"
        ))
    })?;
    let highest = lifted
        .iter()
        .map(|p| p[2])
        .fold(f64::NEG_INFINITY, f64::max);
    let lowest = lifted.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    let climb: f64 = lifted
        .windows(2)
        .map(|w| (w[1][2] - w[0][2]).max(0.0))
        .sum();
    let (n, e) = terrain.dem().size();
    route.details.insert(
        "terrain".into(),
        serde_json::json!({
            "alt_agl_m": agl_m,
            "home_ground_amsl_m": terrain.home_ground_amsl_m(),
            "lowest_alt_m": lowest,
            "highest_alt_m": highest,
            "climb_m": climb,
            "max_climb_slope": slopes[0],
            "max_descent_slope": slopes[1],
            "dem_samples": [n, e],
        }),
    );
    route.points = lifted;
    Ok(())
}

/// The final, independent re-check of every segment: no caller can skip it.
fn recheck(route: &Route) -> Result<(), PlanFailure> {
    let p = &route.points;
    let bad = match &route.check {
        Check::Grid { grid, touch } => first_blocked_grid_segment(grid, p, *touch),
        Check::Boxes(world) => skyplan_world3::first_blocked_segment(&world.brute_force(), p),
        Check::AnyAngle(grid) => {
            let at = |q: [f64; 3]| skyplan_anyangle::GridPoint::from_ne(grid.frame(), q[0], q[1]);
            p.windows(2).position(|w| {
                !skyplan_anyangle::segment_is_free_any_angle(grid, at(w[0]), at(w[1]))
            })
        }
    };
    verdict(p, bad)
}

/// The re-check's answer for route `p` whose segment `bad` (if any) is blocked.
fn verdict(p: &[[f64; 3]], bad: Option<usize>) -> Result<(), PlanFailure> {
    if p.is_empty() {
        return Err(PlanFailure::internal(
            "internal check failed: the route is empty; please report this with the request",
        ));
    }
    match bad {
        None => Ok(()),
        Some(k) => Err(PlanFailure::internal(format!(
            "internal check failed: segment {k} of the route (N {:.2}, E {:.2}, {:.2} m → N {:.2}, E {:.2}, {:.2} m) meets an obstacle; please report this with the request",
            p[k][0],
            p[k][1],
            p[k][2],
            p[k + 1][0],
            p[k + 1][1],
            p[k + 1][2]
        ))),
    }
}

#[cfg(test)]
mod kept_tests {
    use super::Kept;

    #[test]
    fn kept_builds_what_is_missing_and_holds_the_most_recent_few() {
        let mut kept: Kept<u32> = Kept::at_most(2);
        // Two at most, the oldest kept dropped first: 1 goes when 3 comes, then 2 when 1 does.
        let mut built = Vec::new();
        for k in [1, 2, 1, 3, 1, 2] {
            let (got, us) = kept.get_or_build(|&x| x == k, || Ok::<_, ()>(k)).unwrap();
            assert_eq!(*got, k);
            built.push(us.is_some());
        }
        assert_eq!(built, [true, true, false, true, true, true]);
        assert!(kept.any(|&x| x == 1) && kept.any(|&x| x == 2) && !kept.any(|&x| x == 3));
    }
}
