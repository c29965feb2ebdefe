//! `GET /api/map`: the map's name, home, bounds and obstacles, and on request the grid at an
//! altitude and margin as run-length rows.

use crate::error::ApiError;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use skyplan_cspace::Grid2;
use skyplan_plan::{PlanRequest, PlanSpec, World};

/// Most cells a grid may have (in `/api/map` and in plans): 16 million, about 4000 × 4000.
pub const MAX_GRID_CELLS: f64 = 16_000_000.0;

/// The query of `GET /api/map`: any of the three asks for the grid (the others default to
/// 5 m, 5 m, 1 m).
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MapQuery {
    pub alt_m: Option<f64>,
    pub safety_m: Option<f64>,
    pub cell_m: Option<f64>,
}

impl MapQuery {
    /// The grid's slice as a plan request (resolved and checked by the planning API, with its
    /// defaults), when the grid is asked for.
    pub fn request(&self) -> Option<PlanRequest> {
        (self.alt_m.is_some() || self.safety_m.is_some() || self.cell_m.is_some()).then(|| {
            PlanRequest {
                alt_m: self.alt_m,
                safety_m: self.safety_m,
                cell_m: self.cell_m,
                ..PlanRequest::default()
            }
        })
    }
}

/// Refuses a cell size that would make a grid larger than [`MAX_GRID_CELLS`] on this world.
pub(crate) fn check_grid_size(world: &World, cell_m: f64, what: &str) -> Result<(), ApiError> {
    if world.fixed_grid().is_some() {
        return Ok(()); // the grid is the map's own, whatever the cell size asked
    }
    if !(cell_m.is_finite() && cell_m > 0.0) {
        return Err(ApiError::bad_request(format!(
            "{what} {cell_m}: expected a number above 0"
        )));
    }
    let b = world.bounds_ne(cell_m);
    let cells =
        ((b.north_max_m - b.north_min_m) / cell_m) * ((b.east_max_m - b.east_min_m) / cell_m);
    if cells > MAX_GRID_CELLS {
        let min_cell_m = ((b.north_max_m - b.north_min_m) * (b.east_max_m - b.east_min_m)
            / MAX_GRID_CELLS)
            .sqrt();
        return Err(ApiError::bad_request(format!(
            "{what} {cell_m}: the grid would have {cells:.0} cells, more than this server's {MAX_GRID_CELLS:.0}; use at least {min_cell_m:.2} m",
        )));
    }
    Ok(())
}

/// The grid at one altitude and margin: rows from the southern edge, each as run lengths of
/// alternating free and blocked cells, starting with free (a row starting blocked begins with 0).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct GridRuns {
    #[serde(flatten)]
    pub info: skyplan_plan::GridInfo,
    pub runs: Vec<Vec<u32>>,
}

impl GridRuns {
    pub fn new(grid: &Grid2, alt_m: f64, safety_m: f64) -> Self {
        let cols = grid.cols() as usize;
        let runs = grid
            .blocked_cells()
            .chunks(cols.max(1))
            .map(|row| {
                let mut out = Vec::new();
                let mut current = false; // runs start with free
                let mut len = 0u32;
                for &blocked in row {
                    if blocked == current {
                        len += 1;
                    } else {
                        out.push(len);
                        current = blocked;
                        len = 1;
                    }
                }
                out.push(len);
                out
            })
            .collect();
        Self {
            info: skyplan_plan::GridInfo::of(grid, alt_m, safety_m),
            runs,
        }
    }
}

/// The map without the grid (computed once).
pub(crate) fn map_info(world: &World) -> Value {
    let home = world.frame().map(|f| {
        let h = f.home();
        json!({ "lat_deg": h.lat_deg, "lon_deg": h.lon_deg })
    });
    let bounds = world.bounds_ne(PlanSpec::default().cell_m);
    let obstacles: Vec<[f64; 6]> = world
        .colliders()
        .map(|m| {
            m.boxes
                .iter()
                .map(|b| {
                    [
                        b.north_m,
                        b.east_m,
                        b.half_north_m,
                        b.half_east_m,
                        b.bottom_m(),
                        b.top_m(),
                    ]
                })
                .collect()
        })
        .unwrap_or_default();
    let max_top_m = obstacles.iter().map(|o| o[5]).fold(0.0, f64::max);
    let (default_start_ne, default_goal_ne) = world.default_endpoints_ne();
    json!({
        "name": world.name(),
        "kind": world.kind(),
        "home": home,
        "bounds": bounds,
        "default_start_ne": default_start_ne,
        "default_goal_ne": default_goal_ne,
        "obstacle_fields": ["north_m", "east_m", "half_north_m", "half_east_m", "bottom_m", "top_m"],
        "obstacles": obstacles,
        "max_top_m": max_top_m,
    })
}
