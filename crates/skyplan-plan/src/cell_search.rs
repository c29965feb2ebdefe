//! [`CellSearch`]: many cell-to-cell queries on one grid with one grid planner — what MovingAI
//! replays and benchmarks need (JPS+ builds its table once, the others reuse their node arrays).

use crate::failure::PlanFailure;
use crate::planner_id::{Family, PlannerId};
use skyplan_cspace::{Cell, Grid2};
use skyplan_search::{
    ChQuery, ContractionHierarchy, GridPath, GridSearch, JpsPlusTable, MoveModel, Planner,
    SearchError,
};
use std::sync::Arc;

enum Engine {
    Plus(Arc<JpsPlusTable>, Box<GridSearch>),
    Online(Box<GridSearch>, Planner),
    Contraction(Arc<ContractionHierarchy>, Box<ChQuery>),
}

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
    precompute_us: u64,
}

impl<'g> CellSearch<'g> {
    /// Prepares `planner` (a grid-search planner: jps, jps-plus, astar, dijkstra, theta, or the
    /// contraction hierarchy ch) on `grid`; other planners are refused with a message naming
    /// the ones that work.
    pub fn new(grid: &'g Grid2, planner: PlannerId, model: MoveModel) -> Result<Self, PlanFailure> {
        let family = planner.info().family;
        if !family.is_cell_search() {
            let grid_planners: Vec<&str> = PlannerId::ALL
                .iter()
                .filter(|p| p.info().family.is_cell_search())
                .map(|p| p.name())
                .collect();
            return Err(PlanFailure::bad_request(format!(
                "--planner {planner}: cell-to-cell queries take a grid-search planner: {}",
                grid_planners.join(", ")
            )));
        }
        let t = std::time::Instant::now();
        let engine = match family {
            Family::Grid(Planner::JpsPlus) => Engine::Plus(
                Arc::new(JpsPlusTable::build(Arc::new(grid.clone()), model)),
                Box::default(),
            ),
            Family::Contraction => Engine::Contraction(
                Arc::new(
                    ContractionHierarchy::build(Arc::new(grid.clone()), model).map_err(|e| {
                        PlanFailure::bad_request(format!("--planner {planner}: {e}"))
                    })?,
                ),
                Box::default(),
            ),
            Family::Grid(other) => Engine::Online(Box::new(GridSearch::new()), other),
            Family::AnyAngle
            | Family::Wavefront
            | Family::Costmap
            | Family::Voronoi
            | Family::Sampling(_)
            | Family::Voxel => {
                return Err(PlanFailure::internal(format!(
                    "--planner {planner}: not a cell-to-cell planner"
                )));
            }
        };
        Ok(Self {
            grid,
            model,
            engine,
            precompute_us: crate::session::micros(t.elapsed()),
        })
    }

    /// JPS+ with a table built or loaded before (e.g. from a file, see
    /// [`skyplan_search::table_file`]); refused unless it was built for exactly `grid`.
    /// `precompute_us` is what preparing it cost (building or loading).
    pub fn with_jps_plus_table(
        grid: &'g Grid2,
        table: Arc<JpsPlusTable>,
        precompute_us: u64,
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
            engine: Engine::Plus(table, Box::default()),
            precompute_us,
        })
    }

    /// One query.
    pub fn search(&mut self, start: Cell, goal: Cell) -> Result<GridPath, SearchError> {
        match &mut self.engine {
            Engine::Plus(table, search) => table.search(search, start, goal),
            Engine::Online(search, planner) => {
                search.search(self.grid, start, goal, self.model, *planner)
            }
            Engine::Contraction(ch, query) => ch.search(query, start, goal),
        }
    }

    /// One-off preparation time (the JPS+ table, the contraction hierarchy), microseconds.
    pub fn precompute_us(&self) -> u64 {
        self.precompute_us
    }
}
