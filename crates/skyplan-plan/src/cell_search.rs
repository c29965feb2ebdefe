//! [`CellSearch`]: many cell-to-cell queries on one grid with one grid planner — what MovingAI
//! replays and benchmarks need (JPS+ builds its table once, the others reuse their node arrays).

use crate::algorithm::{Engine, Workspace};
use crate::auto::AutoPick;
use crate::failure::PlanFailure;
use crate::planner_id::PlannerId;
use skyplan_cspace::{Cell, Grid2};
use skyplan_search::{
    BlockJps, ContractionHierarchy, FirstMoveTable, GridPath, JpsPlusTable, MoveModel, SearchError,
    SubgoalGraph,
};
use std::sync::Arc;

/// A grid planner prepared for many queries on one grid.
///
/// ```
/// use skyplan_plan::{CellSearch, PlannerId};
/// use skyplan_search::MoveModel;
/// let grid = skyplan_cspace::Grid2::from_ascii("....\n.##.\n....")?;
/// let mut s = CellSearch::new(&grid, PlannerId::JpsPlus, MoveModel::Octile)?;
/// let p = s.search(skyplan_cspace::Cell::new(0, 0), skyplan_cspace::Cell::new(2, 3))?;
/// assert_eq!(p.cells.first(), Some(&skyplan_cspace::Cell::new(0, 0)));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct CellSearch<'g> {
    grid: &'g Grid2,
    model: MoveModel,
    engine: Engine,
    workspace: Box<Workspace>,
    /// For JPS: the grid's bit rows and columns packed once (the grid is borrowed for as long).
    block_jps: Option<BlockJps<'g>>,
    precompute_us: u64,
    auto: Option<AutoPick>,
}

impl<'g> CellSearch<'g> {
    /// Prepares `planner` (a grid-search planner: jps, jps-plus, astar, dijkstra, theta, or the
    /// contraction hierarchy ch; auto picks for one query: see [`CellSearch::for_queries`]) on
    /// `grid`; other planners are refused with a message naming the ones that work.
    pub fn new(grid: &'g Grid2, planner: PlannerId, model: MoveModel) -> Result<Self, PlanFailure> {
        Self::for_queries(grid, planner, model, 1)
    }

    /// As [`CellSearch::new`], for a batch of `queries` queries: `auto` picks its planner for
    /// that many ([`crate::auto::pick`]; [`CellSearch::auto_pick`] says what and why). The
    /// statistics and the pick count in [`CellSearch::precompute_us`].
    ///
    /// ```
    /// use skyplan_plan::{CellSearch, PlannerId};
    /// use skyplan_search::MoveModel;
    /// // 100 rows of `..#.`: 300 free cells in runs of 1.5 along the rows.
    /// let grid = skyplan_cspace::Grid2::from_ascii(&"..#.\n".repeat(100))?;
    /// let s = CellSearch::for_queries(&grid, PlannerId::Auto, MoveModel::Octile, 200)?;
    /// assert_eq!(s.auto_pick().map(|p| p.planner), Some(PlannerId::JpsPlus));
    /// // Short free runs: from 250 queries a contraction hierarchy pays for itself…
    /// let s = CellSearch::for_queries(&grid, PlannerId::Auto, MoveModel::Octile, 500)?;
    /// assert_eq!(s.auto_pick().map(|p| p.planner), Some(PlannerId::Ch));
    /// // …and from 300² / 100 = 900 a first-move table (60 kB) does.
    /// let s = CellSearch::for_queries(&grid, PlannerId::Auto, MoveModel::Octile, 1_000)?;
    /// assert_eq!(s.auto_pick().map(|p| p.planner), Some(PlannerId::FirstMove));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn for_queries(
        grid: &'g Grid2,
        planner: PlannerId,
        model: MoveModel,
        queries: u64,
    ) -> Result<Self, PlanFailure> {
        let t = std::time::Instant::now();
        let auto = (planner == PlannerId::Auto)
            .then(|| crate::auto::pick_for(&crate::auto::MapStats::of(grid), queries, model));
        let planner = auto.as_ref().map_or(planner, |p| p.planner);
        let Some(cells) = planner.algorithm().cells() else {
            return Err(PlanFailure::bad_request(format!(
                "planner {planner}: cell-to-cell queries take a grid-search planner: {}",
                PlannerId::names_where(PlannerId::is_cell_search)
            )));
        };
        let engine = cells.prepare_alone(grid, model)?;
        let block_jps = (planner == PlannerId::Jps).then(|| BlockJps::new(grid, model));
        Ok(Self {
            grid,
            model,
            engine,
            workspace: Box::default(),
            block_jps,
            precompute_us: crate::session::micros(t.elapsed()),
            auto,
        })
    }

    /// JPS+ with a table built or loaded before (e.g. from a file, see
    /// [`skyplan_search::table_file`]); refused unless it was built for exactly `grid`.
    /// `precompute_us` is what preparing it cost (building or loading); `auto` is the pick to
    /// report, if `auto` chose it ([`crate::auto::pick_with_jps_plus_table`]).
    pub fn with_jps_plus_table(
        grid: &'g Grid2,
        table: Arc<JpsPlusTable>,
        precompute_us: u64,
        auto: Option<AutoPick>,
    ) -> Result<Self, PlanFailure> {
        // The same grid (shared, as a session or the bench shares it) or an equal one.
        if !std::ptr::eq(&**table.grid(), grid) && **table.grid() != *grid {
            return Err(PlanFailure::bad_request(
                "the JPS+ table was built for another grid",
            ));
        }
        Ok(Self {
            grid,
            model: table.model(),
            engine: Engine::Plus(table),
            workspace: Box::default(),
            block_jps: None,
            precompute_us,
            auto,
        })
    }

    /// The contraction hierarchy `ch` built or loaded before (e.g. from a file, see
    /// [`skyplan_search::ch_file`]); refused unless it was built for exactly `grid`.
    /// `precompute_us` is what preparing it cost; `auto` is the pick to report, if `auto` chose it
    /// ([`crate::auto::pick_with_hierarchy`]).
    pub fn with_hierarchy(
        grid: &'g Grid2,
        ch: Arc<ContractionHierarchy>,
        precompute_us: u64,
        auto: Option<AutoPick>,
    ) -> Result<Self, PlanFailure> {
        if !std::ptr::eq(&**ch.grid(), grid) && **ch.grid() != *grid {
            return Err(PlanFailure::bad_request(
                "the contraction hierarchy was built for another grid",
            ));
        }
        Ok(Self {
            grid,
            model: ch.model(),
            engine: Engine::Hierarchy(ch),
            workspace: Box::default(),
            block_jps: None,
            precompute_us,
            auto,
        })
    }

    /// The contraction hierarchy it queries, if it does (`ch`, or `auto` picking it): to save.
    pub fn hierarchy(&self) -> Option<&Arc<ContractionHierarchy>> {
        match &self.engine {
            Engine::Hierarchy(ch) => Some(ch),
            _ => None,
        }
    }

    /// The subgoal graph `graph` built or loaded before (e.g. from a file, see
    /// [`skyplan_search::subgoal_file`]); refused unless it was built for exactly `grid`.
    /// `precompute_us` is what preparing it cost; `auto` is the pick to report, if `auto` chose
    /// it ([`crate::auto::pick_with_subgoal_graph`]).
    pub fn with_subgoal_graph(
        grid: &'g Grid2,
        graph: Arc<SubgoalGraph>,
        precompute_us: u64,
        auto: Option<AutoPick>,
    ) -> Result<Self, PlanFailure> {
        if !std::ptr::eq(&**graph.grid(), grid) && **graph.grid() != *grid {
            return Err(PlanFailure::bad_request(
                "the subgoal graph was built for another grid",
            ));
        }
        Ok(Self {
            grid,
            model: MoveModel::Octile,
            engine: Engine::Subgoal(graph),
            workspace: Box::default(),
            block_jps: None,
            precompute_us,
            auto,
        })
    }

    /// The subgoal graph it queries, if it does (`subgoal`, or `auto` picking it): to save.
    pub fn subgoal_graph(&self) -> Option<&Arc<SubgoalGraph>> {
        match &self.engine {
            Engine::Subgoal(g) => Some(g),
            _ => None,
        }
    }

    /// The first-move table `table` built or loaded before (e.g. from a file, see
    /// [`skyplan_search::first_move_file`]); refused unless it was built for exactly `grid`.
    /// `precompute_us` is what preparing it cost; `auto` is the pick to report, if `auto` chose
    /// it ([`crate::auto::pick_with_first_move_table`]).
    pub fn with_first_move_table(
        grid: &'g Grid2,
        table: Arc<FirstMoveTable>,
        precompute_us: u64,
        auto: Option<AutoPick>,
    ) -> Result<Self, PlanFailure> {
        if !std::ptr::eq(&**table.grid(), grid) && **table.grid() != *grid {
            return Err(PlanFailure::bad_request(
                "the first-move table was built for another grid",
            ));
        }
        Ok(Self {
            grid,
            model: table.model(),
            engine: Engine::FirstMove(table),
            workspace: Box::default(),
            block_jps: None,
            precompute_us,
            auto,
        })
    }

    /// The JPS+ table it reads, if it does (`jps-plus`, or `auto` picking it): to save.
    pub fn jps_plus_table(&self) -> Option<&Arc<JpsPlusTable>> {
        match &self.engine {
            Engine::Plus(t) => Some(t),
            _ => None,
        }
    }

    /// The first-move table it reads, if it does (`first-move`, or `auto` picking it): to save.
    pub fn first_move_table(&self) -> Option<&Arc<FirstMoveTable>> {
        match &self.engine {
            Engine::FirstMove(t) => Some(t),
            _ => None,
        }
    }

    /// One query.
    pub fn search(&mut self, start: Cell, goal: Cell) -> Result<GridPath, SearchError> {
        if let Some(jps) = &mut self.block_jps {
            return jps.search(&mut self.workspace.search, start, goal);
        }
        self.engine
            .search(&mut self.workspace, self.grid, (start, goal), self.model)
    }

    /// What `auto` picked and why (`None` for a named planner).
    pub fn auto_pick(&self) -> Option<&AutoPick> {
        self.auto.as_ref()
    }

    /// One-off preparation time (the JPS+ table, the contraction hierarchy), microseconds.
    pub fn precompute_us(&self) -> u64 {
        self.precompute_us
    }
}
