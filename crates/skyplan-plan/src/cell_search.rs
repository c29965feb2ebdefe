//! [`CellSearch`]: many cell-to-cell queries on one grid with one grid planner — what MovingAI
//! replays and benchmarks need (JPS+ builds its table once, the others reuse their node arrays).

use crate::failure::PlanFailure;
use crate::planner_id::{Family, PlannerId};
use skyplan_cspace::{Cell, Grid2};
use skyplan_search::{GridPath, GridSearch, JpsPlus, MoveModel, Planner, SearchError};

enum Engine<'g> {
    Plus(Box<JpsPlus<'g>>),
    Online(Box<GridSearch>, Planner),
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
    engine: Engine<'g>,
    precompute_us: u64,
}

impl<'g> CellSearch<'g> {
    /// Prepares `planner` (a grid-search planner: jps, jps-plus, astar, dijkstra, theta) on
    /// `grid`; other planners are refused with a message naming the ones that work.
    pub fn new(grid: &'g Grid2, planner: PlannerId, model: MoveModel) -> Result<Self, PlanFailure> {
        let Family::Grid(p) = planner.info().family else {
            let grid_planners: Vec<&str> = PlannerId::ALL
                .iter()
                .filter(|p| matches!(p.info().family, Family::Grid(_)))
                .map(|p| p.name())
                .collect();
            return Err(PlanFailure::bad_request(format!(
                "--planner {planner}: cell-to-cell queries take a grid-search planner: {}",
                grid_planners.join(", ")
            )));
        };
        let t = std::time::Instant::now();
        let engine = match p {
            Planner::JpsPlus => Engine::Plus(Box::new(JpsPlus::new(grid, model))),
            other => Engine::Online(Box::new(GridSearch::new()), other),
        };
        Ok(Self {
            grid,
            model,
            engine,
            precompute_us: crate::session::micros(t.elapsed()),
        })
    }

    /// One query.
    pub fn search(&mut self, start: Cell, goal: Cell) -> Result<GridPath, SearchError> {
        match &mut self.engine {
            Engine::Plus(plus) => plus.search(start, goal),
            Engine::Online(search, planner) => {
                search.search(self.grid, start, goal, self.model, *planner)
            }
        }
    }

    /// One-off preparation time (the JPS+ table), microseconds.
    pub fn precompute_us(&self) -> u64 {
        self.precompute_us
    }
}
