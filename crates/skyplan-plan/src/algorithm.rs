//! [`Algorithm`]: what each registry row runs (OMPL's `Planner`, Nav2's planner plugin): its
//! memory estimate, its plan through the session's caches, and — for the cell-to-cell grid
//! searches — a [`CellPlanner`] the grid pipeline (search, prune, shortcut) and [`CellSearch`]
//! (replays, benchmarks) drive.
//!
//! [`CellSearch`]: crate::CellSearch

use crate::auto::AutoPick;
use crate::failure::PlanFailure;
use crate::planner_id::PlannerId;
use crate::request::Resolved;
use crate::session::{Query, Route, Session};
use crate::world::World;
use skyplan_cspace::{Cell, Grid2};
use skyplan_sampling::PlannerKind;
use skyplan_search::{
    ChQuery, ContractionHierarchy, FirstMoveTable, GridPath, GridSearch, JpsPlusTable, MoveModel,
    Planner, SearchError, SubgoalGraph, SubgoalQuery,
};
use std::sync::Arc;

/// The memory a request needs, estimated before anything is allocated.
pub(crate) struct Memory {
    /// How many units (cells, voxels).
    pub units: u64,
    /// Bytes per unit.
    pub bytes_per_unit: u64,
    /// What a unit is, for the message.
    pub what: &'static str,
    /// What the user can change to need less.
    pub change: &'static str,
}

impl Memory {
    /// `bytes_per_cell` for every cell of the request's grid.
    fn cells(world: &World, r: &Resolved, bytes_per_cell: u64) -> Option<Memory> {
        Some(Memory {
            units: world.cells_at(r.cell_m),
            bytes_per_unit: bytes_per_cell,
            what: "cells",
            change: "use a larger cell_m",
        })
    }
}

/// One planner behind the registry.
pub(crate) trait Algorithm: Sync {
    /// The memory a request needs (`None`: nothing that grows with the map).
    fn memory(&self, world: &World, r: &Resolved) -> Option<Memory>;

    /// The route for a resolved query, through the session's caches.
    fn plan(&self, session: &mut Session, q: &Query) -> Result<Route, PlanFailure>;

    /// The cell-to-cell search, for the planners that are one.
    fn cells(&self) -> Option<&dyn CellPlanner> {
        None
    }

    /// Whether its route comes with a navigation field (a value per cell).
    fn has_field(&self) -> bool {
        false
    }

    /// What its expansion count counts (`expansions`; the sampling planners count samples).
    fn work_unit(&self) -> &'static str {
        "expansions"
    }
}

/// A plain cell-to-cell search function (no preprocessing, no kept state).
pub(crate) type SearchFn = fn(&Grid2, Cell, Cell, MoveModel) -> Result<GridPath, SearchError>;

/// A cell-to-cell search prepared on one grid.
pub(crate) enum Engine {
    /// A [`GridSearch`] algorithm.
    Online(Planner),
    /// JPS+ over its table.
    Plus(Arc<JpsPlusTable>),
    /// Queries of a contraction hierarchy.
    Hierarchy(Arc<ContractionHierarchy>),
    /// Queries of a subgoal graph.
    Subgoal(Arc<SubgoalGraph>),
    /// Lookups in a first-move table.
    FirstMove(Arc<FirstMoveTable>),
    /// A plain function.
    Function(SearchFn),
}

/// The buffers the engines reuse between queries.
#[derive(Default)]
pub(crate) struct Workspace {
    pub search: GridSearch,
    pub ch: ChQuery,
    pub subgoal: SubgoalQuery,
}

impl Engine {
    /// One query.
    pub(crate) fn search(
        &self,
        ws: &mut Workspace,
        grid: &Grid2,
        (start, goal): (Cell, Cell),
        model: MoveModel,
    ) -> Result<GridPath, SearchError> {
        match self {
            Engine::Online(planner) => ws.search.search(grid, start, goal, model, *planner),
            Engine::Plus(table) => table.search(&mut ws.search, start, goal),
            Engine::Hierarchy(ch) => ch.search(&mut ws.ch, start, goal),
            Engine::Subgoal(graph) => graph.search(&mut ws.subgoal, start, goal),
            Engine::FirstMove(table) => table.search(start, goal),
            Engine::Function(f) => f(grid, start, goal, model),
        }
    }
}

/// An engine and its preparation: `Some(µs)` if it was built now, `None` if kept or not
/// needed; `detail` names the kept thing for the plan's details (`jps_plus_table`).
pub(crate) struct Prepared {
    pub engine: Engine,
    pub built_us: Option<u64>,
    pub detail: Option<&'static str>,
    /// What `auto` picked and why (for the plan's details).
    pub auto: Option<AutoPick>,
}

impl Prepared {
    /// An engine over preprocessing the session keeps: `built_us` if built now, `detail` its
    /// name in the plan's details.
    fn kept(engine: Engine, built_us: Option<u64>, detail: &'static str) -> Self {
        Prepared {
            engine,
            built_us,
            detail: Some(detail),
            auto: None,
        }
    }

    fn plain(engine: Engine) -> Self {
        Prepared {
            engine,
            built_us: None,
            detail: None,
            auto: None,
        }
    }
}

/// A cell-to-cell grid search; every one is also an [`Algorithm`] (the grid pipeline).
pub(crate) trait CellPlanner: Sync {
    /// Bytes per grid cell: its tables and search state.
    fn bytes_per_cell(&self) -> u64 {
        24
    }

    /// Prepared on a session's grid: kept preprocessing is reused, new preprocessing is kept
    /// (by default there is none to keep: prepared as [`CellPlanner::prepare_alone`]).
    fn prepare(
        &self,
        _session: &mut Session,
        grid: &Arc<Grid2>,
        r: &Resolved,
    ) -> Result<Prepared, PlanFailure> {
        self.prepare_alone(grid, r.model).map(Prepared::plain)
    }

    /// Prepared on its own (many queries on one grid, outside a session).
    fn prepare_alone(&self, grid: &Grid2, model: MoveModel) -> Result<Engine, PlanFailure>;

    /// Whether its paths turn anywhere (Theta\*): then the plan also reports the octile optimum.
    fn any_angle(&self) -> bool {
        false
    }
}

impl<T: CellPlanner> Algorithm for T {
    fn memory(&self, world: &World, r: &Resolved) -> Option<Memory> {
        Memory::cells(world, r, self.bytes_per_cell())
    }

    fn plan(&self, session: &mut Session, q: &Query) -> Result<Route, PlanFailure> {
        crate::grid::plan(session, q, self)
    }

    fn cells(&self) -> Option<&dyn CellPlanner> {
        Some(self)
    }
}

/// A [`GridSearch`] algorithm (A\*, Dijkstra, JPS, Theta\*): its buffers are the session's.
pub(crate) struct OnlineCells(pub Planner);

impl CellPlanner for OnlineCells {
    fn prepare_alone(&self, _: &Grid2, _: MoveModel) -> Result<Engine, PlanFailure> {
        Ok(Engine::Online(self.0))
    }

    fn any_angle(&self) -> bool {
        self.0 == Planner::ThetaStar
    }
}

/// A plain search function (bidirectional A\*).
pub(crate) struct CellFunction(pub SearchFn);

impl CellPlanner for CellFunction {
    fn prepare_alone(&self, _: &Grid2, _: MoveModel) -> Result<Engine, PlanFailure> {
        Ok(Engine::Function(self.0))
    }
}

/// JPS+: its table is kept per grid (built once, or loaded from a file).
pub(crate) struct JpsPlusCells;

impl CellPlanner for JpsPlusCells {
    fn bytes_per_cell(&self) -> u64 {
        68
    }

    fn prepare(
        &self,
        session: &mut Session,
        grid: &Arc<Grid2>,
        r: &Resolved,
    ) -> Result<Prepared, PlanFailure> {
        if !r.model.has_diagonals() {
            // 4-connected grids have no jumps: GridSearch runs A* for them.
            return Ok(Prepared::plain(Engine::Online(Planner::JpsPlus)));
        }
        let (table, built_us) = session.jps_plus_table(grid, r.model);
        Ok(Prepared::kept(
            Engine::Plus(table),
            built_us,
            "jps_plus_table",
        ))
    }

    fn prepare_alone(&self, grid: &Grid2, model: MoveModel) -> Result<Engine, PlanFailure> {
        if !model.has_diagonals() {
            // As in `prepare`: a table has no 4-connected rule (it would move diagonally).
            return Ok(Engine::Online(Planner::JpsPlus));
        }
        Ok(Engine::Plus(Arc::new(JpsPlusTable::build(
            Arc::new(grid.clone()),
            model,
        ))))
    }
}

/// The contraction hierarchy, kept per grid and move model.
pub(crate) struct HierarchyCells;

impl CellPlanner for HierarchyCells {
    /// Up to ~10 upward edges per cell on open ground (16 bytes each) plus the edge arena.
    fn bytes_per_cell(&self) -> u64 {
        400
    }

    fn prepare(
        &self,
        session: &mut Session,
        grid: &Arc<Grid2>,
        r: &Resolved,
    ) -> Result<Prepared, PlanFailure> {
        let (ch, built_us) = session.contraction_hierarchy(grid, r.model, r.preprocess_limit)?;
        Ok(Prepared::kept(
            Engine::Hierarchy(ch),
            built_us,
            "contraction_hierarchy",
        ))
    }

    fn prepare_alone(&self, grid: &Grid2, model: MoveModel) -> Result<Engine, PlanFailure> {
        let ch = ContractionHierarchy::build(Arc::new(grid.clone()), model)
            .map_err(|e| PlanFailure::bad_request(format!("planner ch: {e}")))?;
        Ok(Engine::Hierarchy(Arc::new(ch)))
    }
}

/// The simple subgoal graph with its contraction hierarchy, kept per grid. It is defined for
/// the 8-connected model without corner cutting; under the other two every free cell is a
/// subgoal, so the graph is the grid's own and its hierarchy is `ch`'s (built, kept and
/// reported as `ch`'s).
pub(crate) struct SubgoalCells;

impl CellPlanner for SubgoalCells {
    /// One byte and one node number per cell, each cell's kept roots (up to 48 on average, 4
    /// bytes each), the graph and its hub labels (a few percent of the cells on the maps it is
    /// for): 112 bytes a cell on 16-cell rooms.
    fn bytes_per_cell(&self) -> u64 {
        128
    }

    fn prepare(
        &self,
        session: &mut Session,
        grid: &Arc<Grid2>,
        r: &Resolved,
    ) -> Result<Prepared, PlanFailure> {
        if r.model != MoveModel::Octile {
            return HierarchyCells.prepare(session, grid, r);
        }
        let (graph, built_us) = session.subgoal_graph(grid, r.preprocess_limit)?;
        Ok(Prepared::kept(
            Engine::Subgoal(graph),
            built_us,
            "subgoal_graph",
        ))
    }

    fn prepare_alone(&self, grid: &Grid2, model: MoveModel) -> Result<Engine, PlanFailure> {
        if model != MoveModel::Octile {
            return HierarchyCells.prepare_alone(grid, model);
        }
        let graph = SubgoalGraph::build(Arc::new(grid.clone()), model)
            .map_err(|e| PlanFailure::bad_request(format!("planner subgoal: {e}")))?;
        Ok(Engine::Subgoal(Arc::new(graph)))
    }
}

/// The first-move table, kept per grid and move model; for small maps (its size grows with the
/// square of the free cells: refused past [`crate::auto::FIRST_MOVE_MAX_BYTES`] and the
/// session's memory limit).
pub(crate) struct FirstMoveCells;

impl CellPlanner for FirstMoveCells {
    fn prepare(
        &self,
        session: &mut Session,
        grid: &Arc<Grid2>,
        r: &Resolved,
    ) -> Result<Prepared, PlanFailure> {
        let (table, built_us) = session.first_move_table(grid, r.model, r.preprocess_limit)?;
        Ok(Prepared::kept(
            Engine::FirstMove(table),
            built_us,
            "first_move_table",
        ))
    }

    fn prepare_alone(&self, grid: &Grid2, model: MoveModel) -> Result<Engine, PlanFailure> {
        let table = FirstMoveTable::build(
            Arc::new(grid.clone()),
            model,
            crate::auto::FIRST_MOVE_MAX_BYTES,
        )
        .map_err(|e| PlanFailure::bad_request(format!("planner first-move: {e}")))?;
        Ok(Engine::FirstMove(Arc::new(table)))
    }
}

/// `auto`: JPS, JPS+, CH, the subgoal graph or the first-move table, picked per grid from its statistics and the queries on it
/// ([`crate::auto::pick`]); in a session the count is the session's `auto` queries on the grid
/// so far, and kept preprocessing (built or loaded) is used when the rule would take it.
pub(crate) struct AutoCells;

impl AutoCells {
    /// The picked planner's cell search.
    fn cells(planner: PlannerId) -> &'static dyn CellPlanner {
        match planner.algorithm().cells() {
            Some(c) => c,
            None => &OnlineCells(Planner::Jps),
        }
    }
}

impl CellPlanner for AutoCells {
    /// What JPS+ needs: `auto` builds a contraction hierarchy only on corridor maps, where it
    /// is small, and falls back to JPS+ when it cannot.
    fn bytes_per_cell(&self) -> u64 {
        JpsPlusCells.bytes_per_cell()
    }

    fn prepare(
        &self,
        session: &mut Session,
        grid: &Arc<Grid2>,
        r: &Resolved,
    ) -> Result<Prepared, PlanFailure> {
        let mut pick = session.auto_pick(grid, r.model);
        let mut prepared = match Self::cells(pick.planner).prepare(session, grid, r) {
            Ok(p) => p,
            // A hierarchy, subgoal graph or first-move table past its time limit: JPS+ answers
            // at once.
            Err(e)
                if matches!(
                    pick.planner,
                    PlannerId::Ch | PlannerId::Subgoal | PlannerId::FirstMove
                ) =>
            {
                pick.planner = PlannerId::JpsPlus;
                pick.why = format!("{}, but {}: JPS+ instead", pick.why, e.message);
                JpsPlusCells.prepare(session, grid, r)?
            }
            Err(e) => return Err(e),
        };
        prepared.auto = Some(pick);
        Ok(prepared)
    }

    /// Prepared for one query: JPS ([`crate::CellSearch::for_queries`] picks for a batch).
    fn prepare_alone(&self, grid: &Grid2, model: MoveModel) -> Result<Engine, PlanFailure> {
        let pick = crate::auto::pick_for(&crate::auto::MapStats::of(grid), 1, model);
        Self::cells(pick.planner).prepare_alone(grid, model)
    }
}

/// A planner on the request's grid that is not a cell search: its bytes per cell, its plan,
/// and whether its route comes with a navigation field.
pub(crate) struct OnGrid {
    bytes_per_cell: u64,
    plan: fn(&mut Session, &Query) -> Result<Route, PlanFailure>,
    field: bool,
}

impl Algorithm for OnGrid {
    fn memory(&self, world: &World, r: &Resolved) -> Option<Memory> {
        Memory::cells(world, r, self.bytes_per_cell)
    }

    fn plan(&self, session: &mut Session, q: &Query) -> Result<Route, PlanFailure> {
        (self.plan)(session, q)
    }

    fn has_field(&self) -> bool {
        self.field
    }
}

/// Exact any-angle paths over the visibility graph kept per grid.
pub(crate) const ANY_ANGLE: OnGrid = OnGrid {
    bytes_per_cell: 24,
    plan: crate::any_angle::plan,
    field: false,
};

/// The wavefront navigation function (its distance field).
pub(crate) const WAVEFRONT: OnGrid = OnGrid {
    bytes_per_cell: 48,
    plan: crate::navfn::wavefront,
    field: true,
};

/// A\* over the inflated cost map (its cost to go).
pub(crate) const COSTMAP: OnGrid = OnGrid {
    bytes_per_cell: 48,
    plan: crate::navfn::costmap,
    field: true,
};

/// The Voronoi roadmap, kept per altitude, margin and cell size.
pub(crate) const VORONOI: OnGrid = OnGrid {
    bytes_per_cell: 24,
    plan: crate::voronoi::plan,
    field: false,
};

/// PRM, lazy PRM, RRT-Connect, RRT\* among the grown boxes.
pub(crate) struct Sampling(pub PlannerKind);

impl Algorithm for Sampling {
    fn memory(&self, _: &World, _: &Resolved) -> Option<Memory> {
        None
    }

    fn plan(&self, session: &mut Session, q: &Query) -> Result<Route, PlanFailure> {
        crate::three_d::sampling(session, q, self.0)
    }

    fn work_unit(&self) -> &'static str {
        "samples"
    }
}

/// Voxel A\* over the lattice of the grown boxes.
pub(crate) struct Voxel;

impl Algorithm for Voxel {
    fn memory(&self, world: &World, r: &Resolved) -> Option<Memory> {
        let b = world.bounds_ne(r.cell_m);
        let n = ((b.north_max_m - b.north_min_m) / r.voxel_m).ceil()
            * ((b.east_max_m - b.east_min_m) / r.voxel_m).ceil()
            * ((r.max_alt_m - r.min_alt_m) / r.layer_m).ceil().max(1.0);
        let units = if n.is_finite() && n < 1.8e19 {
            n as u64
        } else {
            u64::MAX
        };
        Some(Memory {
            units,
            bytes_per_unit: 40,
            what: "voxels",
            change: "use a larger voxel_m or layer_m",
        })
    }

    fn plan(&self, session: &mut Session, q: &Query) -> Result<Route, PlanFailure> {
        crate::three_d::voxel(session, q)
    }
}
